// libFuzzer target with a property oracle for the record log (the container of recordings,
// libraries, results, maps and graphs; storage/record_log.h). The input is a recipe, not a
// card: it says which records to write, then how to damage the card (flipped bytes, zeroed
// blocks, a cut). Reading the damaged card must give
//   - only records that were written, in order, each byte for byte (never a misread);
//   - every missing record reported: records read + lost_records() == records written, with
//     at least one kDataLoss, unless a commit slot's bytes were damaged, in which case at
//     most the last record may vanish unreported (what a power cut while writing it looks
//     like), or both were, in which case any shortfall is reported (damage_recipe.h,
//     check_losses, shared with fuzz_dream_damage);
//   - an end in bounded calls (no hang).
// Any violation aborts, so the fuzzer reports it like a crash.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "damage_recipe.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/record_log.h"

namespace {

using namespace seqslam;
using storage::ByteSpan;

constexpr storage::LogKind kKind{{'S', 'Q', 'F', 'U', 'Z', 'Z', '0', '1'}, 1};
constexpr uint32_t kBlocks = 24;

[[noreturn]] void violated(const char* what, uint32_t a, uint32_t b) {
  fuzz::violated("record log", what, a, b);
}

uint8_t payload_byte(uint32_t record, uint32_t k) {
  return static_cast<uint8_t>(record * 131u + k * 7u + 1u);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Recipe in{data, size};
  static std::vector<uint8_t> card(kBlocks * hal::kBlockSize);
  std::memset(card.data(), 0xEE, card.size());  // not a byte loop: see coverage_ignore.txt
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));

  // Write: up to 60 records of 0..255 bytes (sizes from the recipe), until the card is full.
  storage::LogWriter writer;
  if (writer.create(device, kKind, nullptr, 0) != Status::kOk) violated("create", 0, 0);
  const uint32_t wanted = in.next() % 61u;
  std::vector<uint32_t> sizes;
  static uint8_t payload[256];
  for (uint32_t i = 0; i < wanted; ++i) {
    const uint32_t n = in.next();
    for (uint32_t k = 0; k < n; ++k)
      payload[k] = payload_byte(i, k);
    const ByteSpan part{payload, n};
    if (writer.append(static_cast<uint8_t>(i), &part, 1) != Status::kOk) break;  // full
    sizes.push_back(n);
  }
  const uint32_t written = static_cast<uint32_t>(sizes.size());
  const uint64_t end = writer.end_offset();

  // Damage: up to 8 operations (damage_recipe.h).
  const fuzz::Damage damage = fuzz::damage_card(in, card, end);

  // Read back.
  hal::FakeBlockDevice damaged(Span<uint8_t>(card.data(), damage.length));
  static uint8_t buffer[2048];
  storage::LogReader reader;
  if (reader.open(damaged, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, sizeof buffer)) !=
      Status::kOk) {
    return 0;  // header damaged or cut away: refused with a status
  }
  uint32_t read = 0;
  uint32_t reported = 0;
  int64_t last = -1;
  uint32_t calls = 0;
  for (;; ++calls) {
    if (calls > 4 * written + 16) violated("no end after many calls", calls, written);
    storage::RecordView v;
    const Status s = reader.next(&v);
    if (s == Status::kDataLoss) {
      ++reported;
      continue;
    }
    if (s != Status::kOk) break;
    if (v.sequence >= written || static_cast<int64_t>(v.sequence) <= last) {
      violated("a record out of order or never written", v.sequence, written);
    }
    last = v.sequence;
    if (v.type != static_cast<uint8_t>(v.sequence) || v.payload_size != sizes[v.sequence]) {
      violated("a misread record", v.sequence, v.payload_size);
    }
    for (uint32_t k = 0; k < v.payload_size; ++k) {
      if (v.payload[k] != payload_byte(v.sequence, k)) violated("a misread byte", v.sequence, k);
    }
    ++read;
  }
  fuzz::check_losses("record log", damage, storage::kFirstRecordOffset, written, read, reported,
                     reader.lost_records());
  return 0;
}
