// minitest: a small GoogleTest-compatible harness for the bare-metal target.
//
// Test sources include "test.h", which selects GoogleTest on the host and this header on the
// target, so one test file builds both ways. No C or C++ standard library is needed: output
// goes to seqslam::board::console_*, there is no heap (fixtures live in static storage), no
// exceptions (ASSERT_* returns from the current function, as in gtest).
//
// Supported, with gtest semantics:
//   TEST(Suite, Name), TEST_F(Fixture, Name)      fixtures derive from ::testing::Test and
//                                                 may override SetUp()/TearDown()
//   EXPECT_/ASSERT_ TRUE FALSE EQ NE LT LE GT GE NEAR FLOAT_EQ DOUBLE_EQ STREQ STRNE
//   ADD_FAILURE() FAIL() SUCCEED() GTEST_SKIP()
//   "<< message" after any of them (strings, integers of every width, bool, char, float,
//   double, enums as integers, pointers)
//   ::testing::Test::HasFailure() / HasFatalFailure() / IsSkipped()
//   range-for over braced lists (a std::initializer_list stand-in, see below)
// Each test object is constructed in its own static buffer (.bss), so fixtures may be
// large: the stack holds only what the test itself uses, and the "[  MEMORY  ]" line at the
// end reports the stack high water over the whole run. Each test's line reports the
// instructions it retired (deterministic under QEMU -icount).
// Not supported: parameterised and typed tests, death tests, matchers (EXPECT_THAT),
// SCOPED_TRACE, SetUpTestSuite, command-line filters.
//
// On failure both operands are printed: integers in decimal, bool as true/false, floating
// point with 9 significant digits, characters as 'c' (code), C strings quoted, other
// pointers in hex, enums as their underlying integer, any other class type as "(object)".
//
// main() (minitest.cpp) runs every test in registration order (source order within a file,
// link order across files) and returns 0 only if none failed; the board turns that into
// QEMU's exit status.
#pragma once
#ifndef MINITEST_NO_SYSTEM_HEADER
// Like gtest under /usr/include: the comparison templates compare whatever the test hands
// them (int with size_t, float with double), and warnings about that belong to gtest's
// policy, not to each test. Define MINITEST_NO_SYSTEM_HEADER to lint this header itself.
#pragma GCC system_header
#endif

#include <stddef.h>
#include <stdint.h>

// gtest drags in the C++ library, so host tests may use "for (int x : {1, 2, 3})", which
// needs std::initializer_list. The target has no C++ library headers; this supplies the
// one class the compiler itself depends on (layout fixed by the ABI: pointer, length), for
// test code only.
#if __has_include(<initializer_list>)
#include <initializer_list>
#else
namespace std {  // NOLINT(cert-dcl58-cpp)
template <typename E>
class initializer_list {
 public:
  using value_type = E;
  using reference = const E&;
  using const_reference = const E&;
  using size_type = size_t;
  using iterator = const E*;
  using const_iterator = const E*;

  constexpr initializer_list() noexcept : first_(nullptr), count_(0) {}
  constexpr size_t size() const noexcept { return count_; }
  constexpr const E* begin() const noexcept { return first_; }
  constexpr const E* end() const noexcept { return first_ + count_; }

 private:
  // Called by the compiler for a braced list.
  constexpr initializer_list(const E* first, size_t count) : first_(first), count_(count) {}
  const E* first_;
  size_t count_;
};

template <typename E>
constexpr const E* begin(initializer_list<E> list) noexcept {
  return list.begin();
}
template <typename E>
constexpr const E* end(initializer_list<E> list) noexcept {
  return list.end();
}
}  // namespace std
#endif

namespace minitest {

namespace internal {
struct Placement {};
}  // namespace internal

// Base class of every test, as ::testing::Test.
//
// The destructor is virtual (as in gtest) so that fixtures with implicit destructors pass
// -Wnon-virtual-dtor. A virtual destructor normally makes GCC emit a "deleting destructor"
// that calls the global operator delete, which does not exist on the target; the
// class-specific operator delete below is found first instead, so no global new/delete is
// ever referenced. Test objects are never deleted (they live in static storage), so it
// traps if it is called at all.
class Test {
 public:
  virtual ~Test() = default;
  Test(const Test&) = delete;
  Test& operator=(const Test&) = delete;
  static void operator delete(void* object, size_t size) noexcept;

