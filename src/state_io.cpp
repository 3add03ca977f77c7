#include "seqslam/state_io.h"

namespace seqslam {

void StateOut::put(uint64_t v, uint32_t size) {
  if (!ok()) return;
  uint8_t b[8];
  for (uint32_t i = 0; i < size; ++i)
    b[i] = static_cast<uint8_t>(v >> (8 * i));
  const Status s = sink_->write(b, size);
  if (s != Status::kOk) fail_with(s);
  bytes_ += size;
}

void StateIn::get(uint64_t* v, uint32_t size) {
  if (!ok()) return;
  uint8_t b[8];
  const Status s = source_->read(b, size);
  if (s != Status::kOk) {
    fail_with(s);
    return;
  }
  uint64_t r = 0;
  for (uint32_t i = 0; i < size; ++i)
    r |= static_cast<uint64_t>(b[i]) << (8 * i);
  *v = r;
}

}  // namespace seqslam
