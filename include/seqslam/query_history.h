// The preprocessed query images of the last steps, for the relocalisation scan
// (sequence_scan.h), which compares the library with the S images of the sequence ending at
// its anchor step while the robot drives on.
//
// Steps are stored in order, one image per step (put() of step t after step t - 1), in a ring
// of capacity() steps: step t is available while fewer than capacity() steps followed it. With
// each image the library size the localiser matched it against (`places`), which grows from
// step to step in loop-closure mode and the scan needs per row. Implementations: RAM
// (RamQueryHistory, below) and the SD card (storage/query_store.h: the images on the card,
// the sizes in RAM as one bit a step).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

class QueryHistory {
 public:
  // Steps kept.
  uint32_t capacity() const { return do_capacity(); }
  // Pixels per image.
  uint32_t pixels() const { return do_pixels(); }

  // Stores the image of `step` (the next step after the last put(), or any step after a
  // clear()). kInvalidArgument for a null image, kFailedPrecondition if step does not follow
  // the last one, kOutOfRange for a library size the implementation cannot keep; storage
  // errors (kDataLoss, kUnavailable) pass through. On failure the step is not stored.
  Status put(uint32_t step, const uint8_t* pixels, uint32_t places) {
    if (pixels == nullptr) return Status::kInvalidArgument;
    if (has_last_ && step != last_ + 1) return Status::kFailedPrecondition;
    Status s = do_check_places(places);
    if (s != Status::kOk) return s;
    s = do_put(step % do_capacity(), pixels);
    if (s != Status::kOk) {
      // The slot may be half overwritten: the step it held is gone too.
      if (has_last_ && step >= do_capacity()) lost_ = step - do_capacity(), has_lost_ = true;
      return s;
    }
    places_slot(step % do_capacity(), places);
    last_ = step;
    has_last_ = true;
    return Status::kOk;
  }

  // The image of `step` (valid until the next call to this history) and its library size.
  // kNotFound if the step was never stored or has been overwritten; kInvalidArgument for null
  // outputs; storage errors pass through.
  Status get(uint32_t step, const uint8_t** pixels, uint32_t* places) {
    if (pixels == nullptr || places == nullptr) return Status::kInvalidArgument;
    if (!contains(step)) return Status::kNotFound;
    SEQSLAM_TRY(do_get(step % do_capacity(), pixels));
    *places = places_at(step % do_capacity());
    return Status::kOk;
  }

  // Makes the next get() of steps [step, step + *ready) cheap: the card implementation reads
  // as many consecutive slots as its buffer holds in one request (each request costs the
  // card's access time). *ready (1..count): fewer where the ring wraps, a step is missing or
  // the buffer ends. kNotFound if `step` is not kept; kInvalidArgument for count 0 or a null
  // output; storage errors pass through.
  Status prefetch(uint32_t step, uint32_t count, uint32_t* ready) {
    if (ready == nullptr || count == 0) return Status::kInvalidArgument;
    if (!contains(step)) return Status::kNotFound;
    const uint32_t cap = do_capacity();
    uint32_t n = 1;  // consecutive kept steps from `step`, not across the ring's end
    while (n < count && step % cap + n < cap && contains(step + n))
      ++n;
    return do_prefetch(step % cap, n, ready);
  }

  // The library size stored with `step`. kNotFound if the step is not kept.
  Status places(uint32_t step, uint32_t* out) const {
    if (out == nullptr) return Status::kInvalidArgument;
    if (!contains(step)) return Status::kNotFound;
    *out = places_at(step % do_capacity());
    return Status::kOk;
  }

  bool contains(uint32_t step) const {
    return has_last_ && step <= last_ && last_ - step < do_capacity() &&
           !(has_lost_ && step == lost_);
  }
  // Forgets every step (e.g. the localiser was reset).
  void clear() {
    has_last_ = false;
    has_lost_ = false;
    do_clear();
  }

 protected:
  QueryHistory() = default;
  ~QueryHistory() = default;
  QueryHistory(const QueryHistory&) = default;
  QueryHistory& operator=(const QueryHistory&) = default;

 private:
  virtual uint32_t do_capacity() const = 0;
  virtual uint32_t do_pixels() const = 0;
  virtual Status do_check_places(uint32_t /*places*/) const { return Status::kOk; }
  virtual void do_clear() {}
  virtual Status do_put(uint32_t slot, const uint8_t* pixels) = 0;
  virtual Status do_get(uint32_t slot, const uint8_t** pixels) = 0;
  // Slots [slot, slot + count) (inside the ring) ready for do_get(): *ready of them, >= 1.
  virtual Status do_prefetch(uint32_t /*slot*/, uint32_t count, uint32_t* ready) {
    *ready = count;
    return Status::kOk;
  }
  virtual void places_slot(uint32_t slot, uint32_t places) = 0;
  virtual uint32_t places_at(uint32_t slot) const = 0;

  uint32_t last_ = 0;
  uint32_t lost_ = 0;  // a step whose slot a failed put() overwrote
  bool has_last_ = false;
  bool has_lost_ = false;
};

// Images and sizes in caller-owned RAM: `images` holds capacity * pixels bytes, `places` one
// value per step.
class RamQueryHistory final : public QueryHistory {
 public:
  // kInvalidArgument for 0 pixels; kResourceExhausted if not one step fits.
  Status configure(uint32_t pixels, Span<uint8_t> images, Span<uint32_t> places);

 private:
  uint32_t do_capacity() const override { return capacity_; }
  uint32_t do_pixels() const override { return pixels_; }
  Status do_put(uint32_t slot, const uint8_t* pixels) override;
  Status do_get(uint32_t slot, const uint8_t** pixels) override;
  void places_slot(uint32_t slot, uint32_t places) override { places_[slot] = places; }
  uint32_t places_at(uint32_t slot) const override { return places_[slot]; }

  Span<uint8_t> images_{};
  Span<uint32_t> places_{};
  uint32_t pixels_ = 0;
  uint32_t capacity_ = 1;  // never 0: capacity() is a divisor
};

// Static storage for kSteps steps of kPixels-pixel images.
template <uint32_t kSteps, uint32_t kPixels>
struct RamQueryHistoryStorage {
  static_assert(kSteps > 0 && kPixels > 0, "bad history capacity");
  static constexpr size_t kBytes = kSteps * kPixels + kSteps * sizeof(uint32_t);
  uint8_t images[kSteps * kPixels];
  uint32_t places[kSteps];
  Status attach(RamQueryHistory& history, uint32_t pixels) {
    return history.configure(pixels, Span<uint8_t>(images, kSteps * kPixels),
                             Span<uint32_t>(places, kSteps));
  }
};

}  // namespace seqslam
