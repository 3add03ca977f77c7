// The board runtime's 64-bit division (hal/board/qemu_virt/runtime.cpp, __udivdi3) against
// its defining property: q = n / d is the one value with q * d + r == n and r < d (checked
// with multiplication and subtraction only, which do not go through the routine). On the
// host the same test checks the compiler's division, so both harnesses agree on the cases.
#include <stdint.h>

#include "test.h"

namespace {

// Keeps the compiler from folding the division at compile time.
uint64_t divide(uint64_t n, uint64_t d) {
  volatile uint64_t vn = n;
  volatile uint64_t vd = d;
  return vn / vd;
}

// q * d + r == n with r < d, without overflow: q * d <= n.
bool is_quotient(uint64_t n, uint64_t d, uint64_t q) {
  const uint64_t hi_limit = q == 0 ? 0 : UINT64_MAX / q;
  if (q != 0 && d > hi_limit) return false;  // q * d overflows: q too large
  const uint64_t product = q * d;
  if (product > n) return false;
  return n - product < d;
}

uint64_t next_random(uint64_t* state) {  // xorshift64
  uint64_t x = *state;
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  *state = x;
  return x;
}

TEST(BoardRuntime, DivisionEdgeCases) {
  const uint64_t values[] = {1u,
                             2u,
                             3u,
                             0xFFFFu,
                             0x10000u,
                             0x10001u,
                             0xFFFFFFFFu,
                             0x100000000u,
                             0x100000001u,
                             0x123456789ABCDEFu,
                             UINT64_MAX - 1,
                             UINT64_MAX};
  for (const uint64_t n : values) {
    for (const uint64_t d : values) {
      const uint64_t q = divide(n, d);
      EXPECT_TRUE(is_quotient(n, d, q)) << "n " << n << " d " << d << " q " << q;
    }
    EXPECT_EQ(divide(0, n), 0u);
    EXPECT_EQ(divide(n, 1), n);
    EXPECT_EQ(divide(n, n), 1u);
  }
}

// Operands of every magnitude: n and d each masked to a random bit length.
TEST(BoardRuntime, DivisionOfRandomOperands) {
  uint64_t state = 0x9E3779B97F4A7C15u;
  uint32_t wrong = 0;
  for (uint32_t i = 0; i < 4000; ++i) {
    const uint32_t n_bits = static_cast<uint32_t>(next_random(&state) % 64u) + 1u;
    const uint32_t d_bits = static_cast<uint32_t>(next_random(&state) % 64u) + 1u;
    const uint64_t n = next_random(&state) >> (64u - n_bits);
    uint64_t d = next_random(&state) >> (64u - d_bits);
    if (d == 0) d = 1;
    if (!is_quotient(n, d, divide(n, d))) ++wrong;
  }
  EXPECT_EQ(wrong, 0u);
}

}  // namespace
