#include "cli_common.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>

#include "seqslam/hal/host_file.h"
#include "seqslam/status.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/wxh.h"

namespace seqslam::cli {

namespace fs = std::filesystem;

namespace {

__extension__ typedef unsigned __int128 U128;
__extension__ typedef __int128 I128;

constexpr uint8_t kVolumeMagic[8] = {'S', 'Q', 'S', 'L', 'V', 'O', 'L', '1'};
// Standalone files read into memory when cut short (not whole blocks).
constexpr uint64_t kMaxMemoryFile = uint64_t{1} << 30;

}  // namespace

// ---------------------------------------------------------------------------------------
// Messages

int fail(const std::string& message) {
  std::fprintf(stderr, "seqslam: error: %s\n", message.c_str());
  return kExitFailure;
}

int usage_error(const std::string& message) {
  std::fprintf(stderr, "seqslam: error: %s\nRun with --help for more information.\n",
               message.c_str());
  return kExitUsage;
}

void warn(const std::string& message) {
  std::fprintf(stderr, "seqslam: warning: %s\n", message.c_str());
}

// ---------------------------------------------------------------------------------------
// Parsing

std::string parse_byte_size(const std::string& text, uint64_t* bytes) {
  size_t i = 0;
  uint64_t v = 0;
  while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
    const uint64_t d = static_cast<uint64_t>(text[i] - '0');
    if (v > (UINT64_MAX - d) / 10) return "'" + text + "' is too large";
    v = v * 10 + d;
    ++i;
  }
  if (i == 0) return "'" + text + "' is not a size (digits with an optional K, M or G suffix)";
  unsigned shift = 0;
  if (i + 1 == text.size()) {
    switch (text[i]) {
      case 'k':
      case 'K':
        shift = 10;
        break;
      case 'm':
      case 'M':
        shift = 20;
        break;
      case 'g':
      case 'G':
        shift = 30;
        break;
      default:
        return "'" + text + "' has an unknown suffix (use K, M or G: 1024-based)";
    }
  } else if (i != text.size()) {
    return "'" + text + "' is not a size (digits with an optional K, M or G suffix)";
  }
  if (shift > 0 && v > (UINT64_MAX >> shift)) return "'" + text + "' is too large";
  *bytes = v << shift;
  return {};
}

uint64_t blocks_for(uint64_t bytes) {
  return bytes / hal::kBlockSize + (bytes % hal::kBlockSize != 0 ? 1 : 0);
}

// ---------------------------------------------------------------------------------------
// Formatting

// ---------------------------------------------------------------------------------------
// Devices

MemoryBlockDevice::MemoryBlockDevice(std::vector<uint8_t> bytes) : bytes_(std::move(bytes)) {
  blocks_ = static_cast<uint32_t>(blocks_for(bytes_.size()));
  bytes_.resize(static_cast<size_t>(blocks_) * hal::kBlockSize, 0);
}

Status MemoryBlockDevice::do_read(uint32_t first, uint32_t count, uint8_t* out) {
  const size_t at = static_cast<size_t>(first) * hal::kBlockSize;
  const size_t n = static_cast<size_t>(count) * hal::kBlockSize;
  std::copy(bytes_.begin() + static_cast<std::ptrdiff_t>(at),
            bytes_.begin() + static_cast<std::ptrdiff_t>(at + n), out);
  return Status::kOk;
}

std::string Disk::open(const std::string& path, bool writable) {
  path_ = path;
  if (device_.open(path, writable) != Status::kOk) return device_.error();
  storage::VolumeProblem problem = storage::VolumeProblem::kNone;
  const Status s = volume_.mount(device_, &problem);
  if (s != Status::kOk) {
    std::string message =
        path + ": cannot mount the volume: " + storage::volume_problem_text(problem);
    if (problem == storage::VolumeProblem::kDeviceError && !device_.error().empty()) {
      message += " (" + device_.error() + ")";
    }
    return message;
  }
  return {};
}