  // Whether the running test has failed (at all / fatally) or was skipped.
  static bool HasFailure();
  static bool HasFatalFailure();
  static bool IsSkipped();

  // Used by the harness: SetUp, TestBody unless SetUp failed fatally or skipped, TearDown.
  void MinitestRun_();

 protected:
  Test() = default;
  virtual void SetUp() {}
  virtual void TearDown() {}

 private:
  virtual void TestBody() = 0;
};

// Streams the user's "<< message" of a failed assertion straight to the console.
class Message {
 public:
  Message() = default;

  Message& operator<<(const char* text);
  Message& operator<<(char* text) { return *this << static_cast<const char*>(text); }
  Message& operator<<(char c);
  Message& operator<<(signed char c) { return *this << static_cast<char>(c); }
  Message& operator<<(unsigned char c) { return *this << static_cast<char>(c); }
  template <typename T>
  Message& operator<<(const T& value);

  bool printed() const { return printed_; }

 private:
  void begin();
  bool printed_ = false;
};

namespace internal {

// --- Tiny type traits (there is no <type_traits> on the target) --------------------------
template <typename T>
struct IsPointer {
  static constexpr bool value = false;
};
template <typename T>
struct IsPointer<T*> {
  static constexpr bool value = true;
};
template <typename T>
struct IsMemberPointer {
  static constexpr bool value = false;
};
template <typename T, typename C>
struct IsMemberPointer<T C::*> {
  static constexpr bool value = true;
};
template <typename T>
struct IsArray {
  static constexpr bool value = false;
};
template <typename T, size_t N>
struct IsArray<T[N]> {
  static constexpr bool value = true;
};
template <typename T>
struct ArrayElement {
  using type = void;
};
template <typename T, size_t N>
struct ArrayElement<T[N]> {
  using type = T;
};
template <typename T>
struct Pointee {
  using type = void;
};
template <typename T>
struct Pointee<T*> {
  using type = T;
};
template <typename A, typename B>
struct IsSame {
  static constexpr bool value = false;
};
template <typename A>
struct IsSame<A, A> {
  static constexpr bool value = true;
};
template <typename T>
struct RemoveCv {
  using type = T;
};
template <typename T>
struct RemoveCv<const T> {
  using type = T;
};
template <typename T>
struct RemoveCv<volatile T> {
  using type = T;
};
template <typename T>
struct RemoveCv<const volatile T> {
  using type = T;
};
template <typename T>
struct IsCharLike {
  using U = typename RemoveCv<T>::type;
  static constexpr bool value =
      IsSame<U, char>::value || IsSame<U, signed char>::value || IsSame<U, unsigned char>::value;
};

// --- Value printing (failure reports) ----------------------------------------------------
void print(bool v);
void print(char v);
void print(signed char v);
void print(unsigned char v);
void print(wchar_t v);
void print(char16_t v);
void print(char32_t v);
void print(short v);
void print(unsigned short v);
void print(int v);
void print(unsigned int v);
void print(long v);
void print(unsigned long v);
void print(long long v);
void print(unsigned long long v);
void print(float v);
void print(double v);
void print(long double v);
void print_cstring(const char* s);                 // quoted, or NULL
void print_chars(const char* s, size_t capacity);  // quoted, stops at NUL or capacity
void print_address(uintptr_t address);
void print_raw(const char* text);
void print_signed(int64_t v);
void print_unsigned(uint64_t v);

template <typename T>
void print_value(const T& value) {
  if constexpr (__is_enum(T)) {
    using Underlying = __underlying_type(T);
    if constexpr (static_cast<Underlying>(-1) < static_cast<Underlying>(0)) {
      print_signed(static_cast<int64_t>(static_cast<Underlying>(value)));
    } else {
      print_unsigned(static_cast<uint64_t>(static_cast<Underlying>(value)));
    }
  } else if constexpr (__is_class(T) || __is_union(T)) {
    print_raw("(object)");
  } else if constexpr (IsArray<T>::value) {
    if constexpr (IsCharLike<typename ArrayElement<T>::type>::value) {
      print_chars(reinterpret_cast<const char*>(&value[0]), sizeof(T));
    } else {
      print_raw("(array)");
    }
  } else if constexpr (IsPointer<T>::value) {
    if constexpr (IsCharLike<typename Pointee<T>::type>::value) {
      print_cstring(reinterpret_cast<const char*>(value));
    } else {
      print_address(reinterpret_cast<uintptr_t>(value));
    }
  } else if constexpr (IsSame<T, decltype(nullptr)>::value) {
    print_raw("(nullptr)");
  } else if constexpr (IsMemberPointer<T>::value) {
    print_raw("(member pointer)");
  } else {
    print(value);
  }
}

// --- Assertion plumbing -----------------------------------------------------------------
// Each assertion first evaluates a check, which on failure prints "file:line: Failure" and
// the details. The user's message (if any) is then streamed by the Message, and Reporter
// records the failure (and ends the line).
struct Result {
  bool ok;
  explicit operator bool() const { return ok; }
};

enum class Severity { kNonFatal, kFatal, kSkip };

class Reporter {
 public:
  explicit Reporter(Severity severity) : severity_(severity) {}
  void operator=(const Message& message) const;

