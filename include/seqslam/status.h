// One error vocabulary for the whole library.
//
// Bad input is not a bug: every function that can be handed bad input returns a Status (or a
// Result<T>) and leaves its outputs and state untouched on failure. A broken *invariant* (a bug
// in this library) is different and traps via SEQSLAM_ASSERT (see assert.h).
#pragma once

#include <stdint.h>

#include "seqslam/assert.h"

namespace seqslam {

// Codes follow the gRPC/Pigweed canon so they read the same across projects. Ok is 0.
// (clang-format 14 mangles the attribute on an enum, hence the markers.)
// clang-format off
enum class [[nodiscard]] Status : uint8_t {
  kOk = 0,
  kInvalidArgument = 1,     // the argument is malformed whatever the state (e.g. width 0)
  kOutOfRange = 2,          // a value is outside the supported range (e.g. image > kMaxPixels)
  kResourceExhausted = 3,   // caller-owned storage is full (e.g. the place library)
  kFailedPrecondition = 4,  // the object is not in a state for this call (e.g. not configured)
  kDataLoss = 5,            // stored data is damaged (checksum, truncation)
  kNotFound = 6,            // the requested item does not exist
  kUnavailable = 7,         // transiently unavailable (hardware, missing snapshot)
  kInternal = 8,            // an invariant was violated; should never be seen
};
// clang-format on

// Short stable name of a status, e.g. "OUT_OF_RANGE", for logs and test messages.
const char* status_name(Status s);

constexpr bool ok(Status s) {
  return s == Status::kOk;
}

// A value or the reason there is none. T must be default-constructible and trivially
// copyable enough for firmware use (no heap, no exceptions).
template <typename T>
class [[nodiscard]] Result {
 public:
  constexpr Result(T value) : status_(Status::kOk), value_(value) {}  // NOLINT: implicit by design
  constexpr Result(Status status) : status_(status), value_() {}      // NOLINT: implicit by design

  constexpr bool ok() const { return status_ == Status::kOk; }
  constexpr Status status() const { return status_; }
  // The value; only when ok(). Reading the value of an error is a bug in the caller (it
  // would silently use a default-constructed T), so it traps; value_or() is the way to
  // read a result that may be an error.
  constexpr const T& value() const {
    SEQSLAM_ASSERT(ok());
    return value_;
  }
  constexpr T value_or(T fallback) const { return ok() ? value_ : fallback; }

 private:
  Status status_;
  T value_;
};

}  // namespace seqslam

// Propagates a failure: evaluates `expr` (a Status) once and returns it from the enclosing
// function unless it is kOk (Pigweed's PW_TRY). For the early returns that would otherwise be
// written out at every call: `SEQSLAM_TRY(device.read(block, 1, buf));`.
#define SEQSLAM_TRY(expr)                                      \
  do {                                                         \
    const ::seqslam::Status seqslam_try_status_ = (expr);      \
    if (seqslam_try_status_ != ::seqslam::Status::kOk) {       \
      return seqslam_try_status_;                              \
    }                                                          \
  } while (0)
