// libFuzzer target: arbitrary bytes as the card holding a dream recording. The reader and the
// replay must return statuses, never crash, hang or read out of bounds (ASan/UBSan).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/dream_replay.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace seqslam;
  // Whole blocks, at least the header block and one more.
  const size_t blocks = size / hal::kBlockSize + 2;
  std::vector<uint8_t> card(blocks * hal::kBlockSize, 0);
  for (size_t i = 0; i < size; ++i)
    card[i] = data[i];
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);

  storage::DreamReader reader;
  if (reader.open(device, Span<uint8_t>(buffer.data(), buffer.size())) == Status::kOk) {
    storage::DreamItem item;
    for (int i = 0; i < 100000; ++i) {
      const Status s = reader.next(&item);
      if (s == Status::kOutOfRange) break;
      if (s == Status::kOk && (item.type == storage::DreamRecord::kPlace ||
                               item.type == storage::DreamRecord::kReducedPlace)) {
        volatile uint8_t sink = 0;
        for (uint32_t k = 0; k < item.place.size.pixels(); ++k)
          sink ^= item.place.gray[k];
        (void)sink;
      }
    }
  }
  // The same bytes through the replay, as the firmware would consume them.
  storage::DreamReplay replay;
  if (replay.open(device, Span<uint8_t>(buffer.data(), buffer.size())) == Status::kOk) {
    (void)replay.configure(replay.header().mapping);
    hal::SensorSnapshot snap;
    for (int i = 0; i < 100000; ++i) {
      if (replay.next(&snap) != Status::kOk) break;
      if ((i & 1) == 0 && replay.capture() == Status::kOk) {
        hal::Frame frame;
        (void)replay.read(&frame);
      }
    }
  }
  return 0;
}
