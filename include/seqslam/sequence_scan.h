// The relocalisation scan: the full search at one step, spread over as many steps as the
// budget needs (docs/firmware.md, "Localising on a whole route").
//
// When the board does not know where it is (an unknown start, a kidnap, a jump between parts
// of the route, or too long without a fix), the windowed matcher cannot help: the place may be
// anywhere in the library. A full search needs every library image compared with the S query
// images of a sequence - S x M differences, far more than one step's budget on the head board
// (M = 5 000: about 290 M instructions and 2.5 MB read from the card). So the scan fixes an
// anchor step and computes, over many calls, exactly the answer the diagonal matcher would give
// at the anchor had it been reset S - 1 steps before (same normalised values, sums, offset,
// best, runner-up and confidence: tests/unit/test_sequence_scan.cpp) - the global answer, with
// the global runner-up the windowed matcher cannot see.
//
// How: the library is streamed once, in place order, a chunk of images at a time (the image
// store's view); each chunk is compared with each of the S query images (QueryHistory, read
// once per chunk). Every row keeps the window sums of its local normalisation and its last
// 2 h + 1 raw differences (h = W / 2), so a place's normalised value is final h places after
// it was read; the value of row k at place f is added to the sequence ending at place f + k.
// A sequence is complete once every row has passed its place; complete costs go into a list
// of the 2 R + 2 lowest (by cost, then place), which is enough to hold both the best and the
// best more than R places from it, whichever the final best is. Anytime: result() is the best
// complete sequence so far (marked incomplete) at any point.
//
// Memory (SequenceScanStorage): S (2 h + 1) raw values of 17 bits (kScanHighBits), 24 bytes of
// window sums a row, S + kMaxScanChunk + h + 1 partial sums, 2 R + 2 ranked entries: for
// S = 30, W = 50, R = 10 about 4.6 KB on the head board, whatever M. Work per place
// streamed: S differences (sad_many) and S normalisations; card: the place's image once, and
// S query images per chunk.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/normalise.h"
#include "seqslam/place_library.h"
#include "seqslam/query_history.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// Library images compared per view of the image store (bounds the stack and the partial sums).
inline constexpr uint32_t kMaxScanChunk = 8;

// The raw differences a row keeps are SADs, < 255 kMaxPixels + 1: the low 16 bits in a uint16
// and the rest (kScanHighBits, rounded up to 1, 2 or 4 so no value straddles two words) packed
// into uint32 words - 17 bits a value on the head board (kMaxPixels 512) instead of 32.
namespace detail {
constexpr uint32_t bit_length(uint32_t v) {
  uint32_t b = 0;
  for (; v != 0; v >>= 1)
    ++b;
  return b;
}
constexpr uint32_t high_bits(uint32_t bits) {
  return bits <= 17 ? 1u : (bits <= 18 ? 2u : 4u);
}
}  // namespace detail
inline constexpr uint32_t kScanHighBits = detail::high_bits(detail::bit_length(255u * kMaxPixels));
static_assert(255u * kMaxPixels < (1u << (16 + kScanHighBits)), "SADs must fit the packed ring");
// uint32 words of high bits for a row of `cells` raw values.
constexpr uint32_t scan_high_words(uint32_t cells) {
  return (cells * kScanHighBits + 31u) / 32u;
}

struct ScanRow {  // one query row's streaming normalisation
  uint64_t s2 = 0;
  uint32_t s1 = 0;
  uint32_t low = 0;     // first place of the window the sums hold
  uint32_t places = 0;  // the library size this row was matched against
};

// A partial diagonal sum, for the sequence ending at a place: the sum of its terms (each <
// 2^16, at most kMaxSeqLen of them: below 2^25) and their count in the top 7 bits, one word.
struct ScanEnd {
  static constexpr uint32_t kTermShift = 25;
  uint32_t packed = 0;
  uint32_t sum() const { return packed & ((1u << kTermShift) - 1u); }
  uint32_t terms() const { return packed >> kTermShift; }
  void add(uint16_t value) { packed += value + (1u << kTermShift); }
};
static_assert(kMaxSeqLen < (1u << (32 - ScanEnd::kTermShift)) &&
                  uint64_t{kMaxSeqLen} * 0xFFFFu < (uint64_t{1} << ScanEnd::kTermShift),
              "a scan's partial sum and its count must share one word");

struct ScanRank {  // a complete sequence: its cost and end place
  uint32_t cost = 0;
  uint32_t place = 0;
};

struct SequenceScanBuffers {
  Span<uint16_t> raw;       // >= seq_len * (2 (window / 2) + 1): low 16 bits of each value
  Span<uint32_t> raw_high;  // >= seq_len * scan_high_words(2 (window / 2) + 1)
  Span<ScanRow> rows;       // >= seq_len
  Span<ScanEnd> ends;       // >= seq_len + kMaxScanChunk + window / 2 + 1
  Span<ScanRank> ranked;    // >= 2 exclusion + 2
  // Optional: >= seq_len x pixels keeps the scan's query images in RAM (read from the history
  // once a scan, not once a chunk: the card's requests are what a chunk costs on the board).
  Span<uint8_t> queries{};
};

