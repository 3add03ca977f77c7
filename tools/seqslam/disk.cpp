// seqslam disk create|list|export|import|map: disk images holding a seqslam volume (the SD
// card); `disk map` reads the firmware's explore outputs back (map tiles and pose graph).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "cli_common.h"
#include "seqslam/preprocess.h"
#include "seqslam/storage/bytes.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/map_store.h"
#include "seqslam/storage/query_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/state_file.h"
#include "seqslam_tools/graph_csv.h"
#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/output_file.h"

namespace seqslam::cli {

namespace {

namespace fs = std::filesystem;

// Blocks moved per device read or write when copying.
constexpr uint32_t kChunkBlocks = 128;

struct FileSpec {
  std::string name;
  uint64_t bytes = 0;
  bool has_size = false;  // else: the size of `from`
  std::string from;
};

std::string check_name(const std::string& name) {
  const bool chars_ok = std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
  if (name.empty() || name.size() >= storage::kVolumeNameBytes || !chars_ok) {
    return "'" + name + "' is not a valid volume file name (1..15 characters of A-Z a-z 0-9 . _ -)";
  }
  return {};
}

// NAME:SIZE[:FROM]; SIZE may be empty when FROM is given (then FROM's size).
std::string parse_file_spec(const std::string& text, FileSpec* out) {
  const size_t c1 = text.find(':');
  if (c1 == std::string::npos) return "'" + text + "' is not NAME:SIZE[:FROM]";
  FileSpec f;
  f.name = text.substr(0, c1);
  std::string error = check_name(f.name);
  if (!error.empty()) return error;
  const size_t c2 = text.find(':', c1 + 1);
  const std::string size =
      text.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1);
  if (c2 != std::string::npos) {
    f.from = text.substr(c2 + 1);
    if (f.from.empty()) return "'" + text + "': FROM (after the second ':') is empty";
  }
  if (size.empty()) {
    if (f.from.empty()) return "'" + text + "': SIZE is missing (it may be empty only with FROM)";
  } else {
    error = parse_byte_size(size, &f.bytes);
    if (!error.empty()) return "'" + text + "': " + error;
    if (f.bytes == 0) return "'" + text + "': SIZE must be at least 1 byte";
    f.has_size = true;
  }
  *out = f;
  return {};
}

std::string bytes_text(uint64_t blocks) {
  return std::to_string(blocks) + " blocks = " + std::to_string(blocks * hal::kBlockSize) +
         " bytes";
}

// Copies the host file `path` into `device` from block 0. The device must be large enough
// (the caller checks). Bytes of the last, partly filled block after the file's end keep
// their old contents. `device_zeroed`: the device holds zeros (a new image), so chunks of
// zeros are not written (a new image stays sparse). Returns an empty string or a message.
std::string copy_into(hal::BlockDevice& device, const std::string& path, const std::string& what,
                      const hal::FileBlockDevice& disk, bool device_zeroed) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return path + ": cannot open: " + std::strerror(errno);
  std::vector<uint8_t> chunk(static_cast<size_t>(kChunkBlocks) * hal::kBlockSize);
  uint32_t block = 0;
  for (;;) {
    in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size()));
    const size_t n = static_cast<size_t>(in.gcount());
    if (n == 0) break;
    const uint32_t blocks = static_cast<uint32_t>(blocks_for(n));
    if (device_zeroed && std::all_of(chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n),
                                     [](uint8_t b) { return b == 0; })) {
      block += blocks;
      if (n < chunk.size()) break;
      continue;
    }
    if (n % hal::kBlockSize != 0) {
      uint8_t last[hal::kBlockSize];
      if (device.read(block + blocks - 1, 1, last) != Status::kOk) {
        return what + ": read failed: " + disk.error();
      }
      const size_t keep = n % hal::kBlockSize;
      std::copy(last + keep, last + hal::kBlockSize,
                chunk.begin() + static_cast<std::ptrdiff_t>(n));
    }
    if (device.write(block, blocks, chunk.data()) != Status::kOk) {
      return what + ": write failed: " + disk.error();
    }
    block += blocks;
    if (n < chunk.size()) break;
  }
  if (in.bad()) return path + ": read failed";
  if (device.sync() != Status::kOk) return what + ": flush failed: " + disk.error();
  return {};
}

