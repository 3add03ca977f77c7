#include "sim_test_util.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

namespace seqslam::sim::test {

ScratchDir::ScratchDir(const std::string& tag) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "seqslam_sim_";
  if (info != nullptr) name += std::string(info->test_suite_name()) + "_" + info->name();
  if (!tag.empty()) name += "_" + tag;
  name += "_" + std::to_string(static_cast<long>(::getpid()));
  path_ = (std::filesystem::path(::testing::TempDir()) / name).string();
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  std::filesystem::create_directories(path_, ec);
  EXPECT_FALSE(ec) << path_ << ": " << ec.message();
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::vector<char> read_bytes(const std::string& path, bool* ok) {
  std::ifstream in(path, std::ios::binary);
  if (ok != nullptr) *ok = static_cast<bool>(in);
  if (!in) return {};
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace seqslam::sim::test
