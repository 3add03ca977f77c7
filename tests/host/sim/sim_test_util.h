// Helpers shared by the simulator tests: scratch directories and file contents.
#pragma once

#include <string>
#include <vector>

namespace seqslam::sim::test {

// A fresh, empty directory for one test (under ::testing::TempDir(), named after the running
// test and the process), removed again when the object goes out of scope.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag = "");
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// The whole file, or an empty vector (and ok = false) if it cannot be read.
std::vector<char> read_bytes(const std::string& path, bool* ok = nullptr);

}  // namespace seqslam::sim::test
