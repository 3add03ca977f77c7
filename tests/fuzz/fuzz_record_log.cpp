// libFuzzer target with a property oracle for the record log (the container of recordings,
// libraries, results, maps and graphs; storage/record_log.h). The input is a recipe, not a
// card: it says which records to write, then how to damage the card (flipped bytes, zeroed
// blocks, a cut). Reading the damaged card must give
//   - only records that were written, in order, each byte for byte (never a misread);
//   - every missing record reported: records read + lost_records() == records written, with
//     at least one kDataLoss, unless a commit slot's bytes were damaged, in which case at
//     most the last record may vanish unreported (what a power cut while writing it looks
//     like), or both were, in which case any shortfall is reported;
//   - an end in bounded calls (no hang).
// Any violation aborts, so the fuzzer reports it like a crash.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/record_log.h"

namespace {

using namespace seqslam;
using storage::ByteSpan;

constexpr storage::LogKind kKind{{'S', 'Q', 'F', 'U', 'Z', 'Z', '0', '1'}, 1};
constexpr uint32_t kBlocks = 24;

[[noreturn]] void violated(const char* what, uint32_t a, uint32_t b) {
  std::fprintf(stderr, "record log property violated: %s (%u, %u)\n", what, a, b);
  std::abort();
}

uint8_t payload_byte(uint32_t record, uint32_t k) {
  return static_cast<uint8_t>(record * 131u + k * 7u + 1u);
}

struct Recipe {
  const uint8_t* data;
  size_t size;
  size_t at = 0;
  uint8_t next() { return at < size ? data[at++] : 0; }
  bool more() const { return at < size; }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Recipe in{data, size};
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

  // Damage: up to 8 operations.
  // Blocks 1 and 2 start with the commit slots (20 bytes each): kept to tell afterwards
  // which survived the damage byte for byte.
  constexpr uint32_t kSlotBytes = 20;
  uint8_t slots_before[2][kSlotBytes];
  for (uint32_t k = 0; k < 2; ++k)
    std::memcpy(slots_before[k], card.data() + (k + 1) * hal::kBlockSize, kSlotBytes);
  size_t length = card.size();
  const uint32_t ops = in.next() % 9u;
  for (uint32_t o = 0; o < ops && in.more(); ++o) {
    const uint8_t op = in.next() % 3u;
    const uint32_t where =
        (static_cast<uint32_t>(in.next()) << 8 | in.next()) % static_cast<uint32_t>(end);
    if (op == 0) {  // flip bits of one byte
      card[where] ^= static_cast<uint8_t>(in.next() | 1u);
    } else if (op == 1) {  // zero the block holding `where`
      const uint32_t block = where / hal::kBlockSize;
      std::memset(card.data() + block * hal::kBlockSize, 0, hal::kBlockSize);
    } else {  // cut the file at a block boundary
      const size_t cut = (where / hal::kBlockSize) * hal::kBlockSize;
      if (cut < length) length = cut;
    }
  }

  // Read back.
  hal::FakeBlockDevice damaged(Span<uint8_t>(card.data(), length));
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
  uint32_t intact = 0;  // commit slots that survived byte for byte
  for (uint32_t k = 0; k < 2; ++k) {
    intact += std::memcmp(slots_before[k], card.data() + (k + 1) * hal::kBlockSize,
                          kSlotBytes) == 0
                  ? 1u
                  : 0u;
  }
  const uint32_t missing = written - read;
  const uint32_t unreported = missing > reader.lost_records() ? missing - reader.lost_records() : 0;
  if (length < storage::kFirstRecordOffset) {  // cut inside the slots: lost, count unknown
    if (written > 0 && reported == 0) violated("a cut inside the commit slots unreported", 0, 0);
  } else if (intact == 0) {
    // Neither commit left: the reader cannot know the end, and must say so whenever it
    // returns fewer records than were written.
    if (read < written && reported == 0) violated("damaged commits not reported", written, read);
  } else if (intact == 1) {
    // The other commit holds one record less: what a power cut while writing the last
    // record looks like, so at most that one may vanish unreported.
    if (unreported > 1) violated("records lost silently (slots damaged)", missing, unreported);
  } else {
    if (unreported != 0) violated("records lost silently", missing, reader.lost_records());
    if (missing > 0 && reported == 0) violated("a loss without kDataLoss", missing, 0);
  }
  return 0;
}
