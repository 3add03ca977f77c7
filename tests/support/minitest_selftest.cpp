// Self-test of the test harness.
//
// Tests are independent of each other (on the host ctest runs each in its own process);
// run order and TearDown are checked through the failure report instead.
//
// Built twice:
//   minitest_selftest_passes   everything here passes; also built on the host against
//                              GoogleTest, which keeps the two harnesses in agreement
//   minitest_reports_failure   (target only) MINITEST_SELFTEST_FAILURES adds tests that must
//                              fail; ctest checks the exit status and the report text
#include "test.h"

#include <stdint.h>

namespace {

enum class Colour : uint8_t { kRed = 1, kGreen = 2 };
enum Plain { kPlainA = -3, kPlainB = 7 };

struct Opaque {
  int x;
  bool operator==(const Opaque& other) const { return x == other.x; }
  bool operator!=(const Opaque& other) const { return x != other.x; }
};

int g_side_effects = 0;

int side_effect() {
  ++g_side_effects;
  return g_side_effects;
}

TEST(MinitestAssertions, Booleans) {
  EXPECT_TRUE(true);
  EXPECT_FALSE(false);
  ASSERT_TRUE(1 + 1 == 2);
  ASSERT_FALSE(1 + 1 == 3);
  const int* null_pointer = nullptr;
  EXPECT_FALSE(null_pointer);  // contextual conversion, as gtest
}

TEST(MinitestAssertions, Integers) {
  const int8_t i8 = -5;
  const uint8_t u8 = 250;
  const int16_t i16 = -30000;
  const uint16_t u16 = 60000;
  const int32_t i32 = -2000000000;
  const uint32_t u32 = 4000000000u;
  const int64_t i64 = INT64_MIN;
  const uint64_t u64 = UINT64_MAX;
  const size_t size = 3;
  EXPECT_EQ(i8, -5);
  EXPECT_EQ(u8, 250);
  EXPECT_EQ(i16, -30000);
  EXPECT_EQ(u16, 60000);
  EXPECT_EQ(i32, -2000000000);
  EXPECT_EQ(u32, 4000000000u);
  EXPECT_EQ(i64, INT64_MIN);
  EXPECT_EQ(u64, UINT64_MAX);
  EXPECT_EQ(size, 3u);
  EXPECT_NE(i32, 0);
  EXPECT_LT(i64, 0);
  EXPECT_LE(u8, 250);
  EXPECT_GT(u64, 0u);
  EXPECT_GE(i16, -30000);
  ASSERT_EQ(7, 7);
  ASSERT_NE(7, 8);
  ASSERT_LT(7, 8);
  ASSERT_LE(8, 8);
  ASSERT_GT(9, 8);
  ASSERT_GE(9, 9);
}

TEST(MinitestAssertions, OtherScalars) {
  EXPECT_EQ('a', 'a');
  EXPECT_EQ(true, !false);
  EXPECT_EQ(Colour::kGreen, Colour::kGreen);
  EXPECT_NE(Colour::kGreen, Colour::kRed);
  EXPECT_EQ(kPlainA, -3);
  const int value = 3;
  const int* p = &value;
  EXPECT_EQ(p, &value);
  EXPECT_NE(p, nullptr);
  const char* text = "seqslam";
  EXPECT_STREQ(text, "seqslam");
  EXPECT_STRNE(text, "SeqSLAM");
  EXPECT_EQ(Opaque{4}, Opaque{4});
}

TEST(MinitestAssertions, FloatingPoint) {
  const double third = 1.0 / 3.0;
  EXPECT_NEAR(third, 0.3333, 1e-4);
  ASSERT_NEAR(-2.5, -2.5000001, 1e-6);
  EXPECT_DOUBLE_EQ(0.1 + 0.2, 0.3);  // differ by one ULP
  EXPECT_FLOAT_EQ(0.1f + 0.2f, 0.3f);
  EXPECT_LT(0.25, 0.5);
  EXPECT_EQ(1.5f, 1.5f);
}

TEST(MinitestAssertions, BracedListsWork) {  // std::initializer_list, as on the host
  int sum = 0;
  for (const int x : {1, 2, 3, 40}) {
    sum += x;
  }
  EXPECT_EQ(sum, 46);
}

TEST(MinitestMessages, NotEvaluatedOnSuccess) {
  EXPECT_TRUE(true) << "side effect " << side_effect();
  EXPECT_EQ(1, 1) << side_effect() << ' ' << 2.5 << ' ' << true << ' ' << kPlainA;
  ASSERT_NEAR(1.0, 1.0, 0.0) << "x=" << int64_t{-1} << uint64_t{1} << 1.5f << kPlainB;
  SUCCEED() << "a message that is never printed";
  EXPECT_EQ(g_side_effects, 0);
  EXPECT_FALSE(::testing::Test::HasFailure());
}

TEST(MinitestSkip, SkipStopsTheTest) {
  GTEST_SKIP() << "skipping on purpose";
  ADD_FAILURE() << "not reached after GTEST_SKIP";
}

class MinitestFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    EXPECT_EQ(value_, 0);  // a fresh object for every test
    value_ = 42;
    ++set_ups_;
  }
  void TearDown() override { value_ = -1; }

  int value_ = 0;
  int set_ups_ = 0;
  int32_t big_[256] = {};  // fixtures may be larger than a stack frame would like
};

