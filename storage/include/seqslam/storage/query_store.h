// The query history (seqslam/query_history.h) on the SD card: the relocalisation scan's
// query images stay on the card, so the head board's RAM holds only a buffer of a few images
// and the library size of each step, as one bit a step: whether it grew by one place since
// the step before (the localiser's library stays the same in repeat mode and grows by one
// place a step in loop-closure mode; any other change is refused).
//
// A volume file (`queries`, docs/firmware.md) of `steps` slots; slot s starts at block
// s x ceil(A / 512) and holds one preprocessed image (A bytes, the rest of its last block
// zero). It is scratch: written every localisation step (one write request, no sync: a power
// cut loses nothing that matters, the next run starts with an empty history) and read back by
// the scan, as many consecutive slots a read request as the buffer holds. Nothing in it is
// trusted across runs: configure() forgets every step.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/query_history.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam::storage {

inline constexpr const char* kQueriesFile = "queries";

class StoredQueryHistory final : public QueryHistory {
 public:
  // Uses `device` (the `queries` file) for images of `pixels` pixels; `buffer` holds one slot
  // (ceil(pixels / 512) blocks) or more: prefetch() reads as many consecutive slots as it
  // holds in one request. `grew` holds one bit per step (32 a word). Capacity: the slots the
  // file holds, at most 32 x grew.size(). kInvalidArgument for 0 pixels or a buffer smaller
  // than a slot; kResourceExhausted if not one slot fits.
  Status configure(hal::BlockDevice& device, uint32_t pixels, Span<uint8_t> buffer,
                   Span<uint32_t> grew);

 private:
  uint32_t do_capacity() const override { return capacity_; }
  uint32_t do_pixels() const override { return pixels_; }
  // kOutOfRange unless the size equals the last step's or exceeds it by one.
  Status do_check_places(uint32_t places) const override {
    return !sized_ || places == current_ || places == current_ + 1 ? Status::kOk
                                                                   : Status::kOutOfRange;
  }
  void do_clear() override { sized_ = false; }
  Status do_put(uint32_t slot, const uint8_t* pixels) override;
  Status do_get(uint32_t slot, const uint8_t** pixels) override;
  Status do_prefetch(uint32_t slot, uint32_t count, uint32_t* ready) override;
  void places_slot(uint32_t slot, uint32_t places) override;
  uint32_t places_at(uint32_t slot) const override;
  bool grew_at(uint32_t slot) const { return (grew_[slot / 32u] >> (slot % 32u)) & 1u; }

  hal::BlockDevice* device_ = nullptr;
  Span<uint8_t> buffer_{};
  Span<uint32_t> grew_{};
  uint32_t current_ = 0;    // the library size of the last step stored
  uint32_t last_slot_ = 0;  // ... and its slot
  bool sized_ = false;
  uint32_t pixels_ = 0;
  uint32_t slot_blocks_ = 1;
  uint32_t capacity_ = 1;
  uint32_t buffered_ = 0xFFFFFFFFu;  // the first slot the buffer holds ...
  uint32_t buffered_slots_ = 0;       // ... and how many
};

}  // namespace seqslam::storage
