// The error vocabulary: Result<T> and status names.
#include "seqslam/status.h"

#include "test.h"

namespace seqslam {
namespace {

Result<uint32_t> halve(uint32_t v) {
  if (v % 2 != 0) return Status::kInvalidArgument;
  return v / 2;
}

TEST(Result, CarriesAValueOrAStatus) {
  const Result<uint32_t> good = halve(8);
  EXPECT_TRUE(good.ok());
  EXPECT_EQ(good.status(), Status::kOk);
  EXPECT_EQ(good.value(), 4u);
  EXPECT_EQ(good.value_or(99u), 4u);

  const Result<uint32_t> bad = halve(7);
  EXPECT_FALSE(bad.ok());
  EXPECT_EQ(bad.status(), Status::kInvalidArgument);
  EXPECT_EQ(bad.value_or(99u), 99u);
}

#if defined(SEQSLAM_TEST_GTEST) && GTEST_HAS_DEATH_TEST
// Reading the value of an error is the caller's bug: it traps instead of handing out a
// default-constructed value (issue 15). Host only: the target harness cannot survive a trap.
TEST(ResultDeathTest, ValueOfAnErrorTraps) {
  const Result<uint32_t> bad = halve(7);
  EXPECT_DEATH((void)bad.value(), "");
}
#endif

TEST(Status, NamesAreStable) {
  EXPECT_STREQ(status_name(Status::kOk), "OK");
  EXPECT_STREQ(status_name(Status::kDataLoss), "DATA_LOSS");
  EXPECT_STREQ(status_name(Status::kInternal), "INTERNAL");
}

}  // namespace
}  // namespace seqslam
