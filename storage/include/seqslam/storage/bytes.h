// Little-endian encoding into byte buffers, with bounds checks, and CRC-32.
//
// Every on-disk structure of seqslam (docs/dream_format.md) is written field by field through
// these helpers, never by copying C structs, so the format does not depend on the compiler's
// padding or the CPU's byte order.
#pragma once

#include <stddef.h>
#include <stdint.h>

namespace seqslam::storage {

// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320, init and final xor 0xFFFFFFFF; the
// zlib/PNG CRC). Nibble-table implementation: 64 bytes of table, two lookups per byte.
// crc32_update continues a running CRC: crc32(a + b) == crc32_update(crc32(a), b).
uint32_t crc32_update(uint32_t crc, const uint8_t* data, size_t size);
inline uint32_t crc32(const uint8_t* data, size_t size) {
  return crc32_update(0, data, size);
}

// Sequential writer into a fixed buffer. After an overflow every further put is ignored and
// ok() is false, so callers check once at the end.
class ByteWriter {
 public:
  ByteWriter(uint8_t* buffer, size_t size) : buffer_(buffer), size_(size) {}

  void u8(uint8_t v) { put(&v, 1); }
  void u16(uint16_t v) {
    const uint8_t b[2] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)};
    put(b, 2);
  }
  void u32(uint32_t v) {
    const uint8_t b[4] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                          static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)};
    put(b, 4);
  }
  void u64(uint64_t v) {
    u32(static_cast<uint32_t>(v));
    u32(static_cast<uint32_t>(v >> 32));
  }
  void i16(int16_t v) { u16(static_cast<uint16_t>(v)); }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  void bytes(const uint8_t* data, size_t n) { put(data, n); }
  void zeros(size_t n) {
    for (size_t i = 0; i < n; ++i)
      u8(0);
  }

  bool ok() const { return ok_; }
  size_t position() const { return pos_; }

 private:
  void put(const uint8_t* data, size_t n) {
    if (!ok_ || n > size_ - pos_) {
      ok_ = false;
      return;
    }
    for (size_t i = 0; i < n; ++i)
      buffer_[pos_ + i] = data[i];
    pos_ += n;
  }

  uint8_t* buffer_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
};

// Sequential reader from a fixed buffer. Reading past the end yields zeros and makes ok()
// false; callers check once after reading a structure.
class ByteReader {
 public:
  ByteReader(const uint8_t* buffer, size_t size) : buffer_(buffer), size_(size) {}

  uint8_t u8() {
    uint8_t b = 0;
    get(&b, 1);
    return b;
  }
  uint16_t u16() {
    uint8_t b[2] = {};
    get(b, 2);
    return static_cast<uint16_t>(b[0] | (b[1] << 8));
  }
  uint32_t u32() {
    uint8_t b[4] = {};
    get(b, 4);
    return static_cast<uint32_t>(b[0]) | (static_cast<uint32_t>(b[1]) << 8) |
           (static_cast<uint32_t>(b[2]) << 16) | (static_cast<uint32_t>(b[3]) << 24);
  }
  uint64_t u64() {
    const uint64_t lo = u32();
    return lo | (static_cast<uint64_t>(u32()) << 32);
  }
  int16_t i16() { return static_cast<int16_t>(u16()); }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  int64_t i64() { return static_cast<int64_t>(u64()); }
  // Returns a pointer to the next n bytes and skips them, or null past the end.
  const uint8_t* bytes(size_t n) {
    if (!ok_ || n > size_ - pos_) {
      ok_ = false;
      return nullptr;
    }
    const uint8_t* p = buffer_ + pos_;
    pos_ += n;
    return p;
  }
  void skip(size_t n) { (void)bytes(n); }

  bool ok() const { return ok_; }
  size_t position() const { return pos_; }
  size_t remaining() const { return ok_ ? size_ - pos_ : 0; }

 private:
  void get(uint8_t* out, size_t n) {
    if (!ok_ || n > size_ - pos_) {
      ok_ = false;
      return;
    }
    for (size_t i = 0; i < n; ++i)
      out[i] = buffer_[pos_ + i];
    pos_ += n;
  }

  const uint8_t* buffer_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace seqslam::storage
