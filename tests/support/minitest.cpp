// minitest runtime: registration list, assertion reports, value printing and main().
// See minitest.h. Output goes to the board console; the process status is main's result.
#include "minitest.h"

#include "seqslam/board/board.h"

namespace minitest {
namespace {

namespace board = ::seqslam::board;

// State of the running test.
struct State {
  bool failed;
  bool fatal;
  bool skipped;
};
State g_state = {false, false, false};

internal::TestInfo* g_first = nullptr;
internal::TestInfo* g_last = nullptr;

void out(const char* text) {
  board::console_print(text);
}

bool str_equal(const char* a, const char* b) {
  if (a == nullptr || b == nullptr) {
    return a == b;
  }
  for (; *a != '\0' && *a == *b; ++a, ++b) {
  }
  return *a == *b;
}

void print_char_escaped(char c) {
  static const char kHex[] = "0123456789abcdef";
  const unsigned char u = static_cast<unsigned char>(c);
  if (c == '"' || c == '\\') {
    const char buf[2] = {'\\', c};
    board::console_write(buf, 2);
  } else if (c == '\n') {
    out("\\n");
  } else if (u >= 0x20 && u < 0x7f) {
    board::console_write(&c, 1);
  } else {
    const char buf[4] = {'\\', 'x', kHex[u >> 4], kHex[u & 0xf]};
    board::console_write(buf, 4);
  }
}

// ---- Floating point to decimal with integer arithmetic only ------------------------------
// The value is carried as m * 2^e with m normalised (bit 63 set) and scaled by 10 or 0.1
// (64x64->128-bit products) until it lies in [1, 10); then 10 digits are extracted from a
// Q4.60 fixed-point number and rounded to 9 (halfway cases up, unlike printf's
// round-half-even). Each scaling step loses at most ~2^-63 relative, so even 10^-308
// prints correctly to 9 significant digits. No soft-float calls. Checked on the host
// against printf("%.9g") for 3.3 million doubles: identical except exact halfway cases.
constexpr int kSignificantDigits = 9;

struct U128 {
  uint64_t hi;
  uint64_t lo;
};

U128 mul_64x64(uint64_t a, uint64_t b) {
  const uint64_t a_lo = a & 0xffffffffu;
  const uint64_t a_hi = a >> 32;
  const uint64_t b_lo = b & 0xffffffffu;
  const uint64_t b_hi = b >> 32;
  const uint64_t p0 = a_lo * b_lo;
  const uint64_t p1 = a_lo * b_hi;
  const uint64_t p2 = a_hi * b_lo;
  const uint64_t p3 = a_hi * b_hi;
  const uint64_t mid = (p0 >> 32) + (p1 & 0xffffffffu) + (p2 & 0xffffffffu);
  return U128{p3 + (p1 >> 32) + (p2 >> 32) + (mid >> 32), (mid << 32) | (p0 & 0xffffffffu)};
}

// m * 2^e  <-  m * 2^e * c * 2^ce, with c normalised too.
void scale(uint64_t& m, int& e, uint64_t c, int ce) {
  const U128 p = mul_64x64(m, c);  // in [2^126, 2^128)
  if ((p.hi >> 63) != 0) {
    m = p.hi;
    e += ce + 64;
  } else {
    m = (p.hi << 1) | (p.lo >> 63);
    e += ce + 63;
  }
}

void print_decimal(bool negative, uint64_t m, int e) {
  constexpr uint64_t kTen = 0xA000000000000000u;    // 10 * 2^-60
  constexpr uint64_t kTenth = 0xCCCCCCCCCCCCCCCDu;  // 0.1 * 2^67, rounded up
  while ((m >> 63) == 0) {
    m <<= 1;
    --e;
  }
  int exp10 = 0;
  for (;;) {                 // while value >= 10
    const int top = e + 63;  // value in [2^top, 2^(top+1))
    if (top < 3 || (top == 3 && m < kTen)) {
      break;
    }
    scale(m, e, kTenth, -67);
    ++exp10;
  }
  while (e + 63 < 0) {  // while value < 1
    scale(m, e, kTen, -60);
    --exp10;
  }
  uint64_t v = m >> (3 - (e + 63));  // value * 2^60, value in [1, 10)
  constexpr uint64_t kFractionMask = (uint64_t{1} << 60) - 1;
  // 9 digits to print and 7 more to round with. The scaling above may leave a value a few
  // units of 10^-17 below an exact halfway case (0.4375f, 999999999.5), so anything within
  // 5e-7 of a unit below one half counts as half: halfway cases round up.
  constexpr int kExtraDigits = 7;
  char digits[kSignificantDigits + kExtraDigits];
  for (char& d : digits) {
    d = static_cast<char>(v >> 60);
    v = (v & kFractionMask) * 10u;
  }
  uint32_t tail = 0;
  for (int i = kSignificantDigits; i < kSignificantDigits + kExtraDigits; ++i) {
    tail = tail * 10u + static_cast<uint32_t>(digits[i]);
  }
  if (tail >= 4999995u) {
    int i = kSignificantDigits - 1;
    for (; i >= 0; --i) {
      if (++digits[i] < 10) {
        break;
      }
      digits[i] = 0;
    }
    if (i < 0) {
      digits[0] = 1;
      ++exp10;
    }
  }
  int count = kSignificantDigits;
  while (count > 1 && digits[count - 1] == 0) {
    --count;
  }

  char buf[40];
  size_t n = 0;
  if (negative) {
    buf[n++] = '-';
  }
  if (exp10 < -4 || exp10 >= kSignificantDigits) {  // like printf's %.9g
    buf[n++] = static_cast<char>('0' + digits[0]);
    if (count > 1) {
      buf[n++] = '.';
      for (int i = 1; i < count; ++i) {
        buf[n++] = static_cast<char>('0' + digits[i]);
      }
    }
    buf[n++] = 'e';
    buf[n++] = exp10 < 0 ? '-' : '+';
    const int x = exp10 < 0 ? -exp10 : exp10;
    if (x >= 100) {
      buf[n++] = static_cast<char>('0' + x / 100);
    }
    buf[n++] = static_cast<char>('0' + (x / 10) % 10);
    buf[n++] = static_cast<char>('0' + x % 10);
  } else if (exp10 >= 0) {
    for (int i = 0; i <= exp10; ++i) {
      buf[n++] = static_cast<char>('0' + (i < count ? digits[i] : 0));
    }
    if (count > exp10 + 1) {
      buf[n++] = '.';
      for (int i = exp10 + 1; i < count; ++i) {
        buf[n++] = static_cast<char>('0' + digits[i]);
      }
    }
  } else {
    buf[n++] = '0';
    buf[n++] = '.';
    for (int i = -1; i > exp10; --i) {
      buf[n++] = '0';
    }
    for (int i = 0; i < count; ++i) {
      buf[n++] = static_cast<char>('0' + digits[i]);
    }
  }
  board::console_write(buf, n);
}

// Shared by float and double: sign, biased exponent, fraction, format parameters.
void print_ieee(bool negative, uint32_t biased_exp, uint64_t fraction, int fraction_bits,
                uint32_t max_exp, int bias) {
  if (biased_exp == max_exp) {
    out(fraction != 0 ? "nan" : (negative ? "-inf" : "inf"));
    return;
  }
  if (biased_exp == 0 && fraction == 0) {
    out(negative ? "-0" : "0");
    return;
  }
  uint64_t m = fraction;
  int e = 1 - bias - fraction_bits;  // subnormal
  if (biased_exp != 0) {
    m |= uint64_t{1} << fraction_bits;
    e = static_cast<int>(biased_exp) - bias - fraction_bits;
  }
  print_decimal(negative, m, e);
}

uint64_t double_bits(double v) {
  uint64_t bits;
  __builtin_memcpy(&bits, &v, sizeof bits);
  return bits;
}

uint32_t float_bits(float v) {
  uint32_t bits;
  __builtin_memcpy(&bits, &v, sizeof bits);
  return bits;
}

// gtest's AlmostEquals: within 4 units in the last place, NaN never equal. Maps the
// sign-magnitude representation onto a monotonic unsigned scale.
uint64_t biased(uint64_t bits, uint64_t sign_mask) {
  return (bits & sign_mask) != 0 ? ~bits + 1 : bits | sign_mask;
}

bool within_4_ulps(uint64_t a, uint64_t b, uint64_t sign_mask) {
  const uint64_t x = biased(a, sign_mask);
  const uint64_t y = biased(b, sign_mask);
  return (x >= y ? x - y : y - x) <= 4;
}

bool double_is_nan(uint64_t bits) {
  return ((bits >> 52) & 0x7ffu) == 0x7ffu && (bits & ((uint64_t{1} << 52) - 1)) != 0;
}

bool float_is_nan(uint32_t bits) {
  return ((bits >> 23) & 0xffu) == 0xffu && (bits & ((uint32_t{1} << 23) - 1)) != 0;
}

void print_count(int n, const char* what) {
  board::console_print_i64(n);
  out(" ");
  out(what);
  if (n != 1) {
    out("s");
  }
}

void print_test_name(const internal::TestInfo& t) {
  out(t.suite());
  out(".");
  out(t.name());
}

}  // namespace

// ---- Test ----------------------------------------------------------------------------------
void Test::operator delete(void*, size_t) noexcept {
  __builtin_trap();
}

bool Test::HasFailure() {
  return g_state.failed;
}
bool Test::HasFatalFailure() {
  return g_state.fatal;
}
bool Test::IsSkipped() {
  return g_state.skipped;
}

void Test::MinitestRun_() {
  SetUp();
  if (!HasFatalFailure() && !IsSkipped()) {
    TestBody();
  }
  TearDown();
}

// ---- Message -------------------------------------------------------------------------------
void Message::begin() {
  printed_ = true;
}

Message& Message::operator<<(const char* text) {
  begin();
  out(text == nullptr ? "(null)" : text);
  return *this;
}

Message& Message::operator<<(char c) {
  begin();
  board::console_write(&c, 1);
  return *this;
}

namespace internal {

// ---- Printing ------------------------------------------------------------------------------
void print_raw(const char* text) {
  out(text);
}
void print_signed(int64_t v) {
  board::console_print_i64(v);
}
void print_unsigned(uint64_t v) {
  board::console_print_u64(v);
}

void print(bool v) {
  out(v ? "true" : "false");
}

void print(char v) {
  const unsigned char u = static_cast<unsigned char>(v);
  if (u >= 0x20 && u < 0x7f) {
    const char buf[3] = {'\'', v, '\''};
    board::console_write(buf, 3);
    out(" (");
    print_signed(v);
    out(")");
  } else {
    print_signed(v);
  }
}
void print(signed char v) {
  print(static_cast<char>(v));
}
void print(unsigned char v) {
  print(static_cast<char>(v));
}
void print(wchar_t v) {
  print_signed(v);
}
void print(char16_t v) {
  print_unsigned(v);
}
void print(char32_t v) {
  print_unsigned(v);
}
void print(short v) {
  print_signed(v);
}
void print(unsigned short v) {
  print_unsigned(v);
}
void print(int v) {
  print_signed(v);
}
void print(unsigned int v) {
  print_unsigned(v);
}
void print(long v) {
  print_signed(v);
}
void print(unsigned long v) {
  print_unsigned(v);
}
void print(long long v) {
  print_signed(v);
}
void print(unsigned long long v) {
  print_unsigned(v);
}

void print(double v) {
  const uint64_t bits = double_bits(v);
  print_ieee((bits >> 63) != 0, static_cast<uint32_t>((bits >> 52) & 0x7ffu),
             bits & ((uint64_t{1} << 52) - 1), 52, 0x7ffu, 1023);
}

void print(float v) {
  const uint32_t bits = float_bits(v);
  print_ieee((bits >> 31) != 0, (bits >> 23) & 0xffu, bits & ((uint32_t{1} << 23) - 1), 23, 0xffu,
             127);
}

// Rare in tests; the conversion pulls in libgcc's quad-precision helper only if used.
void print(long double v) {
  print(static_cast<double>(v));
}

void print_cstring(const char* s) {
  if (s == nullptr) {
    out("NULL");
    return;
  }
  out("\"");
  for (; *s != '\0'; ++s) {
    print_char_escaped(*s);
  }
  out("\"");
}

void print_chars(const char* s, size_t capacity) {
  out("\"");
  for (size_t i = 0; i < capacity && s[i] != '\0'; ++i) {
    print_char_escaped(s[i]);
  }
  out("\"");
}

void print_address(uintptr_t address) {
  if (address == 0) {
    out("NULL");
  } else {
    board::console_print_hex32(static_cast<uint32_t>(address));
  }
}

// ---- Assertions ----------------------------------------------------------------------------
void Reporter::operator=(const Message& message) const {
  if (message.printed()) {
    out("\n");
  }
  if (severity_ == Severity::kSkip) {
    g_state.skipped = true;
    return;
  }
  g_state.failed = true;
  if (severity_ == Severity::kFatal) {
    g_state.fatal = true;
  }
}

void begin_failure(const char* file, int line) {
  out(file);
  out(":");
  print_signed(line);
  out(": Failure\n");
}

Result fail_here(const char* file, int line, const char* what) {
  begin_failure(file, line);
  out(what);
  out("\n");
  return Result{false};
}

Result skip_here(const char* file, int line) {
  out(file);
  out(":");
  print_signed(line);
  out(": Skipped\n");
  return Result{false};
}

Result check_bool(const char* file, int line, const char* expr, bool actual, bool expected) {
  if (actual == expected) {
    return Result{true};
  }
  begin_failure(file, line);
  out("Value of: ");
  out(expr);
  out("\n  Actual: ");
  print(actual);
  out("\nExpected: ");
  print(expected);
  out("\n");
  return Result{false};
}

void report_compare(const char* file, int line, const char* ea, const char* op, const char* eb) {
  begin_failure(file, line);
  out("Expected: (");
  out(ea);
  out(") ");
  out(op);
  out(" (");
  out(eb);
  out("), actual: ");
}

Result check_near(const char* file, int line, const char* e1, const char* e2, const char* eabs,
                  double v1, double v2, double abs_error) {
  if (v1 == v2) {  // also equal infinities
    return Result{true};
  }
  const double diff = v1 > v2 ? v1 - v2 : v2 - v1;
  if (diff <= abs_error) {  // false for NaN
    return Result{true};
  }
  begin_failure(file, line);
  out("The difference between ");
  out(e1);
  out(" and ");
  out(e2);
  out(" is ");
  print(diff);
  out(", which exceeds ");
  out(eabs);
  out(", where\n");
  out(e1);
  out(" evaluates to ");
  print(v1);
  out(",\n");
  out(e2);
  out(" evaluates to ");
  print(v2);
  out(", and\n");
  out(eabs);
  out(" evaluates to ");
  print(abs_error);
  out(".\n");
  return Result{false};
}

Result check_float_eq(const char* file, int line, const char* e1, const char* e2, float v1,
                      float v2) {
  const uint32_t a = float_bits(v1);
  const uint32_t b = float_bits(v2);
  if (!float_is_nan(a) && !float_is_nan(b) && within_4_ulps(a, b, 0x80000000u)) {
    return Result{true};
  }
  // Not within 4 ULPs, so this reports the two values.
  static_cast<void>(check_eq(file, line, e1, e2, v1, v2));
  return Result{false};
}

Result check_double_eq(const char* file, int line, const char* e1, const char* e2, double v1,
                       double v2) {
  const uint64_t a = double_bits(v1);
  const uint64_t b = double_bits(v2);
  if (!double_is_nan(a) && !double_is_nan(b) && within_4_ulps(a, b, uint64_t{1} << 63)) {
    return Result{true};
  }
  // Not within 4 ULPs, so this reports the two values.
  static_cast<void>(check_eq(file, line, e1, e2, v1, v2));
  return Result{false};
}

Result check_str(const char* file, int line, const char* e1, const char* e2, const char* s1,
                 const char* s2, bool expect_equal) {
  if (str_equal(s1, s2) == expect_equal) {
    return Result{true};
  }
  begin_failure(file, line);
  if (expect_equal) {
    out("Expected equality of these values:\n  ");
    out(e1);
    out("\n    Which is: ");
    print_cstring(s1);
    out("\n  ");
    out(e2);
    out("\n    Which is: ");
    print_cstring(s2);
    out("\n");
  } else {
    out("Expected: (");
    out(e1);
    out(") != (");
    out(e2);
    out("), actual: ");
    print_cstring(s1);
    out(" vs ");
    print_cstring(s2);
    out("\n");
  }
  return Result{false};
}

// ---- Registration --------------------------------------------------------------------------
TestInfo::TestInfo(const char* suite, const char* name, RunFn run_fn, const char* file, int line)
    : suite_(suite), name_(name), run_(run_fn), file_(file), line_(line) {
  if (g_last == nullptr) {
    g_first = this;
  } else {
    g_last->next_ = this;
  }
  g_last = this;
}

}  // namespace internal
}  // namespace minitest

