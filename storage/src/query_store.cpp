#include "seqslam/storage/query_store.h"

namespace seqslam::storage {

Status StoredQueryHistory::configure(hal::BlockDevice& device, uint32_t pixels,
                                     Span<uint8_t> buffer, Span<uint32_t> grew) {
  if (pixels == 0) return Status::kInvalidArgument;
  const uint32_t blocks = (pixels + hal::kBlockSize - 1) / hal::kBlockSize;
  if (buffer.data() == nullptr || buffer.size() < static_cast<size_t>(blocks) * hal::kBlockSize) {
    return Status::kInvalidArgument;
  }
  uint32_t capacity = device.block_count() / blocks;
  if (grew.size() < (capacity + 31u) / 32u) capacity = static_cast<uint32_t>(grew.size()) * 32u;
  if (capacity == 0) return Status::kResourceExhausted;
  device_ = &device;
  buffer_ = buffer;
  grew_ = grew;
  sized_ = false;
  pixels_ = pixels;
  slot_blocks_ = blocks;
  capacity_ = capacity;
  buffered_ = 0xFFFFFFFFu;
  buffered_slots_ = 0;
  clear();
  return Status::kOk;
}

Status StoredQueryHistory::do_put(uint32_t slot, const uint8_t* pixels) {
  uint8_t* b = buffer_.data();
  const uint32_t bytes = slot_blocks_ * hal::kBlockSize;
  for (uint32_t i = 0; i < bytes; ++i)
    b[i] = i < pixels_ ? pixels[i] : 0;
  buffered_slots_ = 0;  // until the write is known to have landed
  const Status s = device_->write(slot * slot_blocks_, slot_blocks_, b);
  if (s == Status::kOk) {
    buffered_ = slot;
    buffered_slots_ = 1;
  }
  return s;
}

void StoredQueryHistory::places_slot(uint32_t slot, uint32_t places) {
  const uint32_t bit = 1u << (slot % 32u);
  if (sized_ && places == current_ + 1) {
    grew_[slot / 32u] |= bit;
  } else {
    grew_[slot / 32u] &= ~bit;
  }
  current_ = places;
  last_slot_ = slot;
  sized_ = true;
}

// The last step's size less one for every step after `slot`'s that grew (walking back from
// the last slot; the base class only asks for kept steps, so the walk stays inside the ring's
// kept part).
uint32_t StoredQueryHistory::places_at(uint32_t slot) const {
  uint32_t places = current_;
  for (uint32_t s = last_slot_; s != slot; s = s == 0 ? capacity_ - 1 : s - 1) {
    if (grew_at(s)) --places;
  }
  return places;
}

Status StoredQueryHistory::do_get(uint32_t slot, const uint8_t** pixels) {
  uint32_t ready = 0;
  SEQSLAM_TRY(do_prefetch(slot, 1, &ready));
  *pixels = buffer_.data() + static_cast<size_t>(slot - buffered_) * slot_blocks_ *
                                 hal::kBlockSize;
  return Status::kOk;
}

Status StoredQueryHistory::do_prefetch(uint32_t slot, uint32_t count, uint32_t* ready) {
  // Already in the buffer (a scan gets each prefetched group's images in order).
  if (buffered_slots_ > 0 && slot >= buffered_ && slot - buffered_ < buffered_slots_) {
    const uint32_t have = buffered_slots_ - (slot - buffered_);
    *ready = have < count ? have : count;
    return Status::kOk;
  }
  const size_t slot_bytes = static_cast<size_t>(slot_blocks_) * hal::kBlockSize;
  const size_t fit = buffer_.size() / slot_bytes;  // >= 1, checked by configure()
  if (count > fit) count = static_cast<uint32_t>(fit);
  buffered_slots_ = 0;
  SEQSLAM_TRY(device_->read(slot * slot_blocks_, count * slot_blocks_, buffer_.data()));
  buffered_ = slot;
  buffered_slots_ = count;
  *ready = count;
  return Status::kOk;
}

}  // namespace seqslam::storage