// --- disk create ------------------------------------------------------------------------

struct CreateOptions {
  std::string image;
  std::string size;
  std::vector<std::string> files;
};

int run_create(const CreateOptions& o) {
  std::vector<FileSpec> specs;
  std::set<std::string> names;
  tools::InputFiles inputs;
  for (const std::string& text : o.files) {
    FileSpec f;
    const std::string error = parse_file_spec(text, &f);
    if (!error.empty()) return usage_error("--file: " + error);
    if (!names.insert(f.name).second) {
      return usage_error("--file: volume file '" + f.name + "' is given twice");
    }
    if (!f.from.empty()) inputs.add(f.from);
    specs.push_back(f);
  }
  if (const std::string clash = inputs.clash(o.image); !clash.empty()) return usage_error(clash);
  if (specs.size() > storage::kVolumeMaxFiles) {
    return usage_error("--file: a volume holds at most " +
                       std::to_string(storage::kVolumeMaxFiles) + " files (" +
                       std::to_string(specs.size()) + " given)");
  }

  std::vector<storage::VolumeFile> table;
  uint64_t needed = 1;  // the file table
  for (FileSpec& f : specs) {
    if (!f.from.empty()) {
      std::error_code ec;
      if (std::string why = tools::check_regular_input(f.from); !why.empty()) return fail(why);
      const uint64_t from_bytes = fs::file_size(f.from, ec);
      if (ec) return fail(f.from + ": cannot read: " + ec.message());
      if (!f.has_size) {
        if (from_bytes == 0) {
          return fail(f.from + ": the file is empty; give volume file '" + f.name + "' a SIZE");
        }
        f.bytes = from_bytes;
      } else if (from_bytes > blocks_for(f.bytes) * hal::kBlockSize) {
        return fail(f.from + " (" + std::to_string(from_bytes) +
                    " bytes) does not fit in volume file '" + f.name + "' (" +
                    bytes_text(blocks_for(f.bytes)) + ")");
      }
    }
    const uint64_t blocks = blocks_for(f.bytes);
    if (blocks > UINT32_MAX)
      return usage_error("--file: volume file '" + f.name + "' is too large");
    storage::VolumeFile entry;
    std::copy(f.name.begin(), f.name.end(), entry.name);
    entry.block_count = static_cast<uint32_t>(blocks);
    table.push_back(entry);
    needed += blocks;
  }

  uint64_t disk_blocks = needed;
  if (!o.size.empty()) {
    uint64_t bytes = 0;
    const std::string error = parse_byte_size(o.size, &bytes);
    if (!error.empty()) return usage_error("--size: " + error);
    disk_blocks = blocks_for(bytes);
    if (disk_blocks < needed) {
      return usage_error("--size " + o.size + " gives " + bytes_text(disk_blocks) +
                         ", but the file table and the files need " + bytes_text(needed));
    }
  }
  if (disk_blocks > UINT32_MAX) {
    return usage_error("a disk image holds at most 4294967295 blocks (2 TiB); " +
                       bytes_text(disk_blocks) + " requested");
  }

  // A temporary file renamed over IMAGE at the end (a device is written in place): a failed
  // or interrupted create leaves no half-made image, and never removes what IMAGE was.
  tools::OutputPath out;
  if (const std::string error = out.open(o.image); !error.empty()) return fail(error);
  hal::FileBlockDevice device;
  auto give_up = [&](const std::string& message) {
    const std::string shown = out.shown(message);  // IMAGE, not the temporary's name
    device.close();
    out.discard();
    return fail(shown);
  };
  if (device.create(out.write_path(), static_cast<uint32_t>(disk_blocks)) != Status::kOk) {
    return give_up(device.error());
  }
  storage::VolumeProblem problem = storage::VolumeProblem::kNone;
  if (storage::Volume::format(device, table.data(), static_cast<uint32_t>(table.size()),
                              &problem) != Status::kOk) {
    return give_up(o.image +
                   ": cannot format the volume: " + storage::volume_problem_text(problem) +
                   (device.error().empty() ? "" : " (" + device.error() + ")"));
  }
  storage::Volume volume;
  if (volume.mount(device, &problem) != Status::kOk) {
    return give_up(o.image +
                   ": cannot mount the new volume: " + storage::volume_problem_text(problem) +
                   (device.error().empty() ? "" : " (" + device.error() + ")"));
  }
  for (const FileSpec& f : specs) {
    if (f.from.empty()) continue;
    storage::Region region;
    if (volume.open(f.name.c_str(), &region) != Status::kOk) {
      return give_up(o.image + ": volume file '" + f.name + "' missing after formatting");
    }
    const std::string error = copy_into(region, f.from, o.image + ":" + f.name, device, true);
    if (!error.empty()) return give_up(error);
  }
  if (device.sync() != Status::kOk) return give_up(device.error());
  device.close();
  if (const std::string error = out.commit(); !error.empty()) return fail(error);
  std::printf("%s: %llu blocks (%llu bytes), %zu file%s, %llu blocks unused\n", o.image.c_str(),
              static_cast<unsigned long long>(disk_blocks),
              static_cast<unsigned long long>(disk_blocks * hal::kBlockSize), specs.size(),
              specs.size() == 1 ? "" : "s", static_cast<unsigned long long>(disk_blocks - needed));
  return kExitOk;
}

