#include "seqslam_tools/output_file.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <mutex>

#include "seqslam/hal/host_file.h"
#include "seqslam_tools/dataset.h"

namespace seqslam::tools {

namespace {

// error_ value for a write that failed earlier without telling why (stdio's error flag set
// by a write that is not ours, e.g. a printf to standard output).
constexpr int kLostOutput = -1;

std::string error_text(int err) {
  return err == kLostOutput ? std::string("a write failed, output lost") : strerror(err);
}

// --- temporaries removed on a signal ----------------------------------------------------
//
// A list of slots that only grows (slots are reused, never freed), so the signal handler
// can walk it without locks: a slot's state is 2 while its path names a temporary to
// remove. Registering and unregistering are rare (one per output file).

struct TempSlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled, 2 armed
  char path[PATH_MAX] = {};
  TempSlot* next = nullptr;
};

std::atomic<TempSlot*> g_slots{nullptr};
std::mutex g_slots_mutex;  // serialises registering and unregistering (not the handler)

constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};

extern "C" void remove_temporaries_and_die(int sig) {
  for (TempSlot* s = g_slots.load(std::memory_order_acquire); s != nullptr; s = s->next) {
    if (s->state.load(std::memory_order_acquire) == 2) unlink(s->path);
  }
  // The default action (terminate) once the handler returns and the signal is unblocked.
  struct sigaction dfl = {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  raise(sig);
}

// Installs the handler for the signals whose action is still the default (an ignored
// signal stays ignored, e.g. SIGHUP under nohup). Once per process.
void install_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (const int sig : kCleanupSignals) {
      struct sigaction old = {};
      if (sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL ||
          (old.sa_flags & SA_SIGINFO) != 0) {
        continue;
      }
      struct sigaction sa = {};
      sa.sa_handler = remove_temporaries_and_die;
      sigemptyset(&sa.sa_mask);
      for (const int other : kCleanupSignals)
        sigaddset(&sa.sa_mask, other);
      sigaction(sig, &sa, nullptr);
    }
  });
}

void register_temp(const std::string& path) {
  if (path.size() >= PATH_MAX) return;  // mkstemp would have refused it
  std::lock_guard<std::mutex> lock(g_slots_mutex);
  TempSlot* slot = nullptr;
  for (TempSlot* s = g_slots.load(std::memory_order_acquire); s != nullptr; s = s->next) {
    if (s->state.load(std::memory_order_acquire) == 0) {
      slot = s;
      break;
    }
  }
  if (slot == nullptr) {
    slot = new TempSlot;  // never freed: the handler may be walking the list
    slot->next = g_slots.load(std::memory_order_acquire);
    g_slots.store(slot, std::memory_order_release);
  }
  slot->state.store(1, std::memory_order_release);
  memcpy(slot->path, path.c_str(), path.size() + 1);
  slot->state.store(2, std::memory_order_release);
}

void unregister_temp(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_slots_mutex);
  for (TempSlot* s = g_slots.load(std::memory_order_acquire); s != nullptr; s = s->next) {
    if (s->state.load(std::memory_order_acquire) == 2 && path == s->path) {
      s->state.store(0, std::memory_order_release);
      return;
    }
  }
}

// Removes a registered temporary file, then forgets it.
void remove_temp(std::string* temp) {
  if (temp->empty()) return;
  unlink(temp->c_str());
  unregister_temp(*temp);
  temp->clear();
}

// --- paths ----------------------------------------------------------------------------

