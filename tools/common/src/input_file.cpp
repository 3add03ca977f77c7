#include "seqslam_tools/input_file.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace seqslam::tools {

std::string unreachable_file(const std::string& path) {
  if (path.empty()) return "(empty path): no file name given";
  struct stat st;
  if (stat(path.c_str(), &st) == 0) return {};
  const int err = errno;
  if (err == ENOENT) {
    struct stat link;
    if (lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
      char target[PATH_MAX];
      const ssize_t n = readlink(path.c_str(), target, sizeof target - 1);
      const std::string to = n > 0 ? std::string(target, static_cast<size_t>(n)) : "?";
      return path + ": a dangling symbolic link (to " + to + ", which does not exist)";
    }
    return path + ": no such file";
  }
  if (err == ELOOP) return path + ": a symbolic link loop (" + strerror(err) + ")";
  if (err == ENOTDIR) return path + ": no such file (a part of the path is not a directory)";
  return path + ": cannot access: " + strerror(err);
}

std::string check_regular_input(const std::string& path) {
  if (std::string why = unreachable_file(path); !why.empty()) return why;
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return unreachable_file(path);
  if (S_ISREG(st.st_mode)) return {};
  if (S_ISDIR(st.st_mode)) return path + ": is a directory, not a file";
  return path + ": is not a regular file (a device, FIFO or socket), which this tool does not read";
}

bool parse_whole_field(const std::string& s, uint64_t lo, uint64_t hi, uint64_t* out) {
  if (s.empty() || s.size() > 18 || (s[0] == '0' && s.size() > 1)) return false;
  uint64_t v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<uint64_t>(c - '0');
  }
  if (v < lo || v > hi) return false;
  *out = v;
  return true;
}

bool parse_finite_field(const std::string& s, double* out) {
  if (s.empty() || s.find_first_not_of("0123456789.eE+-") != std::string::npos) return false;
  errno = 0;
  char* end = nullptr;
  const double v = strtod(s.c_str(), &end);
  if (errno != 0 || end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

std::string read_resume_file(const std::string& path, std::string* content) {
  content->clear();
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return "";
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return path + ": cannot read it to resume: " + strerror(errno);
  char buf[65536];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0)
    content->append(buf, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  return failed ? path + ": cannot read it to resume: read error" : "";
}

int control_byte_at(const std::string& s) {
  for (size_t i = 0; i < s.size(); ++i) {
    if (static_cast<unsigned char>(s[i]) < 0x20) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace seqslam::tools