// --- disk list --------------------------------------------------------------------------

bool same_magic(const uint8_t* block, const uint8_t* magic) {
  return std::equal(magic, magic + 8, block);
}

std::string log_counts(const LogScan& scan, const char* noun) {
  std::string s = "session " + std::to_string(scan.session) + ", " + std::to_string(scan.records) +
                  " " + noun + ", " + describe_log_end(scan);
  if (scan.damaged > 0) s += ", " + std::to_string(scan.damaged) + " damaged records skipped";
  if (scan.too_large > 0) s += ", " + std::to_string(scan.too_large) + " oversized records skipped";
  if (scan.damaged_slot != 0) {
    s += ", commit slot " + std::to_string(scan.damaged_slot) + " damaged (zeros or another " +
         "session's)";
  }
  return s;
}

std::string describe_dream(hal::BlockDevice& device) {
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  storage::DreamProblem problem = storage::DreamProblem::kNone;
  if (reader.open(device, Span<uint8_t>(buffer.data(), buffer.size()), &problem) != Status::kOk) {
    const std::string why = problem == storage::DreamProblem::kLog
                                ? storage::log_problem_text(reader.log_problem())
                                : storage::dream_problem_text(problem);
    return "dream recording, unreadable: " + why;
  }
  const storage::DreamHeader& h = reader.header();
  const LogScan scan = scan_log(device, storage::kDreamKind);
  return std::string("dream recording (") +
         (h.variant == storage::DreamVariant::kFull ? "full" : "reduced") + ", " +
         std::to_string(h.mapping.xmax) + "x" + std::to_string(h.mapping.ymax) +
         (h.colour == storage::ColourFormat::kYuv422 ? ", colour" : "") +
         "): " + log_counts(scan, "records");
}

std::string describe_library(hal::BlockDevice& device) {
  uint8_t payload[storage::kLogHeaderPayloadMax] = {};
  uint32_t size = 0;
  uint8_t none[1];
  storage::LogReader reader;
  storage::LogProblem problem = storage::LogProblem::kNone;
  if (reader.open(device, storage::kLibraryKind, payload, sizeof payload, &size,
                  Span<uint8_t>(none, 1), &problem) != Status::kOk) {
    return std::string("library metadata, unreadable: ") + storage::log_problem_text(problem);
  }
  // Header payload: u16 width, u16 height, u8 preprocessing method, ...
  storage::ByteReader r(payload, sizeof payload);
  const unsigned width = r.u16();
  const unsigned height = r.u16();
  const Preprocessing method = static_cast<Preprocessing>(r.u8());
  const LogScan scan = scan_log(device, storage::kLibraryKind);
  return "library metadata (" + std::to_string(width) + "x" + std::to_string(height) + ", " +
         preprocessing_name(method) + "): " + log_counts(scan, "places");
}