 private:
  Severity severity_;
};

void begin_failure(const char* file, int line);
Result fail_here(const char* file, int line, const char* what);
Result skip_here(const char* file, int line);
Result check_bool(const char* file, int line, const char* expr, bool actual, bool expected);
Result check_near(const char* file, int line, const char* e1, const char* e2, const char* eabs,
                  double v1, double v2, double abs_error);
Result check_float_eq(const char* file, int line, const char* e1, const char* e2, float v1,
                      float v2);
Result check_double_eq(const char* file, int line, const char* e1, const char* e2, double v1,
                       double v2);
Result check_str(const char* file, int line, const char* e1, const char* e2, const char* s1,
                 const char* s2, bool expect_equal);

template <typename A, typename B>
Result check_eq(const char* file, int line, const char* ea, const char* eb, const A& a,
                const B& b) {
  if (a == b) {
    return Result{true};
  }
  begin_failure(file, line);
  print_raw("Expected equality of these values:\n  ");
  print_raw(ea);
  print_raw("\n    Which is: ");
  print_value(a);
  print_raw("\n  ");
  print_raw(eb);
  print_raw("\n    Which is: ");
  print_value(b);
  print_raw("\n");
  return Result{false};
}

void report_compare(const char* file, int line, const char* ea, const char* op, const char* eb);

#define MINITEST_DEFINE_CHECK_(fn, op)                                                            \
  template <typename A, typename B>                                                               \
  Result fn(const char* file, int line, const char* ea, const char* eb, const A& a, const B& b) { \
    if (a op b) {                                                                                 \
      return Result{true};                                                                        \
    }                                                                                             \
    report_compare(file, line, ea, #op, eb);                                                      \
    print_value(a);                                                                               \
    print_raw(" vs ");                                                                            \
    print_value(b);                                                                               \
    print_raw("\n");                                                                              \
    return Result{false};                                                                         \
  }
MINITEST_DEFINE_CHECK_(check_ne, !=)
MINITEST_DEFINE_CHECK_(check_lt, <)
MINITEST_DEFINE_CHECK_(check_le, <=)
MINITEST_DEFINE_CHECK_(check_gt, >)
MINITEST_DEFINE_CHECK_(check_ge, >=)
#undef MINITEST_DEFINE_CHECK_

// --- Registration ------------------------------------------------------------------------
class TestInfo {
 public:
  using RunFn = void (*)();
  TestInfo(const char* suite, const char* name, RunFn run_fn, const char* file, int line);

  const char* suite() const { return suite_; }
  const char* name() const { return name_; }
  const char* file() const { return file_; }
  int line() const { return line_; }
  void run() const { run_(); }
  const TestInfo* next() const { return next_; }
  bool failed() const { return failed_; }
  void mark_failed() const { failed_ = true; }

 private:
  const char* suite_;
  const char* name_;
  RunFn run_;
  const char* file_;
  int line_;
  TestInfo* next_ = nullptr;
  mutable bool failed_ = false;
};

}  // namespace internal
}  // namespace minitest

// Constructs a test object in static storage without a heap. Always inlined, so no
// "operator new" symbol (_Znw...) ever reaches an image.
__attribute__((always_inline)) inline void* operator new(size_t, ::minitest::internal::Placement,
                                                         void* where) noexcept {
  return where;
}

namespace minitest {
namespace internal {

// One instance per test, in .bss (tests are not run concurrently or re-entered).
template <typename T>
void run_test() {
  alignas(T) static unsigned char storage[sizeof(T)];
  T* test = new (Placement{}, storage) T;
  test->MinitestRun_();
  test->~T();
}

}  // namespace internal

template <typename T>
Message& Message::operator<<(const T& value) {
  begin();
  if constexpr (internal::IsSame<T, bool>::value) {
    internal::print_raw(value ? "true" : "false");
  } else if constexpr (internal::IsArray<T>::value) {
    *this << &value[0];
  } else if constexpr (internal::IsPointer<T>::value) {
    internal::print_address(reinterpret_cast<uintptr_t>(value));
  } else {
    internal::print_value(value);
  }
  return *this;
}

}  // namespace minitest

// The gtest spelling of the public names.
namespace testing {
using ::minitest::Message;
using ::minitest::Test;
}  // namespace testing

// ------------------------------------------------------------------------------------------
// Macros. The switch wrapper makes "if (x) EXPECT_TRUE(y); else ..." parse as written.
#define MINITEST_ELSE_BLOCKER_ \
  switch (0)                   \
  case 0:                      \
  default:

#define MINITEST_CHECK_(result, severity, on_failure)                   \
  MINITEST_ELSE_BLOCKER_                                                \
  if (const ::minitest::internal::Result minitest_result_ = (result)) { \
  } else /* NOLINT */                                                   \
    on_failure ::minitest::internal::Reporter(severity) = ::minitest::Message()

#define MINITEST_NONFATAL_(result) \
  MINITEST_CHECK_(result, ::minitest::internal::Severity::kNonFatal, )
#define MINITEST_FATAL_(result) \
  MINITEST_CHECK_(result, ::minitest::internal::Severity::kFatal, return )

#define MINITEST_CLASS_NAME_(suite, name) suite##_##name##_Test

#define MINITEST_TEST_(suite, name, parent)                                                        \
  class MINITEST_CLASS_NAME_(suite, name) final : public parent {                                  \
   public:                                                                                         \
    MINITEST_CLASS_NAME_(suite, name)() = default;                                                 \
                                                                                                   \
   private:                                                                                        \
    void TestBody() override;                                                                      \
    static ::minitest::internal::TestInfo minitest_info_;                                          \
  };                                                                                               \
  ::minitest::internal::TestInfo MINITEST_CLASS_NAME_(suite, name)::minitest_info_(                \
      #suite, #name, &::minitest::internal::run_test<MINITEST_CLASS_NAME_(suite, name)>, __FILE__, \
      __LINE__);                                                                                   \
  void MINITEST_CLASS_NAME_(suite, name)::TestBody()

#define TEST(suite, name) MINITEST_TEST_(suite, name, ::testing::Test)
#define TEST_F(fixture, name) MINITEST_TEST_(fixture, name, fixture)

#define ADD_FAILURE() \
  MINITEST_NONFATAL_(::minitest::internal::fail_here(__FILE__, __LINE__, "Failed"))
#define FAIL() MINITEST_FATAL_(::minitest::internal::fail_here(__FILE__, __LINE__, "Failed"))
#define GTEST_FAIL() FAIL()
#define SUCCEED()                                                               \
  MINITEST_ELSE_BLOCKER_                                                        \
  if (true) {                                                                   \
  } else /* NOLINT */                                                           \
    ::minitest::internal::Reporter(::minitest::internal::Severity::kNonFatal) = \
        ::minitest::Message()
#define GTEST_SUCCEED() SUCCEED()
#define GTEST_SKIP()                                                   \
  MINITEST_CHECK_(::minitest::internal::skip_here(__FILE__, __LINE__), \
                  ::minitest::internal::Severity::kSkip, return )

#define MINITEST_BOOL_(cond, expected, kind) \
  kind(::minitest::internal::check_bool(__FILE__, __LINE__, #cond, (cond) ? true : false, expected))
#define EXPECT_TRUE(cond) MINITEST_BOOL_(cond, true, MINITEST_NONFATAL_)
#define EXPECT_FALSE(cond) MINITEST_BOOL_(cond, false, MINITEST_NONFATAL_)
#define ASSERT_TRUE(cond) MINITEST_BOOL_(cond, true, MINITEST_FATAL_)
#define ASSERT_FALSE(cond) MINITEST_BOOL_(cond, false, MINITEST_FATAL_)

#define MINITEST_CMP_(fn, a, b, kind) \
  kind(::minitest::internal::fn(__FILE__, __LINE__, #a, #b, a, b))
#define EXPECT_EQ(a, b) MINITEST_CMP_(check_eq, a, b, MINITEST_NONFATAL_)
#define EXPECT_NE(a, b) MINITEST_CMP_(check_ne, a, b, MINITEST_NONFATAL_)
#define EXPECT_LT(a, b) MINITEST_CMP_(check_lt, a, b, MINITEST_NONFATAL_)
#define EXPECT_LE(a, b) MINITEST_CMP_(check_le, a, b, MINITEST_NONFATAL_)
#define EXPECT_GT(a, b) MINITEST_CMP_(check_gt, a, b, MINITEST_NONFATAL_)
#define EXPECT_GE(a, b) MINITEST_CMP_(check_ge, a, b, MINITEST_NONFATAL_)
#define ASSERT_EQ(a, b) MINITEST_CMP_(check_eq, a, b, MINITEST_FATAL_)
#define ASSERT_NE(a, b) MINITEST_CMP_(check_ne, a, b, MINITEST_FATAL_)
#define ASSERT_LT(a, b) MINITEST_CMP_(check_lt, a, b, MINITEST_FATAL_)
#define ASSERT_LE(a, b) MINITEST_CMP_(check_le, a, b, MINITEST_FATAL_)
#define ASSERT_GT(a, b) MINITEST_CMP_(check_gt, a, b, MINITEST_FATAL_)
#define ASSERT_GE(a, b) MINITEST_CMP_(check_ge, a, b, MINITEST_FATAL_)

#define MINITEST_NEAR_(a, b, abs_error, kind) \
  kind(::minitest::internal::check_near(__FILE__, __LINE__, #a, #b, #abs_error, a, b, abs_error))
#define EXPECT_NEAR(a, b, abs_error) MINITEST_NEAR_(a, b, abs_error, MINITEST_NONFATAL_)
#define ASSERT_NEAR(a, b, abs_error) MINITEST_NEAR_(a, b, abs_error, MINITEST_FATAL_)

#define EXPECT_FLOAT_EQ(a, b) MINITEST_CMP_(check_float_eq, a, b, MINITEST_NONFATAL_)
#define ASSERT_FLOAT_EQ(a, b) MINITEST_CMP_(check_float_eq, a, b, MINITEST_FATAL_)
#define EXPECT_DOUBLE_EQ(a, b) MINITEST_CMP_(check_double_eq, a, b, MINITEST_NONFATAL_)
#define ASSERT_DOUBLE_EQ(a, b) MINITEST_CMP_(check_double_eq, a, b, MINITEST_FATAL_)

#define MINITEST_STR_(a, b, equal, kind) \
  kind(::minitest::internal::check_str(__FILE__, __LINE__, #a, #b, a, b, equal))
#define EXPECT_STREQ(a, b) MINITEST_STR_(a, b, true, MINITEST_NONFATAL_)
#define EXPECT_STRNE(a, b) MINITEST_STR_(a, b, false, MINITEST_NONFATAL_)
#define ASSERT_STREQ(a, b) MINITEST_STR_(a, b, true, MINITEST_FATAL_)
#define ASSERT_STRNE(a, b) MINITEST_STR_(a, b, false, MINITEST_FATAL_)
