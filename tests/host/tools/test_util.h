// Helpers shared by the seqslam_tools_common tests.
#pragma once

#include <stdint.h>

#include <string>
#include <vector>

namespace seqslam::tools::test {

// The checked-in test data (tests/data), passed by CMake.
std::string data_dir();
std::string corridor_dir();

// A fresh directory under the system temp dir, removed (recursively) on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  // path() + "/" + name
  std::string file(const std::string& name) const;

 private:
  std::string path_;
};

void write_file(const std::string& path, const std::string& bytes);
void write_file(const std::string& path, const std::vector<uint8_t>& bytes);
std::vector<uint8_t> read_file(const std::string& path);
std::string to_string(const std::vector<uint8_t>& bytes);

}  // namespace seqslam::tools::test