std::string describe_library_images(hal::BlockDevice& device, const uint8_t* block) {
  // Header block: magic, u16 version, u16 reserved, u32 session, u16 width, u16 height; CRC
  // in the last 4 bytes.
  storage::ByteReader crc(block + 508, 4);
  if (crc.u32() != storage::crc32(block, 508)) return "library images, damaged header (checksum)";
  storage::ByteReader r(block, 508);
  r.skip(12);
  const uint32_t session = r.u32();
  const unsigned width = r.u16();
  const unsigned height = r.u16();
  const uint64_t pixels = static_cast<uint64_t>(width) * height;
  const uint64_t room = pixels == 0 ? 0 : (device.capacity_bytes() - hal::kBlockSize) / pixels;
  return "library images (" + std::to_string(width) + "x" + std::to_string(height) + "): session " +
         std::to_string(session) + ", room for " + std::to_string(room) + " images";
}

std::string describe_config(hal::BlockDevice& device) {
  storage::RunConfig config;
  storage::LogProblem problem = storage::LogProblem::kNone;
  const Status s = storage::read_run_config(device, &config, &problem);
  if (s != Status::kOk) {
    return std::string("run config, unusable: ") +
           (problem != storage::LogProblem::kNone ? storage::log_problem_text(problem)
                                                  : "damaged or invalid settings") +
           (problem == storage::LogProblem::kVersion
                ? " (not version " + std::to_string(storage::kRunConfigKind.version) +
                      ": write it again with seqslam config write)"
                : std::string());
  }
  // The summary names the route search's settings when they are not the defaults.
  return "run config: " + run_config_summary(config);
}

// A card's map tiles file opened read-only (MapStore) with an index for every tile of the
// largest grid the format allows, as `disk list` and `disk map` read it.
struct ReadOnlyMap {
  std::vector<storage::MapTileIndexEntry> index = std::vector<storage::MapTileIndexEntry>(
      static_cast<size_t>(kMaxGridSide / kGridTileSide) * (kMaxGridSide / kGridTileSide));
  std::vector<uint8_t> buffer = std::vector<uint8_t>(storage::kMapReadBuffer);
  std::unique_ptr<storage::MapStore> store = std::make_unique<storage::MapStore>();
  GridConfig grid;

  Status open(hal::BlockDevice& device, storage::MapProblem* problem) {
    return store->open(device, Span<storage::MapTileIndexEntry>(index.data(), index.size()),
                       Span<uint8_t>(buffer.data(), buffer.size()), &grid, problem);
  }
};

// The explore mode's occupancy map: its grid and the tiles saved (MapStore, read-only), and
// the log's records (every save of a tile is one).
std::string describe_map(hal::BlockDevice& device) {
  const LogScan scan = scan_log(device, storage::kMapKind);
  if (!scan.error.empty()) return "map tiles, unreadable: " + scan.error;
  ReadOnlyMap map;
  storage::MapProblem mp = storage::MapProblem::kNone;
  if (map.open(device, &mp) != Status::kOk) {
    return std::string("map tiles, unusable: ") + storage::map_problem_text(mp) + "; " +
           log_counts(scan, "tile records");
  }
  const GridConfig& gc = map.grid;
  return "map tiles (" + std::to_string(gc.width) + "x" + std::to_string(gc.height) + " cells of " +
         std::to_string(gc.cell_mm) + " mm): " + std::to_string(map.store->tile_count()) +
         " tiles; " + log_counts(scan, "tile records");
}

// The explore mode's pose graph (two slots, the newest complete one read; map_store.h).
std::string describe_graph(hal::BlockDevice& device) {
  storage::GraphReader reader;
  storage::MapProblem mp = storage::MapProblem::kNone;
  if (reader.open(device, &mp) != Status::kOk) {
    return std::string("pose graph, unusable: ") + storage::map_problem_text(mp) +
           (mp == storage::MapProblem::kLog
                ? std::string(" (") + storage::log_problem_text(reader.log_problem()) + ")"
                : std::string());
  }
  const storage::GraphFileHeader& h = reader.header();
  return "pose graph: " + std::to_string(h.nodes) + " nodes, " + std::to_string(h.edges) +
         " edges (" + std::to_string(h.closures) + " loop closures), " +
         (h.converged ? "optimised to convergence" : "NOT converged") + ", slot " +
         std::to_string(reader.slot() + 1) + " of 2";
}