// Storage for sequences up to kSeqLen, normalisation windows up to kWindow and exclusions up
// to kExclusion, for static allocation; with kRowPixels > 0, the query images of scans whose
// kSeqLen x pixels fit kSeqLen x kRowPixels stay in RAM (SequenceScanBuffers::queries).
template <uint16_t kSeqLen, uint16_t kWindow, uint16_t kExclusion, uint32_t kRowPixels = 0>
struct SequenceScanStorage {
  static_assert(kSeqLen > 0 && kSeqLen <= kMaxSeqLen && kWindow <= kMaxWindow, "bad capacity");
  static constexpr uint32_t kCells = 2u * (kWindow / 2u) + 1u;
  static constexpr uint32_t kRaw = static_cast<uint32_t>(kSeqLen) * kCells;
  static constexpr uint32_t kRawHigh = static_cast<uint32_t>(kSeqLen) * scan_high_words(kCells);
  static constexpr uint32_t kEnds = kSeqLen + kMaxScanChunk + kWindow / 2u + 1u;
  static constexpr uint32_t kRanked = 2u * kExclusion + 2u;
  static constexpr uint32_t kQueries = static_cast<uint32_t>(kSeqLen) * kRowPixels;
  static constexpr size_t kBytes = sizeof(uint16_t) * kRaw + sizeof(uint32_t) * kRawHigh +
                                   sizeof(ScanRow) * kSeqLen + sizeof(ScanEnd) * kEnds +
                                   sizeof(ScanRank) * kRanked + kQueries;
  uint16_t raw[kRaw];
  uint32_t raw_high[kRawHigh];
  ScanRow rows[kSeqLen];
  ScanEnd ends[kEnds];
  ScanRank ranked[kRanked];
  uint8_t queries[kQueries > 0 ? kQueries : 1];
  SequenceScanBuffers buffers() {
    return {Span<uint16_t>(raw, kRaw),       Span<uint32_t>(raw_high, kRawHigh),
            Span<ScanRow>(rows, kSeqLen),    Span<ScanEnd>(ends, kEnds),
            Span<ScanRank>(ranked, kRanked), Span<uint8_t>(queries, kQueries)};
  }
};

// What a scan has found so far.
struct ScanResult {
  Match match;            // as DiagonalMatcher::step at the anchor (query = anchor step)
  bool complete = false;  // the whole library has been scanned: match is final
  uint32_t scanned = 0;   // library places streamed so far
  uint32_t places = 0;    // places the scan streams in all
};

class SequenceScan {
 public:
  // Adopts the sequence configuration (S, W, sigma_min, R, threshold) for images of `pixels`
  // pixels. Statuses of check_sequence_config; kOutOfRange for pixels outside 1..kMaxPixels;
  // kResourceExhausted if a buffer is smaller than SequenceScanBuffers says.
  Status configure(const SequenceConfig& config, uint32_t pixels,
                   const SequenceScanBuffers& buffers);

  // Starts a scan of the sequence ending at step `anchor`: its S query images (steps
  // anchor - S + 1 .. anchor) must be in `history`, whose library sizes it takes now (no
  // image is read before advance()). kFailedPrecondition before configure(), kOutOfRange if
  // anchor < S - 1, kNotFound if the history lacks one of the steps. A running scan is
  // abandoned.
  Status start(uint32_t anchor, QueryHistory& history);

  // Streams up to `budget` more library places, in chunks of up to kMaxScanChunk. With the
  // query images in RAM (SequenceScanBuffers::queries), a scan's first call reads them from
  // the history and streams nothing (its own piece of work: S history reads).
  // kFailedPrecondition without a running scan (or if the library shrank below what the scan
  // streams: it is abandoned). A library read error passes through with the scan unchanged
  // (calling again retries the chunk); a history error (kNotFound when the anchor's rows have
  // been overwritten, or a storage error) abandons the scan, since some rows of the chunk may
  // have advanced: start a new one. *streamed (if not null) gets the places streamed.
  Status advance(PlaceLibrary& library, QueryHistory& history, uint32_t budget,
                 uint32_t* streamed = nullptr);

  // Abandons a running scan.
  void stop() { running_ = false; }
  bool running() const { return running_; }
  bool complete() const { return configured_ && !running_ && finished_; }
  uint32_t anchor() const { return anchor_; }
  // The answer so far (place -1 until a sequence is complete).
  ScanResult result() const;
  const SequenceConfig& config() const { return config_; }

 private:
  void push(uint32_t k, uint32_t place, uint32_t raw);
  Status load_rows(QueryHistory& history);
  uint32_t raw_at(uint32_t k, uint32_t cell) const;
  void set_raw(uint32_t k, uint32_t cell, uint32_t value);
  void finish_row(uint32_t k);
  void add(uint32_t k, uint32_t place, uint16_t value);
  void settle(int64_t last_end);
  void rank(uint32_t cost, uint32_t place);
  int64_t frontier() const;

  SequenceConfig config_{};
  SequenceScanBuffers buffers_{};
  LocalNormaliser normaliser_{};
  uint32_t pixels_ = 0;
  uint32_t ring_ = 1;  // 2 h + 1 raw values a row
  uint32_t anchor_ = 0;
  uint32_t stream_end_ = 0;  // largest row library size: places to stream
  uint32_t next_place_ = 0;  // next library place to stream
  uint32_t next_end_ = 0;    // next sequence end to settle
  uint32_t ranked_count_ = 0;
  uint16_t min_value_ = 0xFFFF;
  bool configured_ = false;
  bool running_ = false;
  bool finished_ = false;
  bool rows_in_ram_ = false;  // the query images fit buffers_.queries ...
  bool rows_loaded_ = false;  // ... and the running scan's are there
};

}  // namespace seqslam
