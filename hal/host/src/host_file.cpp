#include "seqslam/hal/host_file.h"

#include <errno.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cstring>

namespace seqslam::hal {

std::string lock_for_writing(int fd, const std::string& path) {
  struct stat st;
  if (fstat(fd, &st) != 0 || !(S_ISREG(st.st_mode) || S_ISBLK(st.st_mode))) return {};
  if (flock(fd, LOCK_EX | LOCK_NB) == 0) return {};
  if (errno != EWOULDBLOCK) return {};  // no locks on this file system: nothing to guard with
  return path +
         ": in use by another process (it holds the file's lock: another seqslam, "
         "seqslam-sim or seqslam-firmware writing it); nothing was written: try again when it "
         "has finished";
}

void ignore_file_size_signal() {
  struct sigaction old = {};
  if (sigaction(SIGXFSZ, nullptr, &old) != 0) return;
  if (old.sa_handler != SIG_DFL || (old.sa_flags & SA_SIGINFO) != 0) return;
  struct sigaction ignore = {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGXFSZ, &ignore, nullptr);
}

uint64_t file_size_limit() {
  struct rlimit limit = {};
  if (getrlimit(RLIMIT_FSIZE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return UINT64_MAX;
  return uint64_t{limit.rlim_cur};
}

std::string check_file_size_limit(const std::string& path, uint64_t end) {
  const uint64_t limit = file_size_limit();
  if (end <= limit) return {};
  return path + ": the file size limit (ulimit -f) is " + std::to_string(limit) +
         " bytes, and writing it needs " + std::to_string(end) + ": " + std::strerror(EFBIG);
}

}  // namespace seqslam::hal
