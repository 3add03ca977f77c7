// The few symbols GCC may call even in freestanding code (struct copies, array
// initialisation, pure virtual calls). Nothing else: there is deliberately no operator
// new/delete and no malloc, so any heap use fails to link.
//
// Built with -ffreestanding (no builtins) and -fno-tree-loop-distribute-patterns, so GCC
// does not recognise these loops as memset/memcpy and call them recursively; the board's
// CMakeLists.txt repeats both flags for this file.
#include <stddef.h>
#include <stdint.h>

extern "C" {
void* memcpy(void* dst, const void* src, size_t n);
void* memmove(void* dst, const void* src, size_t n);
void* memset(void* dst, int value, size_t n);
int memcmp(const void* a, const void* b, size_t n);
void __cxa_pure_virtual();
uint64_t __udivdi3(uint64_t n, uint64_t d);
}

namespace {

// Whole-word accesses when both pointers are word aligned; RV32 has no fast unaligned
// access. may_alias: these words overlay objects of any type.
using Word = uint32_t __attribute__((may_alias));
constexpr size_t kWord = sizeof(Word);

bool word_aligned(const void* p) {
  return (reinterpret_cast<uintptr_t>(p) & (kWord - 1)) == 0;
}

Word* as_words(void* p) {
  return reinterpret_cast<Word*>(reinterpret_cast<uintptr_t>(p));
}
const Word* as_words(const void* p) {
  return reinterpret_cast<const Word*>(reinterpret_cast<uintptr_t>(p));
}

}  // namespace

extern "C" {

void* memcpy(void* dst, const void* src, size_t n) {
  unsigned char* d = static_cast<unsigned char*>(dst);
  const unsigned char* s = static_cast<const unsigned char*>(src);
  if (word_aligned(d) && word_aligned(s)) {
    Word* dw = as_words(d);
    const Word* sw = as_words(s);
    for (; n >= kWord; n -= kWord) {
      *dw++ = *sw++;
    }
    d = reinterpret_cast<unsigned char*>(dw);
    s = reinterpret_cast<const unsigned char*>(sw);
  }
  for (; n != 0; --n) {
    *d++ = *s++;
  }
  return dst;
}

void* memmove(void* dst, const void* src, size_t n) {
  unsigned char* d = static_cast<unsigned char*>(dst);
  const unsigned char* s = static_cast<const unsigned char*>(src);
  // Compare as integers: relational comparison of unrelated pointers is unspecified.
  const uintptr_t di = reinterpret_cast<uintptr_t>(d);
  const uintptr_t si = reinterpret_cast<uintptr_t>(s);
  if (di <= si || di - si >= n) {
    return memcpy(dst, src, n);  // forward copy is safe
  }
  // dst overlaps the tail of src: copy backwards.
  d += n;
  s += n;
  if (word_aligned(d) && word_aligned(s)) {
    for (; n >= kWord; n -= kWord) {
      d -= kWord;
      s -= kWord;
      *as_words(d) = *as_words(s);
    }
  }
  for (; n != 0; --n) {
    *--d = *--s;
  }
  return dst;
}

void* memset(void* dst, int value, size_t n) {
  unsigned char* d = static_cast<unsigned char*>(dst);
  const unsigned char byte = static_cast<unsigned char>(value);
  for (; n != 0 && !word_aligned(d); --n) {
    *d++ = byte;
  }
  if (n >= kWord) {
    const Word pattern = 0x01010101u * byte;
    Word* dw = as_words(d);
    for (; n >= kWord; n -= kWord) {
      *dw++ = pattern;
    }
    d = reinterpret_cast<unsigned char*>(dw);
  }
  for (; n != 0; --n) {
    *d++ = byte;
  }
  return dst;
}

int memcmp(const void* a, const void* b, size_t n) {
  const unsigned char* x = static_cast<const unsigned char*>(a);
  const unsigned char* y = static_cast<const unsigned char*>(b);
  for (; n != 0; --n, ++x, ++y) {
    if (*x != *y) {
      return *x < *y ? -1 : 1;
    }
  }
  return 0;
}

// Unsigned 64-bit division, which RV32IM lacks. Replaces libgcc's member (1 072 bytes of code
// plus its 256-byte __clz_tab) with about a tenth of that: the board divides 64-bit values
// in a few places a step (sequence costs, odometry set-up, patch normalisation), never in a
// per-pixel loop, so three short paths suffice: both halves fit 32 bits (one divu); a
// divisor below 2^16 (four divu steps on 16-bit digits, each remainder below the divisor);
// anything else by shift and subtract from the aligned divisor (at most 48 steps then).
// Division by zero traps, as the core never divides by zero (its callers check).
// tests/support/board_runtime_test.cpp checks q * d + r == n, r < d over edge cases and
// pseudo-random operands of every magnitude.
uint64_t __udivdi3(uint64_t n, uint64_t d) {
  if (d == 0) __builtin_trap();
  const uint32_t nh = static_cast<uint32_t>(n >> 32);
  if (nh == 0 && (d >> 32) == 0) return static_cast<uint32_t>(n) / static_cast<uint32_t>(d);
  if (d < 0x10000u) {
    const uint32_t d32 = static_cast<uint32_t>(d);
    uint64_t q = 0;
    uint32_t r = 0;
    for (int shift = 48; shift >= 0; shift -= 16) {
      const uint32_t cur = (r << 16) | static_cast<uint32_t>((n >> shift) & 0xFFFFu);
      q = (q << 16) | (cur / d32);
      r = cur % d32;
    }
    return q;
  }
  if (d > n) return 0;
  uint64_t bit = 1;
  while ((d & (uint64_t{1} << 63)) == 0 && (d << 1) <= n) {
    d <<= 1;
    bit <<= 1;
  }
  uint64_t q = 0;
  for (; bit != 0; bit >>= 1, d >>= 1) {
    if (n >= d) {
      n -= d;
      q |= bit;
    }
  }
  return q;
}

// Called through a vtable slot of an abstract class, i.e. never by correct code.
void __cxa_pure_virtual() {
  __builtin_trap();
}

}  // extern "C"
