// libFuzzer target with a property oracle for dream recordings (storage/dream.h) and their
// replay (dream_replay.h), as fuzz_record_log is for the container below them. The input is a
// recipe (damage_recipe.h): how many places to record and their timestamps' steps, then how
// to damage the card. Reading the damaged recording must give
//   - only places that were recorded, in order, with their index, timestamp and every pixel
//     (never a misread, never a valid place refused as invalid);
//   - every missing place reported by the rule of check_losses (the log's lost count, with
//     a kDataLoss);
// and the replay, as the firmware consumes it, must deliver the same places with the same
// pixels, counting in bad_records() every damaged record the reader reported.
// Any violation aborts, so the fuzzer reports it like a crash.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "damage_recipe.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/dream_replay.h"
#include "seqslam/storage/record_log.h"

namespace {

using namespace seqslam;

constexpr uint32_t kBlocks = 16;
constexpr uint16_t kWidth = 8;  // small: the records, not the pixels, are what is fuzzed
constexpr uint16_t kHeight = 4;
constexpr uint32_t kPixels = kWidth * kHeight;

[[noreturn]] void violated(const char* what, uint32_t a, uint32_t b) {
  fuzz::violated("dream recording", what, a, b);
}

uint8_t pixel(uint32_t place, uint32_t k) {
  return static_cast<uint8_t>(place * 37u + k * 11u + 5u);
}

void make_image(uint32_t place, uint8_t* gray) {
  for (uint32_t k = 0; k < kPixels; ++k)
    gray[k] = pixel(place, k);
}

bool same_pixels(uint32_t place, const uint8_t* gray) {
  uint8_t expected[kPixels];
  make_image(place, expected);
  return std::memcmp(expected, gray, kPixels) == 0;
}

// Records up to 60 reduced places (timestamps from the recipe) until the card is full.
// Returns the places written and their timestamps; `end` is the log's end offset.
std::vector<uint32_t> record(fuzz::Recipe& in, hal::BlockDevice& device, uint64_t* end) {
  storage::DreamHeader header;
  header.variant = storage::DreamVariant::kReduced;
  header.mapping = hal::PipelineMapping::reduction(kWidth, kHeight);
  header.has_head = false;
  storage::DreamWriter writer;
  if (writer.create(device, header) != Status::kOk) violated("create", 0, 0);
  std::vector<uint32_t> stamps;
  const uint32_t wanted = in.next() % 61u;
  uint8_t gray[kPixels];
  uint32_t t = 0;
  for (uint32_t i = 0; i < wanted; ++i) {
    make_image(i, gray);
    t += static_cast<uint32_t>(in.next()) * 40000u;  // wraps as the bus clock does
    storage::DreamPlace p;
    p.index = i;
    p.timestamp_us = t;
    p.size = ImageSize{kWidth, kHeight};
    p.gray = gray;
    if (writer.place(p) != Status::kOk) break;  // full
    stamps.push_back(t);
  }
  *end = writer.log().end_offset();
  return stamps;
}

struct Read {
  bool opened = false;
  uint32_t places = 0;    // intact places returned
  uint32_t reported = 0;  // kDataLoss / kResourceExhausted statuses
};

// The reader: places in order, intact, losses reported.
Read check_reader(hal::BlockDevice& card, const fuzz::Damage& damage,
                  const std::vector<uint32_t>& stamps, std::vector<uint8_t>& buffer) {
  storage::DreamReader reader;
  if (reader.open(card, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) return {};
  const uint32_t written = static_cast<uint32_t>(stamps.size());
  uint32_t read = 0;
  uint32_t reported = 0;
  int64_t last = -1;
  for (uint32_t calls = 0;; ++calls) {
    if (calls > 4 * written + 16) violated("no end after many calls", calls, written);
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kDataLoss || s == Status::kResourceExhausted) {
      ++reported;
      continue;
    }
    if (s != Status::kOk) break;
    if (item.type != storage::DreamRecord::kReducedPlace) violated("an item never written", 0, 0);
    const storage::DreamPlace& p = item.place;
    if (p.index >= written || static_cast<int64_t>(p.index) <= last) {
      violated("a place out of order or never written", p.index, written);
    }
    last = p.index;
    if (p.timestamp_us != stamps[p.index] || p.size.width != kWidth ||
        p.size.height != kHeight || !same_pixels(p.index, p.gray)) {
      violated("a misread place", p.index, p.timestamp_us);
    }
    ++read;
  }
  fuzz::check_losses("dream recording", damage, storage::kFirstRecordOffset, written, read,
                     reported, reader.lost_records());
  return {true, read, reported};
}

// The replay, as the firmware consumes it: every place captured, the same places and pixels
// the reader gives, every damaged record the reader reported counted in bad_records().
void check_replay(hal::BlockDevice& card, const std::vector<uint32_t>& stamps,
                  std::vector<uint8_t>& buffer, const Read& read) {
  storage::DreamReplay replay;
  if (replay.open(card, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) {
    if (read.opened) violated("replay: refused what the reader opened", 0, 0);
    return;
  }
  uint32_t delivered = 0;
  if (replay.configure(replay.header().mapping) != Status::kOk) violated("configure", 0, 0);
  const uint32_t written = static_cast<uint32_t>(stamps.size());
  int64_t last = -1;
  for (uint32_t calls = 0;; ++calls) {
    if (calls > 4 * written + 16) violated("replay: no end after many calls", calls, written);
    hal::SensorSnapshot snap;
    if (replay.next(&snap) != Status::kOk) break;
    if (replay.capture() != Status::kOk) violated("replay: a place without its image", calls, 0);
    hal::Frame frame;
    if (replay.read(&frame) != Status::kOk) violated("replay: read", calls, 0);
    const uint32_t index = snap.sequence;
    if (index >= written || static_cast<int64_t>(index) <= last ||
        frame.timestamp_us != stamps[index] || !same_pixels(index, frame.gray)) {
      violated("replay: a misread place", index, written);
    }
    last = index;
    ++delivered;
  }
  if (delivered != read.places) violated("replay: other places than the reader", delivered, read.places);
  if (replay.bad_records() != read.reported) {
    violated("replay: damaged records not counted", replay.bad_records(), read.reported);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Recipe in{data, size};
  static std::vector<uint8_t> card(kBlocks * hal::kBlockSize);
  std::memset(card.data(), 0xEE, card.size());
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
  uint64_t end = 0;
  const std::vector<uint32_t> stamps = record(in, device, &end);

  const fuzz::Damage damage = fuzz::damage_card(in, card, end);
  hal::FakeBlockDevice damaged(Span<uint8_t>(card.data(), damage.length));
  static std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  const Read read = check_reader(damaged, damage, stamps, buffer);
  check_replay(damaged, stamps, buffer, read);
  return 0;
}