std::string describe_contents(const std::string& name, hal::BlockDevice& device,
                              const hal::FileBlockDevice& disk) {
  uint8_t block[hal::kBlockSize];
  if (device.read(0, 1, block) != Status::kOk) return "unreadable: " + disk.error();
  // The graph's newest copy may be in the file's second half: known by name (issue 34: the
  // explore files were listed as "unknown data").
  if (name == storage::kGraphFile || same_magic(block, storage::kGraphKind.magic)) {
    return describe_graph(device);
  }
  if (std::all_of(block, block + hal::kBlockSize, [](uint8_t b) { return b == 0; })) {
    return "empty (zeros)";
  }
  if (same_magic(block, storage::kMapKind.magic)) return describe_map(device);
  if (same_magic(block, storage::kStateKind.magic)) {
    const LogScan scan = scan_log(device, storage::kStateKind);
    if (!scan.error.empty()) return "saved run state, unreadable: " + scan.error;
    return "saved run state (explore, to continue): " + log_counts(scan, "records");
  }
  // The query history has no header: scratch the firmware overwrites every step.
  if (name == storage::kQueriesFile) return "query history (scratch, no header)";
  if (same_magic(block, storage::kDreamKind.magic)) return describe_dream(device);
  if (same_magic(block, storage::kLibraryKind.magic)) return describe_library(device);
  if (same_magic(block, storage::kLibraryImagesMagic))
    return describe_library_images(device, block);
  if (same_magic(block, storage::kRunConfigKind.magic)) return describe_config(device);
  if (same_magic(block, storage::kResultsKind.magic)) {
    const LogScan scan = scan_log(device, storage::kResultsKind);
    if (!scan.error.empty()) return "results, unreadable: " + scan.error;
    return "results: " + log_counts(scan, "results");
  }
  if (looks_like_volume(device)) return "a volume file table (a disk image inside?)";
  return "unknown data";
}

struct ImageOptions {
  std::string image;
};

int run_list(const ImageOptions& o) {
  Disk disk;
  const std::string error = disk.open(o.image, false);
  if (!error.empty()) return fail(error);
  const storage::Volume& v = disk.volume();
  uint64_t used = 1;
  for (uint32_t i = 0; i < v.file_count(); ++i)
    used += v.file(i).block_count;
  const uint64_t blocks = disk.device().block_count();
  std::printf("%s: %llu blocks (%llu bytes), %u file%s, %llu blocks unused\n", o.image.c_str(),
              static_cast<unsigned long long>(blocks),
              static_cast<unsigned long long>(blocks * hal::kBlockSize), v.file_count(),
              v.file_count() == 1 ? "" : "s",
              static_cast<unsigned long long>(blocks >= used ? blocks - used : 0));
  std::printf("%-15s %10s %10s %12s  %s\n", "name", "first", "blocks", "bytes", "contents");
  for (uint32_t i = 0; i < v.file_count(); ++i) {
    const storage::VolumeFile& f = v.file(i);
    storage::Region region(disk.device(), f.first_block, f.block_count);
    const std::string contents = describe_contents(f.name, region, disk.device());
    std::printf("%-15s %10u %10u %12llu  %s\n", f.name, f.first_block, f.block_count,
                static_cast<unsigned long long>(f.block_count) * hal::kBlockSize, contents.c_str());
  }
  return kExitOk;
}

// --- disk export / import ---------------------------------------------------------------

struct TransferOptions {
  std::string image;
  std::string name;
  std::string path;
};

