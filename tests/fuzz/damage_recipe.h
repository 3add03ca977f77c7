// What the property-oracle fuzz targets of the on-card formats share (fuzz_record_log,
// fuzz_dream_damage): the input is a recipe, not a card. It says what to write, then how to
// damage the card; the target reads the damaged card back and judges what it got against what
// it wrote. Here: reading the recipe, the damage, and the rule for losses that every reader
// of a record log must keep (storage/record_log.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "seqslam/hal/block_device.h"

namespace seqslam::fuzz {

[[noreturn]] inline void violated(const char* format, const char* what, uint32_t a, uint32_t b) {
  std::fprintf(stderr, "%s property violated: %s (%u, %u)\n", format, what, a, b);
  std::abort();
}

// The fuzzer's bytes, read one at a time (0 past the end).
struct Recipe {
  const uint8_t* data;
  size_t size;
  size_t at = 0;
  uint8_t next() { return at < size ? data[at++] : 0; }
  bool more() const { return at < size; }
};

// Blocks 1 and 2 of a format-2 log start with its commit slots (20 bytes each).
inline constexpr uint32_t kSlotBytes = 20;

struct Damage {
  size_t length = 0;    // the card's readable length after any cut (whole blocks)
  uint32_t intact = 0;  // commit slots that survived byte for byte (0-2)
};

// Up to 8 operations on the first `end` bytes of `card` (the written log): a flipped byte, a
// zeroed block, a cut at a block boundary.
inline Damage damage_card(Recipe& in, std::vector<uint8_t>& card, uint64_t end) {
  uint8_t slots_before[2][kSlotBytes];
  for (uint32_t k = 0; k < 2; ++k)
    std::memcpy(slots_before[k], card.data() + (k + 1) * hal::kBlockSize, kSlotBytes);
  Damage d;
  d.length = card.size();
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
      if (cut < d.length) d.length = cut;
    }
  }
  for (uint32_t k = 0; k < 2; ++k) {
    d.intact += std::memcmp(slots_before[k], card.data() + (k + 1) * hal::kBlockSize,
                            kSlotBytes) == 0
                    ? 1u
                    : 0u;
  }
  return d;
}

// What a reader may lose without saying so. `written` records were written, `read` came back
// intact, `reported` kDataLoss statuses were returned, `lost` is the reader's lost count;
// `first_record` is the byte where records start (kFirstRecordOffset):
//   - a cut inside the commit slots: any loss must be reported;
//   - neither commit left: any shortfall must be reported;
//   - one left: the other holds one record less, which reads exactly like a power cut while
//     writing the last record, so at most that one may vanish unreported;
//   - both left: every missing record counted in `lost`, with a kDataLoss.
inline void check_losses(const char* format, const Damage& d, uint64_t first_record,
                         uint32_t written, uint32_t read, uint32_t reported, uint32_t lost) {
  const uint32_t missing = written - read;
  const uint32_t unreported = missing > lost ? missing - lost : 0;
  if (d.length < first_record) {
    if (written > 0 && reported == 0) violated(format, "a cut inside the commit slots unreported", 0, 0);
  } else if (d.intact == 0) {
    if (read < written && reported == 0) violated(format, "damaged commits not reported", written, read);
  } else if (d.intact == 1) {
    if (unreported > 1) violated(format, "records lost silently (slots damaged)", missing, unreported);
  } else {
    if (unreported != 0) violated(format, "records lost silently", missing, lost);
    if (missing > 0 && reported == 0) violated(format, "a loss without kDataLoss", missing, 0);
  }
}

}  // namespace seqslam::fuzz
