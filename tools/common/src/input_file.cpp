#include "seqslam_tools/input_file.h"

#include <errno.h>
#include <limits.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

}  // namespace seqslam::tools
