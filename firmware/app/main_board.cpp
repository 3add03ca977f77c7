// The application on the emulated RV32IMC board: the volume is the virtio disk (a disk-image
// file attached by scripts/qemu-run.sh --disk), the sensors and camera are the volume's
// replay recording. Exit status 0 when the run completed, 1 on a failure during the run,
// 2 when it could not start.
#include "app.h"
#include "seqslam/board/board.h"
#include "seqslam/board/virtio_block.h"
#include "seqslam/hal/counting_block_device.h"

namespace {

seqslam::board::VirtioBlockDevice g_disk;
// Every request the application makes of the card, counted (the time they cost is modelled
// on the PC: docs/card_model.md).
seqslam::hal::CountingBlockDevice g_card{g_disk};
seqslam::storage::Volume g_volume;
seqslam::app::Application g_app;

void print(const char* text) {
  seqslam::board::console_print(text);
}

}  // namespace

int main() {
  using seqslam::Status;
  if (g_disk.init() != Status::kOk) {
    print("board: no disk: virtio-blk: ");
    print(g_disk.reason());
    print("\n");
    return 2;
  }
  seqslam::storage::VolumeProblem vp = seqslam::storage::VolumeProblem::kNone;
  if (g_volume.mount(g_card, &vp) != Status::kOk) {
    print("board: ");
    print(seqslam::storage::volume_problem_text(vp));
    print("\n");
    return 2;
  }
  if (g_app.start(g_volume, nullptr, nullptr, print) != Status::kOk) return 2;
  const Status s = g_app.run();
  g_app.report();
  const seqslam::hal::CardCounters card = g_card.counters();
  const uint32_t figures[] = {card.read_requests,  card.multi_read_requests, card.blocks_read,
                              card.write_requests, card.blocks_written,      card.sync_requests,
                              card.failed_requests};
  // The same line as the PC build (main_host.cpp): reads multi-block blocks writes blocks
  // syncs failed.
  print("card:");
  for (uint32_t v : figures) {
    print(" ");
    seqslam::board::console_print_u64(v);
  }
  print("\n");
  const seqslam::board::MemoryUsage mem = seqslam::board::memory_usage();
  print("board: RAM used ");
  seqslam::board::console_print_u64(mem.ram_used_bytes);
  print(" of ");
  seqslam::board::console_print_u64(mem.ram_capacity_bytes);
  print(" bytes (stack reserved ");
  seqslam::board::console_print_u64(mem.stack_bytes);
  print(", high-water ");
  seqslam::board::console_print_u64(seqslam::board::stack_high_water_bytes());
  print(")\n");
  print(s == Status::kOk ? "board: run complete\n" : "board: run failed\n");
  return s == Status::kOk ? 0 : 1;
}
