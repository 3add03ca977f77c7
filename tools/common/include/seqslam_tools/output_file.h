// Output files of the host tools that never destroy an input and never report success when
// a write failed (issue 17).
//
//  * InputFiles: the files a command reads, by identity (device and inode after following
//    symbolic links, so `./a`, `a`, a link to it and a hard link all match). An output that
//    is one of them is refused before anything is written (the tools exit with status 2).
//  * OutputFile: a stream output. A regular file (or a new path) is written to a temporary
//    file in the same directory and renamed over the target by commit(); a failure, an
//    uncommitted destructor or SIGINT/SIGTERM/SIGHUP/SIGPIPE removes the temporary and leaves
//    the old target untouched. An existing device or FIFO, and "-" (standard output), are
//    written in place and never removed. Every write, the flush and the close are checked.
//  * OutputPath: the same for code that writes a file by its path itself (a disk image or a
//    dream recording through hal::FileBlockDevice): it hands out the temporary path, and
//    commit() renames it.
//  * finish_stdout(): the checked flush of standard output at the end of a program.
//
// One writer at a time (issue 34): a file written in place (append mode, a block device) is
// locked while it is open, and an existing regular target that is replaced keeps its lock
// from open() to the rename (seqslam/hal/host_file.h, advisory flock); a second process
// writing it is refused at open(), before anything is written. A new target is renamed into
// place only if no other process created it meanwhile. Opening also ignores SIGXFSZ, so a
// file size limit (`ulimit -f`) fails the write with EFBIG ("File too large") like a full
// disk: a message, the temporary removed.
//
// Error messages name the target file ("OUT: write failed: No space left on device").
#pragma once

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace seqslam::tools {

// The identity of an existing file: st_dev and st_ino of stat() (symbolic links followed).
struct FileIdentity {
  uint64_t device = 0;
  uint64_t inode = 0;
  friend bool operator==(const FileIdentity& a, const FileIdentity& b) {
    return a.device == b.device && a.inode == b.inode;
  }
};
// False when `path` does not exist (or cannot be stat'ed).
bool file_identity(const std::string& path, FileIdentity* out);

class InputFiles {
 public:
  // Adds `path` if it exists; "-" and paths that do not exist are ignored.
  void add(const std::string& path);
  // Adds `path` and, when it is a directory or an index file of images (dataset.h,
  // list_images), every image it lists.
  void add_sequence(const std::string& path);
  // Adds a map_server map: the YAML file and the PGM of the same stem.
  void add_map(const std::string& yaml);

  // "" when `output` is none of the inputs (or does not exist yet), else the message
  // "OUT: is also an input of this command (INPUT); refusing to overwrite it: give another
  // file". "-" is checked as standard output (when that is a file).
  std::string clash(const std::string& output) const;

 private:
  std::vector<std::pair<FileIdentity, std::string>> files_;
};

class OutputFile {
 public:
  enum class Mode {
    kReplace,  // a regular file is replaced as a whole on commit (temporary + rename)
    kAppend,   // appended to in place (resumable outputs: every row kept as it is written)
  };

  OutputFile() = default;
  ~OutputFile();  // not committed: the temporary is removed, the target is untouched
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Opens `path` for writing ("-" = standard output). Returns "" or a message naming the
  // file (a directory, a missing directory, no permission, another process writing it ...).
  std::string open(const std::string& path, Mode mode = Mode::kReplace);
  bool is_open() const { return file_ != nullptr; }

  // Each returns false once any write has failed (the first failure is kept for commit()).
  bool write(const void* data, size_t size);
  bool write(std::string_view text) { return write(text.data(), text.size()); }
  bool print(const char* format, ...) __attribute__((format(printf, 2, 3)));
  // Pushes buffered bytes to the file (resumable outputs do after every row).
  bool flush();
  bool failed() const { return error_ != 0; }
  // "PATH: write failed: <why>" for the first failure, "" when nothing failed.
  std::string error() const;

  // Checks every write, flushes, closes and (for a temporary) renames it over the target.
  // Returns "" or a message naming the file; on failure the temporary is removed.
  std::string commit();
  // Closes without committing: the temporary is removed (a target written in place keeps
  // what was written).
  void discard();

  const std::string& path() const { return path_; }
  // Written in place (standard output, a device or FIFO, append mode): nothing is renamed.
  bool in_place() const { return temp_.empty(); }

 private:
  void record_error(int err);

  std::string path_;    // as given (for messages)
  std::string target_;  // the file renamed over (symbolic links resolved)
  std::string temp_;    // the temporary file, or "" when written in place
  FILE* file_ = nullptr;
  bool is_stdout_ = false;
  int error_ = 0;               // errno of the first failed write
  int lock_fd_ = -1;            // holds the lock of the existing target until the rename
  bool target_is_new_ = false;  // the target did not exist at open(): never replace one
};

class OutputPath {
 public:
  OutputPath() = default;
  ~OutputPath();  // not committed: the temporary is removed
  OutputPath(const OutputPath&) = delete;
  OutputPath& operator=(const OutputPath&) = delete;

  // Chooses where the file is written: a new temporary file next to `path` (a regular file
  // or a new path), or `path` itself when it is an existing character or block device. A
  // FIFO, socket or directory is refused (the writers seek and read back). Returns "" or a
  // message naming the file.
  std::string open(const std::string& path);
  // Where the writer writes (the temporary, or the device).
  const std::string& write_path() const { return in_place_ ? path_ : temp_; }
  bool in_place() const { return in_place_; }
  // The writer must have flushed and closed the file. Renames the temporary over the
  // target. Returns "" or a message naming the file; on failure the temporary is removed.
  std::string commit();
  // Removes the temporary (a device keeps what was written).
  void discard();

  const std::string& path() const { return path_; }
  // `message` (e.g. a writer's error naming write_path()) with the temporary's name replaced
  // by the target's, for messages that name the file the user gave.
  std::string shown(std::string message) const;

 private:
  std::string path_;
  std::string target_;
  std::string temp_;
  bool in_place_ = false;
  int lock_fd_ = -1;            // as OutputFile's
  bool target_is_new_ = false;  // as OutputFile's
};

// Writes `size` bytes to `path` as one OutputFile (temporary + rename). Returns "" or a
// message naming the file.
std::string write_output(const std::string& path, const void* data, size_t size);
inline std::string write_output(const std::string& path, std::string_view text) {
  return write_output(path, text.data(), text.size());
}

// Writes `text` to standard output, keeping the reason of a failed write for
// finish_stdout() (a printf that fails mid-way leaves only stdio's error flag: "output lost").
void write_stdout(std::string_view text);

// Flushes standard output and checks that everything written to it arrived (fflush and
// ferror). Returns "" or "writing standard output: <why>".
std::string finish_stdout();

}  // namespace seqslam::tools
