// The SD card on the PC: a file of 512-byte blocks (a disk image). Host only.
//
// The same images are attached to the emulated board (scripts/qemu-run.sh --disk), so what
// the firmware writes under QEMU and what the host build writes can be compared byte for
// byte, and the PC tools read both.
#pragma once

#include <cstdio>
#include <string>

#include "seqslam/hal/block_device.h"

namespace seqslam::hal {

class FileBlockDevice final : public BlockDevice {
 public:
  FileBlockDevice() = default;
  ~FileBlockDevice() { close(); }
  FileBlockDevice(const FileBlockDevice&) = delete;
  FileBlockDevice& operator=(const FileBlockDevice&) = delete;

  // Opens an existing image (its size must be a non-zero multiple of 512). With `writable`
  // false, writes return kResourceExhausted (write-protected card). Writable, it holds the
  // file's advisory lock until close() (host_file.h), so a second process cannot write the
  // same card at once. kNotFound if the file does not exist, kInvalidArgument for a size
  // that is not whole blocks or a FIFO, socket or directory, kUnavailable for other I/O
  // errors and for a card another process holds the lock of; error() has the message.
  Status open(const std::string& path, bool writable);
  // Creates (or truncates) an image of `blocks` zero blocks and opens it writable, holding
  // its lock as open() does (a locked file is refused before any of it changes). A regular
  // file is sized with ftruncate (sparse: fast, and no space until written); a device has
  // its blocks written with zeros.
  Status create(const std::string& path, uint32_t blocks);
  void close();

  const std::string& error() const { return error_; }
  const std::string& path() const { return path_; }

 private:
  uint32_t do_block_count() const override { return blocks_; }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override;
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override;
  Status do_sync() override;

  std::FILE* file_ = nullptr;
  uint32_t blocks_ = 0;
  bool writable_ = false;
  std::string path_;
  std::string error_;
};

}  // namespace seqslam::hal