std::string Disk::open_file(const std::string& name, storage::Region* out) const {
  storage::VolumeProblem problem = storage::VolumeProblem::kNone;
  if (volume_.open(name.c_str(), out, &problem) != Status::kOk) {
    const std::string names = file_names();
    return path_ + ": no volume file '" + name + "' (" +
           (names.empty() ? std::string("the volume has no files") : "the volume has: " + names) +
           ")";
  }
  return {};
}

std::string Disk::check_write_limit(const std::string& name, uint64_t bytes) const {
  for (uint32_t i = 0; i < volume_.file_count(); ++i) {
    const storage::VolumeFile& f = volume_.file(i);
    if (name != f.name) continue;
    const uint64_t end = (uint64_t{f.first_block} + blocks_for(bytes)) * hal::kBlockSize;
    const std::string error = hal::check_file_size_limit(path_, end);
    return error.empty() ? error : error + " (volume file '" + name + "'; nothing was written)";
  }
  return {};
}

std::string Disk::file_names() const {
  std::string names;
  for (uint32_t i = 0; i < volume_.file_count(); ++i) {
    if (!names.empty()) names += ", ";
    names += volume_.file(i).name;
  }
  return names;
}

bool looks_like_volume(hal::BlockDevice& device) {
  uint8_t block[hal::kBlockSize];
  if (device.block_count() == 0 || device.read(0, 1, block) != Status::kOk) return false;
  return std::equal(std::begin(kVolumeMagic), std::end(kVolumeMagic), block);
}

int refuse_inputs_as_outputs(const tools::InputFiles& inputs,
                             std::initializer_list<std::string> outputs) {
  for (const std::string& output : outputs) {
    if (output.empty()) continue;
    const std::string clash = inputs.clash(output);
    if (!clash.empty()) return usage_error(clash);
  }
  return kExitOk;
}

std::string log_source_file(const std::string& spec) {
  std::error_code ec;
  if (fs::exists(spec, ec)) return spec;
  const size_t colon = spec.rfind(':');
  return colon != std::string::npos && colon > 0 ? spec.substr(0, colon) : spec;
}