// The file a path names, symbolic links resolved (so replacing it keeps the link).
std::string resolve_target(const std::string& path) {
  struct stat ls;
  if (lstat(path.c_str(), &ls) == 0 && S_ISLNK(ls.st_mode)) {
    if (char* real = realpath(path.c_str(), nullptr)) {
      std::string resolved(real);
      free(real);
      return resolved;
    }
  }
  return path;
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string base_name_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The permissions a file created with fopen() would get (0666 less the umask), read
// without changing the umask where /proc tells it.
mode_t new_file_mode() {
  static const mode_t mask = [] {
    if (FILE* f = fopen("/proc/self/status", "r")) {
      char line[256];
      unsigned value = 0;
      bool found = false;
      while (!found && fgets(line, sizeof line, f) != nullptr)
        found = sscanf(line, "Umask: %o", &value) == 1;
      fclose(f);
      if (found) return mode_t{value};
    }
    const mode_t m = umask(022);
    umask(m);
    return m;
  }();
  return 0666 & ~mask;
}

// Creates a temporary file next to `target` (same directory, so rename() replaces the
// target in one step), registered for removal on a signal, with the target's permissions
// (or a new file's). Returns the descriptor, or -1 with errno set.
int make_temp(const std::string& target, std::string* temp) {
  install_handlers();
  // No signal between creating the file and registering it (it would be left behind).
  sigset_t block, previous;
  sigemptyset(&block);
  for (const int sig : kCleanupSignals)
    sigaddset(&block, sig);
  pthread_sigmask(SIG_BLOCK, &block, &previous);
  const std::string dir = directory_of(target);
  std::string name = dir + "/." + base_name_of(target) + ".tmp-XXXXXX";
  int fd = mkstemp(name.data());
  if (fd < 0 && errno == ENAMETOOLONG) {
    name = dir + "/.seqslam.tmp-XXXXXX";
    fd = mkstemp(name.data());
  }
  const int err = errno;
  if (fd >= 0) register_temp(name);
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (fd < 0) {
    errno = err;
    return -1;
  }
  *temp = name;
  struct stat st;
  const mode_t mode = stat(target.c_str(), &st) == 0 && S_ISREG(st.st_mode) ? (st.st_mode & 07777)
                                                                            : new_file_mode();
  (void)fchmod(fd, mode);  // best effort: the contents matter, the mode is a courtesy
  return fd;
}

// An existing file that may not be written keeps that protection (rename() would replace
// it regardless). Returns "" or the message.
std::string check_writable(const std::string& path, const std::string& target) {
  if (access(target.c_str(), W_OK) == 0 || errno == ENOENT) return {};
  return path + ": cannot open for writing: " + error_text(errno);
}

// Renames the temporary over `target`. `must_be_new`: the target did not exist when the
// output was opened, so nothing held its lock; if another process has created it since, it
// is not replaced (renameat2 RENAME_NOREPLACE, where the file system has it).
std::string rename_over(const std::string& path, std::string* temp, const std::string& target,
                        bool must_be_new) {
  int result = -1;
  if (must_be_new) {
    result = renameat2(AT_FDCWD, temp->c_str(), AT_FDCWD, target.c_str(), RENAME_NOREPLACE);
    if (result != 0 && (errno == EINVAL || errno == ENOSYS)) must_be_new = false;
  }
  if (!must_be_new) result = rename(temp->c_str(), target.c_str());
  if (result != 0) {
    const int err = errno;
    const std::string message =
        err == EEXIST
            ? path +
                  ": another process created it while this one was writing it; not replaced "
                  "(this run's output is not kept: run it again)"
            : path + ": cannot replace it with the written file " + *temp + ": " + error_text(err);
    remove_temp(temp);
    return message;
  }
  unregister_temp(*temp);
  temp->clear();
  return {};
}

// The lock of an existing regular target that is replaced as a whole (issue 34): held from
// open() until the rename, so a second process writing the same output is refused at once
// instead of one run's file silently replacing the other's. Returns "" with *fd the open
// descriptor holding the lock (-1: no target, or one that cannot be opened to lock it), or
// the message.
std::string lock_target(const std::string& path, const std::string& target, int* fd) {
  *fd = open(target.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (*fd < 0) *fd = open(target.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (*fd < 0) return {};  // check_writable or the write reports what is wrong with it
  std::string error = hal::lock_for_writing(*fd, path);
  if (!error.empty()) {
    close(*fd);
    *fd = -1;
  }
  return error;
}

void unlock_target(int* fd) {
  if (*fd >= 0) close(*fd);
  *fd = -1;
}

// Small text files (index files) are worth listing; recordings and images are not.
bool may_be_index_file(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (1 << 20)) {
    return false;
  }
  FILE* f = fopen(path.c_str(), "rb");
  if (f == nullptr) return false;
  char head[4096];
  const size_t n = fread(head, 1, sizeof head, f);
  fclose(f);
  return memchr(head, 0, n) == nullptr;
}

}  // namespace

// --- inputs ---------------------------------------------------------------------------

bool file_identity(const std::string& path, FileIdentity* out) {
  struct stat st;
  if (path.empty() || stat(path.c_str(), &st) != 0) return false;
  out->device = st.st_dev;
  out->inode = st.st_ino;
  return true;
}

void InputFiles::add(const std::string& path) {
  FileIdentity id;
  if (path == "-" || !file_identity(path, &id)) return;
  files_.emplace_back(id, path);
}

void InputFiles::add_sequence(const std::string& path) {
  add(path);
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return;
  if (!S_ISDIR(st.st_mode) && !may_be_index_file(path)) return;
  const ImageList images = list_images(path);
  if (!images) return;  // loading the input reports what is wrong with it
  for (const std::string& image : images.value())
    add(image);
}

void InputFiles::add_map(const std::string& yaml) {
  add(yaml);
  const size_t dot = yaml.find_last_of('.');
  const size_t slash = yaml.find_last_of('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) {
    add(yaml.substr(0, dot) + ".pgm");
  }
}

std::string InputFiles::clash(const std::string& output) const {
  FileIdentity id;
  std::string name = output;
  if (output == "-") {
    struct stat st;
    if (fstat(STDOUT_FILENO, &st) != 0 || !S_ISREG(st.st_mode)) return {};
    id.device = st.st_dev;
    id.inode = st.st_ino;
    name = "standard output";
  } else if (!file_identity(output, &id)) {
    return {};
  }
  for (const auto& [input_id, input] : files_) {
    if (input_id == id) {
      return name + ": is also an input of this command" +
             (input == output ? std::string() : " (" + input + ")") +
             "; refusing to overwrite it: give another file";
    }
  }
  return {};
}

// --- OutputFile ---------------------------------------------------------------------------

OutputFile::~OutputFile() {
  discard();
}

std::string OutputFile::open(const std::string& path, Mode mode) {
  discard();
  hal::ignore_file_size_signal();  // a file size limit is a write error, not a silent death
  path_ = path;
  target_.clear();
  error_ = 0;
  is_stdout_ = false;
  if (path.empty()) return "(empty path): no output file name given";
  if (path == "-") {
    file_ = stdout;
    is_stdout_ = true;
    return {};
  }
  target_ = resolve_target(path);
  struct stat st;
  const bool exists = stat(target_.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) return path + ": is a directory, not a file";
  if (mode == Mode::kAppend || (exists && !S_ISREG(st.st_mode))) {
    // In place: appended rows, or a device or FIFO (never replaced, never removed).
    file_ = fopen(target_.c_str(), mode == Mode::kAppend ? "ab" : "wb");
    if (file_ == nullptr) return path + ": cannot open for writing: " + error_text(errno);
    // Two processes appending to one file would interleave their rows (duplicates).
    if (std::string error = hal::lock_for_writing(fileno(file_), path); !error.empty()) {
      fclose(file_);
      file_ = nullptr;
      return error;
    }
    return {};
  }
  if (std::string error = check_writable(path, target_); !error.empty()) return error;
  target_is_new_ = !exists;
  if (std::string error = lock_target(path, target_, &lock_fd_); !error.empty()) return error;
  const int fd = make_temp(target_, &temp_);
  if (fd < 0) {
    const int err = errno;
    unlock_target(&lock_fd_);
    return path + ": cannot create: " + error_text(err);
  }
  file_ = fdopen(fd, "wb");
  if (file_ == nullptr) {
    const int err = errno;
    close(fd);
    remove_temp(&temp_);
    unlock_target(&lock_fd_);
    return path + ": cannot create: " + error_text(err);
  }
  return {};
}

void OutputFile::record_error(int err) {
  if (error_ == 0) error_ = err != 0 ? err : EIO;
}

bool OutputFile::write(const void* data, size_t size) {
  if (file_ == nullptr) record_error(EBADF);
  if (error_ != 0) return false;
  if (size == 0) return true;
  errno = 0;
  if (fwrite(data, 1, size, file_) != size) {
    record_error(errno);
    return false;
  }
  return true;
}

bool OutputFile::print(const char* format, ...) {
  if (file_ == nullptr) record_error(EBADF);
  if (error_ != 0) return false;
  va_list args;
  va_start(args, format);
  errno = 0;
  const int n = vfprintf(file_, format, args);
  va_end(args);
  if (n < 0) {
    record_error(errno);
    return false;
  }
  return true;
}

bool OutputFile::flush() {
  if (file_ == nullptr) record_error(EBADF);
  if (error_ != 0) return false;
  errno = 0;
  if (fflush(file_) != 0) record_error(errno);
  return error_ == 0;
}

std::string OutputFile::error() const {
  if (error_ == 0) return {};
  return (is_stdout_ ? std::string("standard output") : path_) +
         ": write failed: " + error_text(error_);
}

std::string OutputFile::commit() {
  if (file_ == nullptr) return (path_.empty() ? std::string("(no file)") : path_) + ": not open";
  errno = 0;
  if (fflush(file_) != 0) record_error(errno);
  if (ferror(file_) != 0) record_error(kLostOutput);
  if (is_stdout_) {
    file_ = nullptr;
    clearerr(stdout);  // reported here, not again by finish_stdout()
    return error();
  }
  FILE* f = file_;
  file_ = nullptr;
  errno = 0;
  if (fclose(f) != 0) record_error(errno);
  if (error_ != 0) {
    const std::string message = error();
    remove_temp(&temp_);
    unlock_target(&lock_fd_);
    return message;
  }
  if (temp_.empty()) return {};
  std::string message = rename_over(path_, &temp_, target_, target_is_new_);
  unlock_target(&lock_fd_);
  return message;
}

void OutputFile::discard() {
  if (file_ != nullptr && !is_stdout_) fclose(file_);
  file_ = nullptr;
  remove_temp(&temp_);
  unlock_target(&lock_fd_);
}

// --- OutputPath ---------------------------------------------------------------------------

OutputPath::~OutputPath() {
  discard();
}

std::string OutputPath::open(const std::string& path) {
  discard();
  hal::ignore_file_size_signal();  // a file size limit is a write error, not a silent death
  path_ = path;
  in_place_ = false;
  if (path.empty()) return "(empty path): no output file name given";
  target_ = resolve_target(path);
  struct stat st;
  const bool exists = stat(target_.c_str(), &st) == 0;
  if (exists && !S_ISREG(st.st_mode)) {
    if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
      in_place_ = true;  // a device: written where it is, never removed (its writer locks it)
      return {};
    }
    if (S_ISDIR(st.st_mode)) return path + ": is a directory, not a file";
    return path +
           ": is a FIFO or socket: this file is written with seeks and read back; give a "
           "regular file or a device";
  }
  if (std::string error = check_writable(path, target_); !error.empty()) return error;
  target_is_new_ = !exists;
  if (std::string error = lock_target(path, target_, &lock_fd_); !error.empty()) return error;
  const int fd = make_temp(target_, &temp_);
  if (fd < 0) {
    const int err = errno;
    unlock_target(&lock_fd_);
    return path + ": cannot create: " + error_text(err);
  }
  if (close(fd) != 0) {
    const int err = errno;
    remove_temp(&temp_);
    unlock_target(&lock_fd_);
    return path + ": cannot create: " + error_text(err);
  }
  return {};
}

