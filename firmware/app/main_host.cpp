// The application on the PC: the same code as the board, with a disk-image file as the SD
// card. `seqslam-firmware --disk IMAGE` runs exactly what the emulated board runs on the same
// image (the run configuration, the replay recording and the library on it), so both can be
// compared byte for byte. Exit status as main_board.cpp, and 2 for a usage error.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "app.h"
#include "seqslam/hal/counting_block_device.h"
#include "seqslam/hal/file_block_device.h"
#include "seqslam/hal/host_file.h"
#include "seqslam/hal/sd_card_model.h"

namespace {

void print(const char* text) {
  std::fputs(text, stdout);
}

}  // namespace

int main(int argc, char** argv) {
  using seqslam::Status;
  std::string disk;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--disk") == 0 && i + 1 < argc) {
      disk = argv[++i];
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf(
          "usage: seqslam-firmware --disk IMAGE\n"
          "Runs the head-board application on a disk image (see docs/firmware.md).\n");
      return 0;
    } else {
      std::fprintf(stderr, "seqslam-firmware: unknown argument %s (see --help)\n", argv[i]);
      return 2;
    }
  }
  if (disk.empty()) {
    std::fprintf(stderr, "seqslam-firmware: --disk IMAGE is required\n");
    return 2;
  }
  // A file size limit (ulimit -f) fails a write with EFBIG instead of killing the process.
  seqslam::hal::ignore_file_size_signal();
  seqslam::hal::FileBlockDevice device;
  if (device.open(disk, true) != Status::kOk) {  // also refused: a card another process writes
    std::fprintf(stderr, "seqslam-firmware: %s\n", device.error().c_str());
    return 2;
  }
  // The card is written anywhere up to its end: under a smaller file size limit some writes
  // would fail half way through the run, so refuse before anything is written (status 1, an
  // I/O error as a failed write would be).
  const std::string limit = seqslam::hal::check_file_size_limit(disk, device.capacity_bytes());
  if (!limit.empty()) {
    std::fprintf(stderr, "seqslam-firmware: %s (nothing was written)\n", limit.c_str());
    return 1;
  }
  // Counted as on the board (main_board.cpp), and priced with the SD card model.
  seqslam::hal::CountingBlockDevice card(device);
  seqslam::storage::Volume volume;
  seqslam::storage::VolumeProblem vp = seqslam::storage::VolumeProblem::kNone;
  if (volume.mount(card, &vp) != Status::kOk) {
    std::fprintf(stderr, "seqslam-firmware: %s: %s\n", disk.c_str(),
                 seqslam::storage::volume_problem_text(vp));
    return 2;
  }
  // The application holds the whole firmware state (tens of KB): not on the stack.
  auto app = std::make_unique<seqslam::app::Application>();
  if (app->start(volume, nullptr, nullptr, print) != Status::kOk) {
    if (!device.error().empty()) {
      std::fprintf(stderr, "seqslam-firmware: %s\n", device.error().c_str());
    }
    return 2;
  }
  const Status s = app->run();
  app->report();
  const seqslam::hal::CardCounters c = card.counters();
  std::printf("card: %u %u %u %u %u %u %u\n", static_cast<unsigned>(c.read_requests),
              static_cast<unsigned>(c.multi_read_requests), static_cast<unsigned>(c.blocks_read),
              static_cast<unsigned>(c.write_requests), static_cast<unsigned>(c.blocks_written),
              static_cast<unsigned>(c.sync_requests), static_cast<unsigned>(c.failed_requests));
  std::printf("host: card time on SPI at 25 MHz (docs/card_model.md): %.1f ms\n",
              static_cast<double>(seqslam::hal::card_time_ns(c)) / 1e6);
  std::printf(s == Status::kOk ? "host: run complete\n" : "host: run failed\n");
  // The card file's own error (e.g. "write failed: File too large"): the app counts storage
  // errors, the host says which file and why.
  if (s != Status::kOk && !device.error().empty()) {
    std::fprintf(stderr, "seqslam-firmware: %s\n", device.error().c_str());
  }
  // The card is written in place (it is the device); the report goes to standard output,
  // and a report that did not arrive (a full disk, /dev/full) is a failed run, not a quiet one.
  if (std::fflush(stdout) != 0 || std::ferror(stdout) != 0) {
    std::fprintf(stderr, "seqslam-firmware: writing standard output: %s\n", std::strerror(errno));
    return 1;
  }
  return s == Status::kOk ? 0 : 1;
}