int run_export(const TransferOptions& o) {
  tools::InputFiles inputs;
  inputs.add(o.image);
  if (const std::string clash = inputs.clash(o.path); !clash.empty()) return usage_error(clash);
  Disk disk;
  std::string error = disk.open(o.image, false);
  storage::Region region;
  if (error.empty()) error = disk.open_file(o.name, &region);
  if (!error.empty()) return fail(error);
  tools::OutputFile out;
  error = out.open(o.path);
  if (!error.empty()) return fail(error);
  std::vector<uint8_t> chunk(static_cast<size_t>(kChunkBlocks) * hal::kBlockSize);
  const uint32_t total = region.block_count();
  for (uint32_t at = 0; at < total;) {
    const uint32_t n = std::min(kChunkBlocks, total - at);
    if (region.read(at, n, chunk.data()) != Status::kOk) {
      return fail(o.image + ":" + o.name + ": read failed at block " + std::to_string(at) + ": " +
                  disk.device().error());
    }
    if (!out.write(chunk.data(), static_cast<size_t>(n) * hal::kBlockSize)) {
      return fail(out.error() + " (at byte " + std::to_string(uint64_t{at} * hal::kBlockSize) +
                  ")");
    }
    at += n;
  }
  error = out.commit();
  if (!error.empty()) return fail(error);
  std::printf("%s: %llu bytes (%u blocks) from %s:%s\n", o.path.c_str(),
              static_cast<unsigned long long>(region.capacity_bytes()), total, o.image.c_str(),
              o.name.c_str());
  return kExitOk;
}

int run_import(const TransferOptions& o) {
  tools::InputFiles inputs;
  inputs.add(o.path);
  if (const std::string clash = inputs.clash(o.image); !clash.empty()) return usage_error(clash);
  std::error_code ec;
  if (std::string why = tools::check_regular_input(o.path); !why.empty()) return fail(why);
  const uint64_t bytes = fs::file_size(o.path, ec);
  if (ec) return fail(o.path + ": cannot read: " + ec.message());
  Disk disk;
  std::string error = disk.open(o.image, true);
  storage::Region region;
  if (error.empty()) error = disk.open_file(o.name, &region);
  if (!error.empty()) return fail(error);
  if (bytes > region.capacity_bytes()) {
    return fail(o.path + " (" + std::to_string(bytes) + " bytes) does not fit in volume file '" +
                o.name + "' of " + o.image + " (" + bytes_text(region.block_count()) + ")");
  }
  if (error = disk.check_write_limit(o.name, bytes); !error.empty()) return fail(error);
  error = copy_into(region, o.path, o.image + ":" + o.name, disk.device(), false);
  if (!error.empty()) return fail(error);
  std::printf("%s:%s: %llu bytes from %s (%llu bytes of the file left as they were)\n",
              o.image.c_str(), o.name.c_str(), static_cast<unsigned long long>(bytes),
              o.path.c_str(), static_cast<unsigned long long>(region.capacity_bytes() - bytes));
  return kExitOk;
}

// --- disk map -----------------------------------------------------------------------------

struct MapOptions {
  std::string image;
  std::string out;
};

// The map tiles file as an OccupancyGrid over a read-only MapStore, exported as map_server
// PGM + YAML.
std::string export_map(Disk& disk, const std::string& stem, std::string* summary) {
  storage::Region region;
  std::string error = disk.open_file(storage::kMapFile, &region);
  if (!error.empty()) return error;
  const std::string where = disk.path() + ":" + storage::kMapFile;
  ReadOnlyMap tiles;
  storage::MapProblem mp = storage::MapProblem::kNone;
  const Status s = tiles.open(region, &mp);
  const std::unique_ptr<storage::MapStore>& store = tiles.store;
  const GridConfig& gc = tiles.grid;
  if (s != Status::kOk) {
    return where + ": not a usable map: " +
           (mp == storage::MapProblem::kLog || mp == storage::MapProblem::kDamaged
                ? std::string(storage::map_problem_text(mp)) + " (" +
                      storage::log_problem_text(store->log_problem()) + ")"
                : std::string(storage::map_problem_text(mp))) +
           " (" + status_name(s) + ")";
  }
  auto ram = std::make_unique<OccupancyGridStorage<4>>();
  OccupancyGrid grid;
  GridIssue issue = GridIssue::kNone;
  if (grid.configure(gc, ram->buffers(), *store, &issue) != Status::kOk) {
    return where + ": grid: " + grid_issue_text(issue);
  }
  auto map = tools::grid_map(grid);
  if (!map) return where + ": " + map.error();
  if (!tools::save_map(map.value(), stem, &error)) return error;
  uint64_t free_cells = 0, occupied = 0;
  for (const CellState c : map.value().cells) {
    free_cells += c == CellState::kFree ? 1 : 0;
    occupied += c == CellState::kOccupied ? 1 : 0;
  }
  *summary = std::to_string(store->tile_count()) + " tiles, " + std::to_string(gc.width) + "x" +
             std::to_string(gc.height) + " cells of " + std::to_string(gc.cell_mm) + " mm, " +
             std::to_string(free_cells) + " free, " + std::to_string(occupied) + " occupied";
  return {};
}

