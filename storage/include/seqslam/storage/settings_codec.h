// The card codec and the range check of a settings table (run_config.h), for any table: a
// callable `table(v, config)` that calls v(field, Setting) for each setting and v.pad(bytes)
// for reserved bytes, as visit_run_settings does (RunSettings below). Settings with
// since == kPcOnly are not on the card; the others are stored in table order, little-endian
// at their type's width, composites as the other formats write them (codec.h).
#pragma once

#include <stdint.h>

#include "seqslam/storage/bytes.h"
#include "seqslam/storage/run_config.h"

namespace seqslam::storage {

// The run configuration's table as a callable (the codec's and the tools' Table parameter).
struct RunSettings {
  template <class V, class C>
  constexpr void operator()(V& v, C& c) const {
    visit_run_settings(v, c);
  }
};

namespace settings_detail {

// The composites' byte layouts (storage/src/codec.cpp).
void put(ByteWriter& w, const hal::PipelineMapping& m);
void put(ByteWriter& w, const PreprocessConfig& p);
void put(ByteWriter& w, const OdometryConfig& o);
void get(ByteReader& r, hal::PipelineMapping* m);
void get(ByteReader& r, PreprocessConfig* p);
void get(ByteReader& r, OdometryConfig* o);

class Writer {
 public:
  explicit Writer(ByteWriter& w) : w_(w) {}
  template <class T>
  SEQSLAM_SETTINGS_INLINE void operator()(const T& field, const Setting& s) {
    if (s.since != kPcOnly) put(field);
  }
  void pad(uint32_t bytes) { w_.zeros(bytes); }

 private:
  void put(uint8_t v) { w_.u8(v); }
  void put(uint16_t v) { w_.u16(v); }
  void put(uint32_t v) { w_.u32(v); }
  void put(int32_t v) { w_.i32(v); }
  void put(bool v) { w_.u8(v ? 1 : 0); }
  void put(Angle v) { w_.u32(v.bam); }
  void put(TriggerMode v) { w_.u8(static_cast<uint8_t>(v)); }
  void put(LocaliserMatcher v) { w_.u8(static_cast<uint8_t>(v)); }
  template <typename Rep, int F>
  void put(Fixed<Rep, F> v) {
    if constexpr (sizeof(Rep) == 8) {
      w_.i64(static_cast<int64_t>(v.raw()));
    } else if constexpr (sizeof(Rep) == 4) {
      w_.u32(static_cast<uint32_t>(v.raw()));
    } else {
      w_.u16(static_cast<uint16_t>(v.raw()));
    }
  }
  void put(const hal::PipelineMapping& m) { settings_detail::put(w_, m); }
  void put(const PreprocessConfig& p) { settings_detail::put(w_, p); }
  void put(const OdometryConfig& o) { settings_detail::put(w_, o); }
  void put(const MapOrigin& o) {
    w_.i32(o.x_mm);
    w_.i32(o.y_mm);
  }
  void put(const MapSize& s) {
    w_.u16(s.width);
    w_.u16(s.height);
  }

  ByteWriter& w_;
};

class Reader {
 public:
  explicit Reader(ByteReader& r) : r_(r) {}
  template <class T>
  SEQSLAM_SETTINGS_INLINE void operator()(T& field, const Setting& s) {
    if (s.since != kPcOnly) get(field);
  }
  void pad(uint32_t bytes) { r_.skip(bytes); }

 private:
  void get(uint8_t& v) { v = r_.u8(); }
  void get(uint16_t& v) { v = r_.u16(); }
  void get(uint32_t& v) { v = r_.u32(); }
  void get(int32_t& v) { v = r_.i32(); }
  void get(bool& v) { v = r_.u8() != 0; }
  void get(Angle& v) { v = Angle{r_.u32()}; }
  // Any byte is representable in the enums (uint8_t underlying); an unknown value is refused
  // by the check.
  void get(TriggerMode& v) { v = static_cast<TriggerMode>(r_.u8()); }
  void get(LocaliserMatcher& v) { v = static_cast<LocaliserMatcher>(r_.u8()); }
  template <typename Rep, int F>
  void get(Fixed<Rep, F>& v) {
    if constexpr (sizeof(Rep) == 8) {
      v = Fixed<Rep, F>::from_raw(static_cast<Rep>(r_.i64()));
    } else if constexpr (sizeof(Rep) == 4) {
      v = Fixed<Rep, F>::from_raw(static_cast<Rep>(r_.u32()));
    } else {
      v = Fixed<Rep, F>::from_raw(static_cast<Rep>(r_.u16()));
    }
  }
  void get(hal::PipelineMapping& m) { settings_detail::get(r_, &m); }
  void get(PreprocessConfig& p) { settings_detail::get(r_, &p); }
  void get(OdometryConfig& o) { settings_detail::get(r_, &o); }
  void get(MapOrigin& o) {
    o.x_mm = r_.i32();
    o.y_mm = r_.i32();
  }
  void get(MapSize& s) {
    s.width = r_.u16();
    s.height = r_.u16();
  }