// ---- main ----------------------------------------------------------------------------------
int main() {
  using minitest::internal::TestInfo;
  namespace board = ::seqslam::board;
  using minitest::out;

  int tests = 0;
  int suites = 0;
  for (const TestInfo* t = minitest::g_first; t != nullptr; t = t->next()) {
    ++tests;
    bool new_suite = true;
    for (const TestInfo* u = minitest::g_first; u != t; u = u->next()) {
      if (minitest::str_equal(u->suite(), t->suite())) {
        new_suite = false;
        break;
      }
    }
    suites += new_suite ? 1 : 0;
  }

  out("[==========] Running ");
  minitest::print_count(tests, "test");
  out(" from ");
  minitest::print_count(suites, "test suite");
  out(".\n");

  int passed = 0;
  int failed = 0;
  int skipped = 0;
  const uint64_t start_all = board::instructions_retired();
  const TestInfo* previous = nullptr;
  for (const TestInfo* t = minitest::g_first; t != nullptr; t = t->next()) {
    if (previous == nullptr || !minitest::str_equal(t->suite(), previous->suite())) {
      int run = 0;  // consecutive tests of this suite
      for (const TestInfo* u = t; u != nullptr && minitest::str_equal(u->suite(), t->suite());
           u = u->next()) {
        ++run;
      }
      out("[----------] ");
      minitest::print_count(run, "test");
      out(" from ");
      out(t->suite());
      out("\n");
    }
    previous = t;
    out("[ RUN      ] ");
    minitest::print_test_name(*t);
    out("\n");
    minitest::g_state = minitest::State{false, false, false};
    const uint64_t start = board::instructions_retired();
    t->run();
    const uint64_t used = board::instructions_retired() - start;
    if (minitest::g_state.failed) {
      ++failed;
      t->mark_failed();
      out("[  FAILED  ] ");
    } else if (minitest::g_state.skipped) {
      ++skipped;
      out("[  SKIPPED ] ");
    } else {
      ++passed;
      out("[       OK ] ");
    }
    minitest::print_test_name(*t);
    out(" (");
    board::console_print_u64(used);
    out(" instructions)\n");
  }
  const uint64_t used_all = board::instructions_retired() - start_all;

  out("[==========] ");
  minitest::print_count(tests, "test");
  out(" from ");
  minitest::print_count(suites, "test suite");
  out(" ran. (");
  board::console_print_u64(used_all);
  out(" instructions total)\n");
  out("[  PASSED  ] ");
  minitest::print_count(passed, "test");
  out(".\n");
  if (skipped > 0) {
    out("[  SKIPPED ] ");
    minitest::print_count(skipped, "test");
    out(".\n");
  }
  if (failed > 0) {
    out("[  FAILED  ] ");
    minitest::print_count(failed, "test");
    out(", listed below:\n");
    for (const TestInfo* t = minitest::g_first; t != nullptr; t = t->next()) {
      if (t->failed()) {
        out("[  FAILED  ] ");
        minitest::print_test_name(*t);
        out(" (");
        out(t->file());
        out(":");
        board::console_print_i64(t->line());
        out(")\n");
      }
    }
    out("\n ");
    board::console_print_i64(failed);
    out(failed == 1 ? " FAILED TEST\n" : " FAILED TESTS\n");
  }
  out("[  MEMORY  ] stack high water ");
  board::console_print_u64(board::stack_high_water_bytes());
  out(" of ");
  board::console_print_u64(board::stack_size_bytes());
  out(" bytes\n");
  return failed == 0 ? 0 : 1;
}