// The graph file as two CSV files: nodes (index, place, pose) and edges.
std::string export_graph(Disk& disk, const std::string& out_dir, std::string* summary) {
  storage::Region region;
  std::string error = disk.open_file(storage::kGraphFile, &region);
  if (!error.empty()) return error;
  const std::string where = disk.path() + ":" + storage::kGraphFile;
  storage::GraphReader reader;
  auto problem = [&](Status s) {
    const storage::MapProblem mp = reader.problem();
    return where + ": not a usable graph: " + storage::map_problem_text(mp) +
           (mp == storage::MapProblem::kLog || mp == storage::MapProblem::kDamaged
                ? std::string(" (") + storage::log_problem_text(reader.log_problem()) + ")"
                : std::string()) +
           " (" + status_name(s) + ")";
  };
  storage::MapProblem open_problem = storage::MapProblem::kNone;
  storage::LogProblem lp = storage::LogProblem::kNone;
  Status s = reader.open(region, &open_problem);
  if (s != Status::kOk) {
    // The header's own log problem (kind, version, checksum) when the log could not open.
    storage::LogReader probe;
    uint8_t none[1];
    (void)probe.open(region, storage::kGraphKind, nullptr, 0, nullptr, Span<uint8_t>(none, 1), &lp);
    return where + ": not a usable graph: " + storage::map_problem_text(open_problem) +
           (open_problem == storage::MapProblem::kLog
                ? std::string(" (") + storage::log_problem_text(lp) + ")"
                : std::string()) +
           " (" + status_name(s) + ")";
  }
  std::string nodes_csv = tools::kGraphNodesHeader;
  for (uint32_t i = 0; i < reader.header().nodes; ++i) {
    storage::GraphFileNode n;
    s = reader.next_node(&n);
    if (s != Status::kOk) return problem(s);
    nodes_csv += tools::graph_node_line(n.index, n.place, n.pose);
  }
  std::string edges_csv = tools::kGraphEdgesHeader;
  for (uint32_t i = 0; i < reader.header().edges; ++i) {
    PoseGraphEdge e;
    bool closure = false;
    s = reader.next_edge(&e, &closure);
    if (s != Status::kOk) return problem(s);
    edges_csv += tools::graph_edge_line(e, closure);
  }
  s = reader.finish();
  if (s != Status::kOk) return problem(s);
  struct Output {
    const char* name;
    const std::string* text;
  };
  const Output outputs[] = {{"graph_nodes.csv", &nodes_csv}, {"graph_edges.csv", &edges_csv}};
  for (const Output& output : outputs) {
    error = tools::write_output((fs::path(out_dir) / output.name).string(), *output.text);
    if (!error.empty()) return error;
  }
  *summary = std::to_string(reader.header().nodes) + " nodes, " +
             std::to_string(reader.header().edges) + " edges (" +
             std::to_string(reader.header().closures) + " loop closures), " +
             (reader.header().converged ? "optimised to convergence" : "NOT converged");
  return {};
}

int run_map(const MapOptions& o) {
  const std::string stem = (fs::path(o.out) / "map").string();
  tools::InputFiles inputs;
  inputs.add(o.image);
  for (const char* name : {"map.pgm", "map.yaml", "graph_nodes.csv", "graph_edges.csv"}) {
    const std::string clash = inputs.clash((fs::path(o.out) / name).string());
    if (!clash.empty()) return usage_error(clash);
  }
  Disk disk;
  std::string error = disk.open(o.image, false);
  if (!error.empty()) return fail(error);
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) return fail(o.out + ": cannot create the directory: " + ec.message());
  std::string map_summary, graph_summary;
  error = export_map(disk, stem, &map_summary);
  if (!error.empty()) return fail(error);
  error = export_graph(disk, o.out, &graph_summary);
  if (!error.empty()) return fail(error);
  std::printf("%s.pgm, %s.yaml: %s\n", stem.c_str(), stem.c_str(), map_summary.c_str());
  std::printf("%s, %s: %s\n", (fs::path(o.out) / "graph_nodes.csv").string().c_str(),
              (fs::path(o.out) / "graph_edges.csv").string().c_str(), graph_summary.c_str());
  return kExitOk;
}

}  // namespace

