#include "seqslam/sequence_scan.h"

#include "seqslam/difference.h"

namespace seqslam {

Status SequenceScan::configure(const SequenceConfig& config, uint32_t pixels,
                               const SequenceScanBuffers& buffers) {
  Status s = check_sequence_config(config);
  if (s != Status::kOk) return s;
  LocalNormaliser normaliser;
  s = normaliser.configure(config.window, config.sigma_min, pixels);
  if (s != Status::kOk) return s;
  const uint32_t ring = 2u * normaliser.half() + 1u;
  if (buffers.raw.size() < static_cast<size_t>(config.seq_len) * ring ||
      buffers.raw_high.size() < static_cast<size_t>(config.seq_len) * scan_high_words(ring) ||
      buffers.rows.size() < config.seq_len ||
      buffers.ends.size() <
          static_cast<size_t>(config.seq_len) + kMaxScanChunk + normaliser.half() + 1u ||
      buffers.ranked.size() < 2u * static_cast<size_t>(config.exclusion) + 2u) {
    return Status::kResourceExhausted;
  }
  config_ = config;
  buffers_ = buffers;
  normaliser_ = normaliser;
  pixels_ = pixels;
  ring_ = ring;
  rows_in_ram_ = buffers.queries.size() >= static_cast<size_t>(config.seq_len) * pixels;
  configured_ = true;
  running_ = false;
  finished_ = false;
  return Status::kOk;
}

Status SequenceScan::start(uint32_t anchor, QueryHistory& history) {
  if (!configured_) return Status::kFailedPrecondition;
  const uint32_t seq = config_.seq_len;
  if (anchor + 1 < seq) return Status::kOutOfRange;
  running_ = false;
  finished_ = false;
  stream_end_ = 0;
  for (uint32_t k = 0; k < seq; ++k) {
    if (!history.contains(anchor - k)) return Status::kNotFound;
  }
  for (uint32_t k = 0; k < seq; ++k) {
    // The row's library size only (kept in RAM): its image is read as the scan streams.
    uint32_t places = 0;
    SEQSLAM_TRY(history.places(anchor - k, &places));
    buffers_.rows[k] = ScanRow{0, 0, 0, places};
    if (places > stream_end_) stream_end_ = places;
  }
  const size_t ends = buffers_.ends.size();
  for (size_t e = 0; e < ends; ++e)
    buffers_.ends[e] = ScanEnd{};
  anchor_ = anchor;
  rows_loaded_ = false;
  next_place_ = 0;
  next_end_ = 0;
  ranked_count_ = 0;
  min_value_ = 0xFFFF;
  running_ = true;
  // An empty library: nothing to stream; the scan is complete with no answer.
  if (stream_end_ == 0) {
    running_ = false;
    finished_ = true;
  }
  return Status::kOk;
}

uint32_t SequenceScan::raw_at(uint32_t k, uint32_t cell) const {
  const uint32_t low = buffers_.raw[static_cast<size_t>(k) * ring_ + cell];
  const uint32_t bit = cell * kScanHighBits;
  const uint32_t word = buffers_.raw_high[k * scan_high_words(ring_) + bit / 32u];
  const uint32_t high = (word >> (bit % 32u)) & ((1u << kScanHighBits) - 1u);
  return low | high << 16;
}

void SequenceScan::set_raw(uint32_t k, uint32_t cell, uint32_t value) {
  buffers_.raw[static_cast<size_t>(k) * ring_ + cell] = static_cast<uint16_t>(value);
  const uint32_t bit = cell * kScanHighBits;
  uint32_t& word = buffers_.raw_high[k * scan_high_words(ring_) + bit / 32u];
  const uint32_t mask = ((1u << kScanHighBits) - 1u) << (bit % 32u);
  word = (word & ~mask) | ((value >> 16) << (bit % 32u) & mask);
}

// Row k's raw difference at `place` arrives (places arrive in order). The row's window sums
// then hold [max(0, place - 2h), place], which is exactly place - h's window, so that place's
// normalised value is final.
void SequenceScan::push(uint32_t k, uint32_t place, uint32_t raw) {
  ScanRow& row = buffers_.rows[k];
  const uint32_t cell = place % ring_;
  if (place >= ring_) {  // the cell holds place - (2h + 1), which leaves the window
    const uint32_t out = raw_at(k, cell);
    row.s1 -= out;
    row.s2 -= static_cast<uint64_t>(out) * out;
    row.low = place - ring_ + 1;
  }
  set_raw(k, cell, raw);
  row.s1 += raw;
  row.s2 += static_cast<uint64_t>(raw) * raw;
  const uint32_t h = normaliser_.half();
  if (place >= h) {
    const uint32_t f = place - h;
    add(k, f, normaliser_.value_of(raw_at(k, f % ring_), place - row.low + 1, row.s1, row.s2));
  }
}

// Row k has had its last place: the places within h of its end get their clipped windows.
void SequenceScan::finish_row(uint32_t k) {
  ScanRow& row = buffers_.rows[k];
  const uint32_t h = normaliser_.half();
  const uint32_t last = row.places - 1;
  for (uint32_t f = last >= h ? last - h + 1 : 0; f <= last; ++f) {
    while (row.low + h < f) {  // the window of f starts at f - h
      const uint32_t out = raw_at(k, row.low % ring_);
      row.s1 -= out;
      row.s2 -= static_cast<uint64_t>(out) * out;
      ++row.low;
    }
    add(k, f, normaliser_.value_of(raw_at(k, f % ring_), last - row.low + 1, row.s1, row.s2));
  }
}

// Row k's value at `place` belongs to the sequence that ends at place + k at the anchor.
void SequenceScan::add(uint32_t k, uint32_t place, uint16_t value) {
  buffers_.ends[(place + k) % buffers_.ends.size()].add(value);
  if (value < min_value_) min_value_ = value;
}

// The last sequence end to which every row has added its value, given what has been streamed
// (-1: none yet). An unfinished row has final values up to h places behind the stream; the
// lowest unfinished row is the one that holds the ends back. Finished rows hold nothing back.
int64_t SequenceScan::frontier() const {
  const int64_t final_place = static_cast<int64_t>(next_place_) - 1 - normaliser_.half();
  for (uint32_t k = 0; k < config_.seq_len; ++k) {
    if (buffers_.rows[k].places > next_place_) return final_place + k;
  }
  return static_cast<int64_t>(stream_end_) + config_.seq_len;
}

// Sequence ends next_end_ .. last_end are complete: rank the full ones, free their slots.
void SequenceScan::settle(int64_t last_end) {
  const uint32_t seq = config_.seq_len;
  const size_t n = buffers_.ends.size();
  for (; static_cast<int64_t>(next_end_) <= last_end; ++next_end_) {
    ScanEnd& e = buffers_.ends[next_end_ % n];
    if (e.terms() == seq) rank(e.sum(), next_end_);
    e = ScanEnd{};
  }
}

void SequenceScan::rank(uint32_t cost, uint32_t place) {
  ScanRank* r = buffers_.ranked.data();
  const uint32_t cap = 2u * config_.exclusion + 2u;
  // Lexicographic (cost, place); places arrive in increasing order, so an equal cost ranks
  // after the ones already there.
  uint32_t pos = ranked_count_;
  while (pos > 0 && r[pos - 1].cost > cost)
    --pos;
  if (pos >= cap) return;
  const uint32_t end = ranked_count_ < cap ? ranked_count_ : cap - 1;
  for (uint32_t i = end; i > pos; --i)
    r[i] = r[i - 1];
  r[pos] = ScanRank{cost, place};
  if (ranked_count_ < cap) ++ranked_count_;
}

Status SequenceScan::advance(PlaceLibrary& library, QueryHistory& history, uint32_t budget,
                             uint32_t* streamed) {
  if (streamed != nullptr) *streamed = 0;
  if (!running_) return Status::kFailedPrecondition;
  const uint32_t seq = config_.seq_len;
  if (rows_in_ram_ && !rows_loaded_ && next_place_ < stream_end_) {
    const Status s = load_rows(history);
    if (s != Status::kOk) running_ = false;  // a history error: start a new scan
    return s;
  }
  uint32_t done = 0;
  while (done < budget && next_place_ < stream_end_) {
    uint32_t want = stream_end_ - next_place_;
    if (want > budget - done) want = budget - done;
    if (want > kMaxScanChunk) want = kMaxScanChunk;
    if (next_place_ + want > library.size()) {
      running_ = false;  // the library shrank under the scan: nothing sensible to finish
      return Status::kFailedPrecondition;
    }
    const uint8_t* images = nullptr;
    uint32_t chunk = 0;
    Status s = library.view(next_place_, want, &images, &chunk);
    if (s != Status::kOk) return s;
    uint32_t sums[kMaxScanChunk];
    for (uint32_t c = 0; c < chunk; ++c)
      sums[c] = pixel_sum(images + static_cast<size_t>(c) * pixels_, pixels_);
    // Row by row, oldest step first (the history prefetches consecutive steps in one card
    // request); the chunk stays in the image store's view meanwhile (the history is another
    // file, with its own buffer). Rows are independent: their order changes no sum.
    uint32_t ready = 0;  // rows from k down whose images the history has prefetched
    for (uint32_t k = seq; k-- > 0;) {
      const uint32_t places = buffers_.rows[k].places;
      const bool ended = next_place_ >= places;
      const uint8_t* query = nullptr;
      if (rows_in_ram_) {
        query = buffers_.queries.data() + static_cast<size_t>(k) * pixels_;
      } else {
        if (ready == 0 && !ended) s = history.prefetch(anchor_ - k, k + 1, &ready);
        if (ready > 0) --ready;
        uint32_t row_places = 0;
        if (!ended && s == Status::kOk) s = history.get(anchor_ - k, &query, &row_places);
      }
      if (ended) continue;
      if (s != Status::kOk) {
        running_ = false;  // other rows have advanced: the scan cannot resume
        return s;
      }
      uint32_t raw[kMaxScanChunk];
      const uint32_t n = places - next_place_ < chunk ? places - next_place_ : chunk;
      sad_many(query, images, sums, n, pixels_, raw);
      for (uint32_t c = 0; c < n; ++c)
        push(k, next_place_ + c, raw[c]);
      if (next_place_ + n == places) finish_row(k);
    }
    next_place_ += chunk;
    done += chunk;
    settle(frontier());
  }
  if (streamed != nullptr) *streamed = done;
  if (next_place_ >= stream_end_) {
    settle(static_cast<int64_t>(stream_end_) + seq);
    running_ = false;
    finished_ = true;
  }
  return Status::kOk;
}

// The running scan's query images into RAM, oldest first (the history prefetches
// consecutive steps in one request where its buffer holds them).
Status SequenceScan::load_rows(QueryHistory& history) {
  uint32_t ready = 0;
  for (uint32_t k = config_.seq_len; k-- > 0;) {
    if (ready == 0) SEQSLAM_TRY(history.prefetch(anchor_ - k, k + 1, &ready));
    if (ready > 0) --ready;
    const uint8_t* query = nullptr;
    uint32_t row_places = 0;
    SEQSLAM_TRY(history.get(anchor_ - k, &query, &row_places));
    uint8_t* to = buffers_.queries.data() + static_cast<size_t>(k) * pixels_;
    for (uint32_t p = 0; p < pixels_; ++p)
      to[p] = query[p];
  }
  rows_loaded_ = true;
  return Status::kOk;
}

ScanResult SequenceScan::result() const {
  ScanResult out;
  out.complete = finished_ && !running_;
  out.scanned = next_place_;
  out.places = stream_end_;
  Match& m = out.match;
  m.query = anchor_;
  if (ranked_count_ == 0) return out;
  const ScanRank* r = buffers_.ranked.data();
  const uint32_t offset =
      min_value_ == 0xFFFF ? 0u : static_cast<uint32_t>(config_.seq_len) * min_value_;
  m.place = static_cast<int32_t>(r[0].place);
  m.cost = r[0].cost - offset;
  const uint32_t gap = config_.exclusion;
  for (uint32_t i = 1; i < ranked_count_; ++i) {
    const uint32_t d = r[i].place > r[0].place ? r[i].place - r[0].place : r[0].place - r[i].place;
    if (d <= gap) continue;
    m.runner_up = static_cast<int32_t>(r[i].place);
    m.runner_up_cost = r[i].cost - offset;
    m.confidence = confidence_ratio(m.cost, m.runner_up_cost);
    m.localised = out.complete && m.confidence < config_.threshold;
    break;
  }
  return out;
}

}  // namespace seqslam
