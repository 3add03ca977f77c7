// Shared pieces of the `seqslam` host tool: the subcommand groups, exit codes and messages,
// parsing of sizes and decimals, exact formatting of fixed-point values, and opening disk
// images, volume files and standalone log files as block devices.
//
// Each subcommand group lives in its own source file and registers itself with an add_*
// function; the chosen subcommand's action is stored in a Command and run by main() after
// CLI11 has parsed the whole command line (so parse errors never leave half-done work).
#pragma once

#include <stdint.h>

#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "seqslam/fixed.h"
#include "seqslam/hal/block_device.h"
#include "seqslam/hal/file_block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/odometry.h"
#include "seqslam/preprocess.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/record_log.h"
#include "seqslam/storage/volume.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/setting_text.h"

namespace CLI {
class App;
}

namespace seqslam::storage {
struct RunConfig;
}

namespace seqslam::cli {

// Exit statuses (docs/seqslam_cli.md).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // bad input file, damaged data, I/O error
inline constexpr int kExitUsage = 2;    // the command line is wrong (CLI11 or our own checks)

// The action of the chosen subcommand; returns the exit status.
using Command = std::function<int()>;

// Subcommand groups, one source file each.
void add_disk_commands(CLI::App& app, Command* chosen);        // disk.cpp
void add_config_commands(CLI::App& app, Command* chosen);      // config.cpp
void add_results_command(CLI::App& app, Command* chosen);      // results.cpp
void add_convert_commands(CLI::App& app, Command* chosen);     // convert.cpp
void add_dream_commands(CLI::App& app, Command* chosen);       // dream_info.cpp
void add_eval_commands(CLI::App& app, Command* chosen);        // eval.cpp (run, eval)
void add_sweep_command(CLI::App& app, Command* chosen);        // sweep.cpp
void add_tune_command(CLI::App& app, Command* chosen);         // tune.cpp
void add_report_command(CLI::App& app, Command* chosen);       // report_cmd.cpp
void add_transforms_command(CLI::App& app, Command* chosen);   // transforms.cpp
void add_slam_command(CLI::App& app, Command* chosen);         // slam.cpp
void add_explain_command(CLI::App& app, Command* chosen);      // explain.cpp
void add_report_slam_command(CLI::App& app, Command* chosen);  // report_slam.cpp
void add_graph_command(CLI::App& app, Command* chosen);        // graph.cpp

// One line saying what a run configuration does (config.cpp; disk list uses it too), e.g.
// "modes repeat, trigger distance 0.2 m, 32x16, he, S=30 W=50 R=10, threshold 0.85".
std::string run_config_summary(const storage::RunConfig& config);

// ---------------------------------------------------------------------------------------
// Messages: "seqslam: error: ..." / "seqslam: warning: ..." on stderr.

int fail(const std::string& message);         // prints, returns kExitFailure
int usage_error(const std::string& message);  // prints with a --help hint, returns kExitUsage
void warn(const std::string& message);

// ---------------------------------------------------------------------------------------
// Parsing (the settings' values: seqslam_tools/setting_text.h).

// A byte count: decimal digits with an optional suffix K, M or G (1024-based, either case).
std::string parse_byte_size(const std::string& text, uint64_t* bytes);
// Whole 512-byte blocks needed for `bytes` (rounded up).
uint64_t blocks_for(uint64_t bytes);

// ---------------------------------------------------------------------------------------
// Devices.

// A read-only block device over bytes in memory (a standalone file whose size is not a
// whole number of blocks: the last block is padded with zeros).
class MemoryBlockDevice final : public hal::BlockDevice {
 public:
  explicit MemoryBlockDevice(std::vector<uint8_t> bytes);

 private:
  uint32_t do_block_count() const override { return blocks_; }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override;
  Status do_write(uint32_t, uint32_t, const uint8_t*) override {
    return Status::kResourceExhausted;  // write-protected
  }
  Status do_sync() override { return Status::kOk; }

  std::vector<uint8_t> bytes_;
  uint32_t blocks_ = 0;
};

// A disk image opened and its volume mounted. Not movable (the volume points at the file).
class Disk {
 public:
  Disk() = default;
  Disk(const Disk&) = delete;
  Disk& operator=(const Disk&) = delete;