void add_disk_commands(CLI::App& app, Command* chosen) {
  CLI::App* disk = app.add_subcommand(
      "disk", "Disk images of the robot's SD card: a volume of named, fixed-size files");
  disk->require_subcommand(1);

  auto create_opts = std::make_shared<CreateOptions>();
  CLI::App* create = disk->add_subcommand(
      "create", "Create a disk image and format a volume with the given files (in order)");
  create->add_option("IMAGE", create_opts->image, "Disk image file to create (overwritten)")
      ->required();
  create
      ->add_option("--size", create_opts->size,
                   "Size of the image in bytes; suffix K, M or G (1024-based); rounded up to "
                   "whole 512-byte blocks. Default: just big enough for the files")
      ->type_name("SIZE")
      ->check(CLI::Validator(
          [](std::string& s) {
            uint64_t b = 0;
            return parse_byte_size(s, &b);
          },
          ""));
  create
      ->add_option("--file", create_opts->files,
                   "A volume file NAME (1..15 of A-Z a-z 0-9 . _ -) of SIZE bytes (suffix K, M, "
                   "G; rounded up to 512-byte blocks), optionally filled with the bytes of the "
                   "host file FROM (it must fit). SIZE may be empty with FROM (NAME::FROM): "
                   "FROM's size. Repeat for more files (at most 15)")
      ->type_name("NAME:SIZE[:FROM]")
      ->required()
      ->check(CLI::Validator(
          [](std::string& s) {
            FileSpec f;
            return parse_file_spec(s, &f);
          },
          ""));
  create->callback(
      [chosen, create_opts] { *chosen = [create_opts] { return run_create(*create_opts); }; });

  auto list_opts = std::make_shared<ImageOptions>();
  CLI::App* list = disk->add_subcommand(
      "list",
      "List the volume's files: name, first block, blocks, bytes and what each holds "
      "(for record logs: session, complete records, how the log ends)");
  list->add_option("IMAGE", list_opts->image, "Disk image file")->required();
  list->callback([chosen, list_opts] { *chosen = [list_opts] { return run_list(*list_opts); }; });

  auto export_opts = std::make_shared<TransferOptions>();
  CLI::App* exp = disk->add_subcommand(
      "export", "Copy a volume file (its whole region, every block) to a host file");
  exp->add_option("IMAGE", export_opts->image, "Disk image file")->required();
  exp->add_option("NAME", export_opts->name, "Volume file name")->required();
  exp->add_option("OUT", export_opts->path, "Host file to write (overwritten)")->required();
  exp->callback(
      [chosen, export_opts] { *chosen = [export_opts] { return run_export(*export_opts); }; });

  auto import_opts = std::make_shared<TransferOptions>();
  CLI::App* imp = disk->add_subcommand(
      "import",
      "Copy a host file into a volume file from its first byte (it must fit; the "
      "rest of the volume file is left as it is)");
  imp->add_option("IMAGE", import_opts->image, "Disk image file (modified)")->required();
  imp->add_option("NAME", import_opts->name, "Volume file name")->required();
  imp->add_option("IN", import_opts->path, "Host file to copy")->required();
  imp->callback(
      [chosen, import_opts] { *chosen = [import_opts] { return run_import(*import_opts); }; });

  auto map_opts = std::make_shared<MapOptions>();
  CLI::App* map = disk->add_subcommand(
      "map",
      "Read the firmware's explore outputs back: volume file 'map' as a ROS map_server map "
      "(OUT/map.pgm, OUT/map.yaml) and 'graph' as OUT/graph_nodes.csv and "
      "OUT/graph_edges.csv. A damaged, cut or foreign file is refused with the reason");
  map->add_option("IMAGE", map_opts->image, "Disk image file")->required();
  map->add_option("--out", map_opts->out, "Output directory (created)")->required();
  map->callback([chosen, map_opts] { *chosen = [map_opts] { return run_map(*map_opts); }; });
}

}  // namespace seqslam::cli