std::string OutputPath::commit() {
  if (in_place_) return {};
  if (temp_.empty()) return path_ + ": not open";
  std::string message = rename_over(path_, &temp_, target_, target_is_new_);
  unlock_target(&lock_fd_);
  return message;
}

void OutputPath::discard() {
  remove_temp(&temp_);
  unlock_target(&lock_fd_);
}

std::string OutputPath::shown(std::string message) const {
  if (temp_.empty()) return message;
  for (size_t at = message.find(temp_); at != std::string::npos;
       at = message.find(temp_, at + path_.size())) {
    message.replace(at, temp_.size(), path_);
  }
  return message;
}

// --- helpers ------------------------------------------------------------------------------

std::string write_output(const std::string& path, const void* data, size_t size) {
  OutputFile out;
  std::string error = out.open(path);
  if (!error.empty()) return error;
  out.write(data, size);
  return out.commit();
}

namespace {
int g_stdout_error = 0;  // errno of the first failed write_stdout()
}  // namespace

void write_stdout(std::string_view text) {
  errno = 0;
  if (fwrite(text.data(), 1, text.size(), stdout) != text.size() && g_stdout_error == 0) {
    g_stdout_error = errno != 0 ? errno : EIO;
  }
}

std::string finish_stdout() {
  errno = 0;
  int err = g_stdout_error;
  g_stdout_error = 0;
  if (err != 0) {
    (void)fflush(stdout);
  } else if (fflush(stdout) != 0) {
    err = errno != 0 ? errno : EIO;
  } else if (ferror(stdout) != 0) {
    err = kLostOutput;
  }
  if (err == 0) return {};
  clearerr(stdout);
  return "writing standard output: " + error_text(err);
}

}  // namespace seqslam::tools