  ByteReader& r_;
};

// The first setting outside its range [min, max] of raw values (composites: the mapping's
// pixels, the preprocessing method, each coordinate and side; the parts' own checks follow
// in check_run_settings). kCardOnly: the settings a card carries (the others keep values
// the program set).
template <bool kCardOnly>
class RangeCheck {
 public:
  template <class T>
  SEQSLAM_SETTINGS_INLINE void operator()(const T& field, const Setting& s) {
    if (!(kCardOnly && s.since == kPcOnly) && failed_ < 0 && !within(field, s)) {
      failed_ = position_;
    }
    ++position_;
  }
  void pad(uint32_t) {}
  int16_t failed() const { return failed_; }

 private:
  SEQSLAM_SETTINGS_INLINE static bool in(int64_t v, const Setting& s) {
    return v >= s.min && v <= s.max;
  }
  // Values of 32 bits or fewer compare in 32 bits (the head board's word): their ranges fit.
  template <typename T>
  SEQSLAM_SETTINGS_INLINE static bool narrow(T v, const Setting& s) {
    static_assert(sizeof(T) <= 4, "32-bit values only");
    if (s.min <= INT32_MIN || s.max >= INT32_MAX) return in(static_cast<int64_t>(v), s);
    if constexpr (static_cast<T>(-1) > static_cast<T>(0)) {  // unsigned
      const uint32_t u = v;
      return (s.min <= 0 || u >= static_cast<uint32_t>(s.min)) &&
             (s.max < 0 ? false : u <= static_cast<uint32_t>(s.max));
    } else {
      const int32_t i = v;
      return i >= static_cast<int32_t>(s.min) && i <= static_cast<int32_t>(s.max);
    }
  }
  template <typename T>
  SEQSLAM_SETTINGS_INLINE static bool within(const T& v, const Setting& s) {
    if constexpr (sizeof(T) <= 4) {
      return narrow(v, s);
    } else {
      return in(static_cast<int64_t>(v), s);
    }
  }
  template <typename Rep, int F>
  SEQSLAM_SETTINGS_INLINE static bool within(const Fixed<Rep, F>& v, const Setting& s) {
    if constexpr (sizeof(Rep) <= 4) {
      return narrow(v.raw(), s);
    } else {
      return in(static_cast<int64_t>(v.raw()), s);
    }
  }
  SEQSLAM_SETTINGS_INLINE static bool within(const Angle& v, const Setting& s) {
    return narrow(v.bam, s);
  }
  SEQSLAM_SETTINGS_INLINE static bool within(const TriggerMode& v, const Setting& s) {
    return narrow(static_cast<uint8_t>(v), s);
  }
  SEQSLAM_SETTINGS_INLINE static bool within(const LocaliserMatcher& v, const Setting& s) {
    return narrow(static_cast<uint8_t>(v), s);
  }
  static bool within(const bool&, const Setting&) { return true; }
  static bool within(const hal::PipelineMapping& m, const Setting& s) {
    return narrow(static_cast<uint32_t>(m.xmax) * m.ymax, s);
  }
  static bool within(const PreprocessConfig& p, const Setting& s) {
    return narrow(static_cast<uint8_t>(p.method), s);
  }
  static bool within(const OdometryConfig&, const Setting&) { return true; }
  static bool within(const MapOrigin& o, const Setting& s) {
    return narrow(o.x_mm, s) && narrow(o.y_mm, s);
  }
  static bool within(const MapSize& m, const Setting& s) {
    return narrow(m.width, s) && narrow(m.height, s);
  }

  int16_t position_ = 0;
  int16_t failed_ = -1;
};

}  // namespace settings_detail

// `config`'s card settings in table order into out[0..capacity): the bytes written, or 0 when
// they do not fit.
template <class Table, class Config>
uint32_t encode_settings(const Table& table, const Config& config, uint8_t* out,
                         uint32_t capacity) {
  ByteWriter w(out, capacity);
  settings_detail::Writer v(w);
  table(v, config);
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

// Reads the card settings of `data` into *config (the others keep their values): false when
// the data is shorter than the table.
template <class Table, class Config>
bool decode_settings(const Table& table, const uint8_t* data, uint32_t size, Config* config) {
  ByteReader r(data, size);
  Config c = *config;
  settings_detail::Reader v(r);
  table(v, c);
  if (!r.ok()) return false;
  *config = c;
  return true;
}

// The table position (from 0) of the first setting of `config` outside its range, or -1;
// kCardOnly: of the settings a card carries.
template <bool kCardOnly = false, class Table, class Config>
int16_t first_setting_out_of_range(const Table& table, const Config& config) {
  settings_detail::RangeCheck<kCardOnly> v;
  table(v, config);
  return v.failed();
}

}  // namespace seqslam::storage
