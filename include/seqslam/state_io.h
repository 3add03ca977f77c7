// Saving a component's run state and restoring it later, so that a run stopped on the card can
// be continued exactly where it stopped (issue 15: continuing an explore run).
//
// Each component that carries state from one place to the next lists its fields once, in a
// member template `template <class Io> void state(Io& io)` that calls io.field(...) for every
// field. StateOut writes them, StateIn reads them back in the same order, so save and restore
// cannot drift apart. Fields are written little-endian, integer by integer (no struct padding,
// no host layout), into a StateSink (e.g. a record log on the card, storage/checkpoint.h).
//
// Only state is saved, never configuration or buffers: the component is configured as usual
// first (the same settings and capacities), then restored. What a component restores is
// checked against its buffers before it is used (a count beyond a capacity, an index beyond a
// count): a damaged or foreign state is refused with kDataLoss and the component is reset,
// never used to index memory. Each component's section starts with a tag, so a state saved by
// another layout is refused at its first differing section rather than misread.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/span.h"
#include "seqslam/status.h"
#include "seqslam/wide_int.h"

namespace seqslam {

// Where saved bytes go; the implementation may buffer them (write may be called per field).
class StateSink {
 public:
  virtual Status write(const uint8_t* data, uint32_t size) = 0;

 protected:
  ~StateSink() = default;
};

// Where saved bytes come from, in the order they were written; kDataLoss past the end.
class StateSource {
 public:
  virtual Status read(uint8_t* data, uint32_t size) = 0;

 protected:
  ~StateSource() = default;
};

// A section tag from four characters, e.g. state_tag("PGRF").
constexpr uint32_t state_tag(const char (&s)[5]) {
  return static_cast<uint32_t>(static_cast<uint8_t>(s[0])) |
         static_cast<uint32_t>(static_cast<uint8_t>(s[1])) << 8 |
         static_cast<uint32_t>(static_cast<uint8_t>(s[2])) << 16 |
         static_cast<uint32_t>(static_cast<uint8_t>(s[3])) << 24;
}

// The field overloads both directions share; Derived provides integer(T&) for the unsigned
// widths and records the first error (later fields are then skipped).
template <class Derived>
class StateIoBase {
 public:
  Status status() const { return status_; }
  bool ok() const { return status_ == Status::kOk; }

  void field(uint8_t& v) { self().integer(v); }
  void field(uint16_t& v) { self().integer(v); }
  void field(uint32_t& v) { self().integer(v); }
  void field(uint64_t& v) { self().integer(v); }
  void field(int8_t& v) { signed_field<uint8_t>(v); }
  void field(int16_t& v) { signed_field<uint16_t>(v); }
  void field(int32_t& v) { signed_field<uint32_t>(v); }
  void field(int64_t& v) { signed_field<uint64_t>(v); }
  void field(bool& v) {
    uint8_t b = v ? 1 : 0;
    self().integer(b);
    if (b > 1) fail();
    v = b != 0;
  }
  template <typename Rep, int F>
  void field(Fixed<Rep, F>& v) {
    Rep raw = v.raw();
    field(raw);
    v = Fixed<Rep, F>::from_raw(raw);
  }
  void field(Angle& v) { field(v.bam); }
  void field(Int128& v) {
    uint64_t hi = v.high64();
    uint64_t lo = v.low64();
    field(hi);
    field(lo);
    v = Int128::from_parts(hi, lo);
  }
  // An enum stored in its underlying width; values above `last` are refused.
  template <typename E>
  void enumeration(E& v, E last) {
    uint8_t raw = static_cast<uint8_t>(v);
    self().integer(raw);
    if (raw > static_cast<uint8_t>(last)) fail();
    v = static_cast<E>(raw);
  }
  // A struct: persist(io, value), a free function beside the struct's definition (found by
  // argument-dependent lookup), e.g. persist(Io&, Pose2&) in odometry.h.
  template <typename T>
  void field(T& v) {
    persist(self(), v);
  }
  // Every element of `items`.
  template <typename T>
  void array(Span<T> items) {
    for (size_t i = 0; i < items.size() && ok(); ++i)
      field(items[i]);
  }
  // A section's tag: written, or read and compared (a mismatch is kDataLoss).
  void tag(uint32_t expected) {
    uint32_t t = expected;
    self().integer(t);
    if (t != expected) fail();
  }
  // A restored value failed its component's check.
  void fail() { fail_with(Status::kDataLoss); }
  // The first error wins (e.g. kFailedPrecondition: the component cannot save this state).
  void fail_with(Status s) {
    if (status_ == Status::kOk) status_ = s;
  }

 private:
  Derived& self() { return static_cast<Derived&>(*this); }
  template <typename U, typename S>
  void signed_field(S& v) {
    U u = static_cast<U>(v);
    self().integer(u);
    v = static_cast<S>(u);
  }
  Status status_ = Status::kOk;
};

// Saving: every field goes to the sink; the first sink error stops the rest.
class StateOut final : public StateIoBase<StateOut> {
 public:
  static constexpr bool kReading = false;
  explicit StateOut(StateSink& sink) : sink_(&sink) {}
  uint64_t bytes() const { return bytes_; }

  template <typename U>
  void integer(U& v) {
    put(v, sizeof(U));
  }

 private:
  // One out-of-line call per field keeps the field lists small in code (state_io.cpp).
  void put(uint64_t v, uint32_t size);

  StateSink* sink_;
  uint64_t bytes_ = 0;
};

// Restoring: every field comes from the source; after the first error the fields keep
// their values and the caller resets the component.
class StateIn final : public StateIoBase<StateIn> {
 public:
  static constexpr bool kReading = true;
  explicit StateIn(StateSource& source) : source_(&source) {}

  template <typename U>
  void integer(U& v) {
    uint64_t r = v;
    get(&r, sizeof(U));
    v = static_cast<U>(r);
  }

 private:
  // Leaves *v as it is after an error (state_io.cpp).
  void get(uint64_t* v, uint32_t size);

  StateSource* source_;
};

}  // namespace seqslam