std::string LogSource::open(const std::string& spec, const char* default_name) {
  std::error_code ec;
  name_ = spec;
  if (!fs::is_regular_file(spec, ec)) {
    const size_t colon = spec.rfind(':');
    if (colon != std::string::npos && colon > 0 && colon + 1 < spec.size() &&
        fs::exists(spec.substr(0, colon), ec)) {
      disk_ = std::make_unique<Disk>();
      std::string error = disk_->open(spec.substr(0, colon), false);
      if (error.empty()) error = disk_->open_file(spec.substr(colon + 1), &region_);
      if (!error.empty()) return error;
      device_ = &region_;
      return {};
    }
    if (fs::exists(spec, ec)) return spec + ": not a regular file";
    // Why it cannot be reached: missing, a link loop, a dangling link (input_file.h).
    if (colon != std::string::npos && colon > 0 && !fs::exists(spec.substr(0, colon), ec)) {
      return tools::unreachable_file(spec.substr(0, colon)) + " (in '" + spec + "')";
    }
    return tools::unreachable_file(spec);
  }
  file_bytes_ = fs::file_size(spec, ec);
  if (ec) return spec + ": cannot read: " + ec.message();
  if (file_bytes_ == 0) return spec + ": the file is empty";
  if (file_bytes_ % hal::kBlockSize == 0) {
    if (file_.open(spec, false) != Status::kOk) return file_.error();
    if (!looks_like_volume(file_)) {
      device_ = &file_;
      return {};
    }
    file_.close();
    disk_ = std::make_unique<Disk>();
    std::string error = disk_->open(spec, false);
    if (!error.empty()) return error;
    if (default_name == nullptr) {
      return spec + " is a disk image: name the volume file as " + spec +
             ":NAME (the volume has: " + disk_->file_names() + ")";
    }
    error = disk_->open_file(default_name, &region_);
    if (!error.empty()) return error;
    name_ = spec + ":" + default_name;
    device_ = &region_;
    return {};
  }
  // Cut short: read it padded with zeros, so everything before the cut can still be read.
  if (file_bytes_ > kMaxMemoryFile) {
    return spec + ": " + std::to_string(file_bytes_) +
           " bytes is not a whole number of 512-byte blocks (the file is truncated)";
  }
  std::ifstream in(spec, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return spec + ": read failed";
  memory_ = std::make_unique<MemoryBlockDevice>(std::move(bytes));
  if (looks_like_volume(*memory_)) {
    return spec + ": a disk image must be a non-zero whole number of 512-byte blocks (it has " +
           std::to_string(file_bytes_) + " bytes)";
  }
  truncated_ = true;
  device_ = memory_.get();
  return {};
}

std::string log_open_problem(hal::BlockDevice& device, const std::string& what,
                             storage::LogProblem problem) {
  uint8_t block[hal::kBlockSize];
  if (problem == storage::LogProblem::kWrongKind && device.read(0, 1, block) == Status::kOk &&
      std::all_of(block, block + hal::kBlockSize, [](uint8_t b) { return b == 0; })) {
    return "empty: block 0 is all zeros (no " + what + " written yet)";
  }
  return "not a readable " + what + ": " + storage::log_problem_text(problem);
}

bool warn_if_truncated(const LogSource& source) {
  if (!source.truncated()) return false;
  warn(source.name() + ": the file is truncated (" + std::to_string(source.file_bytes()) +
       " bytes, not a whole number of 512-byte blocks)");
  return true;
}

std::string open_dream(LogSource& source, storage::DreamReader& reader,
                       std::vector<uint8_t>& buffer) {
  buffer.resize(storage::kDreamRecordMax);
  storage::DreamProblem problem = storage::DreamProblem::kNone;
  if (reader.open(source.device(), Span<uint8_t>(buffer.data(), buffer.size()), &problem) ==
      Status::kOk) {
    return "";
  }
  return source.name() + ": " +
         (problem == storage::DreamProblem::kLog
              ? log_open_problem(source.device(), "dream recording", reader.log_problem())
              : "not a usable dream recording: " +
                    std::string(storage::dream_problem_text(problem)));
}

LogScan scan_log(hal::BlockDevice& device, const storage::LogKind& kind) {
  LogScan scan;
  std::vector<uint8_t> buffer(storage::kMaxRecordBytes);
  storage::LogReader reader;
  storage::LogProblem problem = storage::LogProblem::kNone;
  const Status open = reader.open(device, kind, nullptr, 0, nullptr,
                                  Span<uint8_t>(buffer.data(), buffer.size()), &problem);
  if (open != Status::kOk) {
    scan.error = storage::log_problem_text(problem);
    return scan;
  }
  scan.session = reader.session();
  scan.damaged_slot = storage::damaged_commit_slot(device, kind);
  for (;;) {
    storage::RecordView record;
    const Status s = reader.next(&record);
    if (s == Status::kOk) {
      ++scan.records;
    } else if (s == Status::kDataLoss) {
      ++scan.damaged;
    } else if (s == Status::kResourceExhausted) {
      ++scan.too_large;
    } else if (s == Status::kOutOfRange) {
      scan.end = reader.end_problem();
      scan.end_offset = reader.problem_offset();
      break;
    } else {
      scan.end = storage::LogProblem::kDeviceError;
      scan.end_offset = reader.problem_offset();
      break;
    }
  }
  return scan;
}

std::string describe_log_end(const LogScan& scan) {
  switch (scan.end) {
    case storage::LogProblem::kEndClean:
      return "ends cleanly";
    case storage::LogProblem::kEndDamagedTail:
      return "damaged tail at byte " + std::to_string(scan.end_offset) +
             " (a record cut by a power loss)";
    case storage::LogProblem::kDeviceError:
      return "read error at byte " + std::to_string(scan.end_offset);
    default:
      return storage::log_problem_text(scan.end);
  }
}

}  // namespace seqslam::cli