TEST_F(MinitestFixture, SetUpRanBeforeTheBody) {
  EXPECT_EQ(value_, 42);
  EXPECT_EQ(set_ups_, 1);
  EXPECT_EQ(big_[255], 0);
  value_ = 7;
}

TEST_F(MinitestFixture, EachTestGetsAFreshFixture) {
  // SetUp checked value_ == 0: not the object the previous test left at 7.
  EXPECT_EQ(value_, 42);
  EXPECT_EQ(set_ups_, 1);
}

}  // namespace

#if defined(MINITEST_SELFTEST_FAILURES)
// Each of these must fail; ctest matches the report against regular expressions (see
// tests/support/CMakeLists.txt), so change both together.
namespace {

int g_after_fatal = 0;

void fatal_helper() {
  ASSERT_EQ(1, 2) << "fatal in helper";
  ++g_after_fatal;  // not reached
}

TEST(MinitestFailures, ExpectContinues) {
  EXPECT_EQ(2 + 2, 5) << "message " << 42 << ' ' << -7 << ' ' << true << ' ' << 2.5;
  EXPECT_TRUE(false);
  ADD_FAILURE() << "third failure still reached";
}

TEST(MinitestFailures, AssertReturns) {
  fatal_helper();
  EXPECT_EQ(g_after_fatal, 0);
  ASSERT_TRUE(false) << "stop here";
  ADD_FAILURE() << "NOT REACHED after ASSERT";
}

TEST(MinitestFailures, PrintsValues) {
  const uint64_t big = UINT64_MAX;
  const int64_t small = INT64_MIN;
  EXPECT_EQ(big, 0u);
  EXPECT_EQ(small, 0);
  EXPECT_EQ('a', 'b');
  EXPECT_EQ(Colour::kGreen, Colour::kRed);
  EXPECT_EQ(Opaque{1}, Opaque{2});
  const char* s = "abc";
  EXPECT_STREQ(s, "abd");
  const int value = 0;
  const int* p = &value;
  EXPECT_EQ(p, nullptr);
  EXPECT_LT(3, 2);
}

TEST(MinitestFailures, PrintsDoubles) {
  EXPECT_EQ(1.0 / 3.0, 0.25);
  EXPECT_EQ(123456789.0, 1234567890.0);
  EXPECT_EQ(-2.5e-7, 1e300);
  EXPECT_EQ(0.1f, 5e-324);
  EXPECT_NEAR(1.0, 1.5, 0.125);
  EXPECT_DOUBLE_EQ(1.0, 1.0000001);
}

TEST(MinitestFailures, FailIsFatal) {
  FAIL() << "explicit FAIL";
  ADD_FAILURE() << "NOT REACHED after FAIL";
}

class FailingSetUp : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(false) << "SetUp fails"; }
  void TearDown() override { ADD_FAILURE() << "TearDown still runs"; }
};

TEST_F(FailingSetUp, BodyIsSkipped) {
  ADD_FAILURE() << "NOT REACHED: body after fatal SetUp";
}

TEST(MinitestFailures, PassingTestAmongFailures) {
  EXPECT_TRUE(true);
}

}  // namespace
#endif
