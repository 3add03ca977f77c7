#include "seqslam/hal/file_block_device.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "seqslam/hal/host_file.h"

namespace seqslam::hal {

namespace {

std::string describe(const std::string& path, const char* what) {
  return path + ": " + what + ": " + std::strerror(errno);
}

// Why `path` cannot be a disk image ("" when it may be one: a regular file, a device, or a
// path that does not exist, which fopen reports). A FIFO would block the open until a
// writer came, and a directory is no image.
std::string not_an_image(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return {};
  if (S_ISDIR(st.st_mode)) return path + ": is a directory, not a disk image";
  if (S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode)) {
    return path + ": is a FIFO or socket, not a disk image (a card is read and written with seeks)";
  }
  return {};
}

}  // namespace

void FileBlockDevice::close() {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  blocks_ = 0;
}

Status FileBlockDevice::open(const std::string& path, bool writable) {
  close();
  path_ = path;
  error_ = not_an_image(path);
  if (!error_.empty()) return Status::kInvalidArgument;
  file_ = std::fopen(path.c_str(), writable ? "r+b" : "rb");
  if (file_ == nullptr) {
    error_ = describe(path, "cannot open disk image");
    return errno == ENOENT ? Status::kNotFound : Status::kUnavailable;
  }
  // One writer at a time (host_file.h): a second process writing the same card would
  // interleave its records with this one's.
  if (writable) {
    error_ = lock_for_writing(fileno(file_), path);
    if (!error_.empty()) {
      close();
      return Status::kUnavailable;
    }
  }
  if (std::fseek(file_, 0, SEEK_END) != 0) {
    error_ = describe(path, "cannot seek");
    close();
    return Status::kUnavailable;
  }
  const long size = std::ftell(file_);
  if (size <= 0 || size % static_cast<long>(kBlockSize) != 0 ||
      size / static_cast<long>(kBlockSize) > 0xFFFFFFFFL) {
    error_ = path + ": a disk image must be a non-zero whole number of 512-byte blocks (it has " +
             std::to_string(size) + " bytes)";
    close();
    return Status::kInvalidArgument;
  }
  blocks_ = static_cast<uint32_t>(size / static_cast<long>(kBlockSize));
  writable_ = writable;
  error_.clear();
  return Status::kOk;
}

Status FileBlockDevice::create(const std::string& path, uint32_t blocks) {
  close();
  path_ = path;
  // Opened without truncating and locked first: a file another process is writing (a card in
  // use) is refused before any of it changes; the zeros come after the lock.
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd >= 0) file_ = fdopen(fd, "r+b");
  if (file_ == nullptr) {
    error_ = describe(path, "cannot create disk image");
    if (fd >= 0) ::close(fd);
    return Status::kUnavailable;
  }
  error_ = lock_for_writing(fileno(file_), path);
  if (!error_.empty()) {
    close();
    return Status::kUnavailable;
  }
  if (struct stat st;
      fstat(fileno(file_), &st) == 0 && S_ISREG(st.st_mode) && ftruncate(fileno(file_), 0) != 0) {
    error_ = describe(path, "cannot size disk image");
    close();
    return Status::kUnavailable;
  }
  struct stat st;
  if (fstat(fileno(file_), &st) == 0 && S_ISREG(st.st_mode)) {
    // A regular file: sized at once, sparse (the zero blocks take no space until written).
    if (ftruncate(fileno(file_), static_cast<off_t>(blocks) * static_cast<off_t>(kBlockSize)) !=
        0) {
      error_ = describe(path, "cannot size disk image");
      close();
      return Status::kUnavailable;
    }
  } else {
    // A device: zero its blocks.
    const uint8_t zeros[kBlockSize] = {};
    for (uint32_t i = 0; i < blocks; ++i) {
      if (std::fwrite(zeros, kBlockSize, 1, file_) != 1) {
        error_ = describe(path, "cannot write disk image");
        close();
        return Status::kUnavailable;
      }
    }
    if (std::fflush(file_) != 0) {
      error_ = describe(path, "cannot write disk image");
      close();
      return Status::kUnavailable;
    }
  }
  blocks_ = blocks;
  writable_ = true;
  error_.clear();
  return Status::kOk;
}

Status FileBlockDevice::do_read(uint32_t first, uint32_t count, uint8_t* out) {
  if (file_ == nullptr) return Status::kUnavailable;
  errno = 0;
  if (std::fseek(file_, static_cast<long>(first) * static_cast<long>(kBlockSize), SEEK_SET) != 0 ||
      std::fread(out, kBlockSize, count, file_) != count) {
    // At the end of the file fread sets no errno: say so rather than "Success".
    error_ = errno != 0 ? describe(path_, "read failed")
                        : path_ + ": read failed at block " + std::to_string(first) +
                              ": the file ends before it";
    std::clearerr(file_);
    return Status::kDataLoss;
  }
  return Status::kOk;
}

Status FileBlockDevice::do_write(uint32_t first, uint32_t count, const uint8_t* data) {
  if (file_ == nullptr) return Status::kUnavailable;
  if (!writable_) return Status::kResourceExhausted;
  if (std::fseek(file_, static_cast<long>(first) * static_cast<long>(kBlockSize), SEEK_SET) != 0 ||
      std::fwrite(data, kBlockSize, count, file_) != count) {
    error_ = describe(path_, "write failed");
    return Status::kDataLoss;
  }
  return Status::kOk;
}

Status FileBlockDevice::do_sync() {
  if (file_ == nullptr) return Status::kUnavailable;
  if (!writable_) return Status::kOk;
  if (std::fflush(file_) != 0) {
    error_ = describe(path_, "flush failed");
    return Status::kDataLoss;
  }
  return Status::kOk;
}

}  // namespace seqslam::hal