  // Opens and mounts `path`. Returns an empty string or a message naming the file.
  std::string open(const std::string& path, bool writable);
  // The volume file `name` as a device. Returns an empty string or a message naming the
  // image and the file (and listing the files there are when it is absent).
  std::string open_file(const std::string& name, storage::Region* out) const;

  hal::FileBlockDevice& device() { return device_; }
  const storage::Volume& volume() const { return volume_; }
  const std::string& path() const { return path_; }
  // The names of the volume's files, comma-separated.
  std::string file_names() const;
  // "" when the first `bytes` of volume file `name` can be written in place within the file
  // size limit (ulimit -f); else the message, so an edit is refused before it touches the
  // card rather than failing half way (hal/host_file.h).
  std::string check_write_limit(const std::string& name, uint64_t bytes) const;

 private:
  hal::FileBlockDevice device_;
  storage::Volume volume_;
  std::string path_;
};

// Where a log (dream recording, results) is read from: a standalone file, a file of a disk
// image named as IMAGE:NAME, or a bare disk image with a default file name. Read-only.
class LogSource {
 public:
  LogSource() = default;
  LogSource(const LogSource&) = delete;
  LogSource& operator=(const LogSource&) = delete;

  // `spec` is FILE or IMAGE:NAME. A FILE that is a disk image (a volume) uses the volume
  // file `default_name`; with no default it is an error that says to name the file.
  // Returns an empty string or a message naming the file and the problem.
  std::string open(const std::string& spec, const char* default_name);

  hal::BlockDevice& device() { return *device_; }
  // The disk image the log was read from; nullptr for a standalone file.
  const Disk* disk() const { return disk_.get(); }
  // "FILE" or "IMAGE:NAME", for messages.
  const std::string& name() const { return name_; }
  // A standalone file whose size is not a whole number of 512-byte blocks (cut short by a
  // copy): it is read as if padded with zeros, and the tool reports it as damaged.
  bool truncated() const { return truncated_; }
  uint64_t file_bytes() const { return file_bytes_; }

 private:
  std::unique_ptr<Disk> disk_;
  storage::Region region_;
  hal::FileBlockDevice file_;
  std::unique_ptr<MemoryBlockDevice> memory_;
  hal::BlockDevice* device_ = nullptr;
  std::string name_;
  bool truncated_ = false;
  uint64_t file_bytes_ = 0;
};

// kExitOk when none of `outputs` (empty ones skipped) is one of `inputs`, else the usage
// error (status 2) naming the output, before anything is written.
int refuse_inputs_as_outputs(const tools::InputFiles& inputs,
                             std::initializer_list<std::string> outputs);

// The host file a log source names (`spec` as LogSource::open reads it): FILE, or IMAGE of
// IMAGE:NAME. For refusing an output that is the input (tools::InputFiles).
std::string log_source_file(const std::string& spec);

// True when block 0 of `device` starts with the volume magic (a disk image).
bool looks_like_volume(hal::BlockDevice& device);

// Why `device` could not be opened as a `what` (e.g. "dream recording"): "not a readable
// <what>: <log problem>", or "empty: block 0 is all zeros (no <what> written yet)".
std::string log_open_problem(hal::BlockDevice& device, const std::string& what,
                             storage::LogProblem problem);

// Warns when `source` is a standalone file cut short (not whole blocks); true if it was.
bool warn_if_truncated(const LogSource& source);

// Opens `source` as a dream recording with `reader` (buffer resized to kDreamRecordMax).
// Returns "" on success, else the message "<name>: <why>" for fail().
std::string open_dream(LogSource& source, storage::DreamReader& reader,
                       std::vector<uint8_t>& buffer);

// Summary of a record log read with LogReader (disk list).
struct LogScan {
  std::string error;  // open failed: why (the other fields are then meaningless)
  uint32_t session = 0;
  uint32_t records = 0;       // complete records read
  uint32_t damaged = 0;       // damaged records in the middle (skipped)
  uint32_t too_large = 0;     // records beyond the buffer (skipped)
  uint32_t damaged_slot = 0;  // storage::damaged_commit_slot()
  storage::LogProblem end = storage::LogProblem::kNone;
  uint64_t end_offset = 0;  // byte offset of the end / the damaged tail
};
LogScan scan_log(hal::BlockDevice& device, const storage::LogKind& kind);
// "ends cleanly", "damaged tail at byte N", ... for a finished scan.
std::string describe_log_end(const LogScan& scan);

}  // namespace seqslam::cli
