#include "card_checks.h"

#include <algorithm>
#include <string>
#include <vector>

#include "seqslam/route_search.h"
#include "seqslam/session/profile.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/query_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/state_file.h"
#include "seqslam_tools/dream_images.h"

namespace seqslam::cli {

namespace {

// What the card holds in one of its log files: the records of a readable log, or why not.
struct LogCount {
  bool present = false;  // the volume has the file
  bool readable = false;
  uint32_t records = 0;
  std::string why;  // not readable: why ("empty (zeros)", the log problem)
};

bool all_zero(hal::BlockDevice& device) {
  uint8_t block[hal::kBlockSize];
  return device.read(0, 1, block) == Status::kOk &&
         std::all_of(block, block + hal::kBlockSize, [](uint8_t b) { return b == 0; });
}

LogCount count_log(Disk& disk, const char* name, const storage::LogKind& kind) {
  LogCount out;
  storage::Region region;
  if (disk.volume().open(name, &region) != Status::kOk) {
    out.why = "the card has no '" + std::string(name) + "' file";
    return out;
  }
  out.present = true;
  if (all_zero(region)) {
    out.why = disk.path() + ":" + name + " is empty (zeros)";
    return out;
  }
  const LogScan scan = scan_log(region, kind);
  if (!scan.error.empty()) {
    out.why = disk.path() + ":" + name + " is not readable: " + scan.error;
    return out;
  }
  out.readable = true;
  out.records = scan.records;
  return out;
}

// Steps the firmware's query history keeps in the card's `queries` file (one 512-byte slot a
// step for every image size, at most profile::kQuerySteps; storage/query_store.h); 0 without it.
uint32_t query_steps(Disk& disk, bool* present) {
  storage::Region region;
  *present = disk.volume().open(storage::kQueriesFile, &region) == Status::kOk;
  return *present ? std::min(region.block_count(), profile::kQuerySteps) : 0u;
}

struct RunUse {
  bool teach, repeat, record, explore, resume;
  bool route;          // the route search localises (repeat, diagonal matcher, not explore)
  bool needs_queries;  // ... or the heuristic reads back its first images (a scan budget)
};

RunUse run_use(const storage::RunConfig& c) {
  RunUse u{};
  u.teach = (c.modes & storage::kModeTeach) != 0;
  u.repeat = (c.modes & storage::kModeRepeat) != 0;
  u.record = (c.modes & storage::kModeRecord) != 0;
  u.explore = (c.modes & storage::kModeExplore) != 0;
  u.resume = (c.modes & storage::kModeContinue) != 0;
  const bool heuristic = c.matcher == LocaliserMatcher::kHeuristic;
  u.route = u.repeat && !u.explore && !heuristic;
  u.needs_queries = u.route || (u.repeat && !u.explore && heuristic && c.heuristic.scan_places > 0);
  return u;
}

// The route search's start place against the library (repeat alone: teach + repeat starts
// unknown). "" or the refusal; a library that cannot be read is a warning.
std::string check_start(Disk& disk, const storage::RunConfig& c, const RunUse& u) {
  if (!u.route || u.teach || c.route.start < 0) return {};
  const LogCount library = count_log(disk, storage::kLibraryFile, storage::kLibraryKind);
  const std::string start = "--start " + std::to_string(c.route.start);
  if (!library.readable) {
    warn(start + " is not checked against the card's library: " + library.why);
    return {};
  }
  if (static_cast<uint32_t>(c.route.start) < library.records) return {};
  return start + ": the card's library (" + disk.path() + ":" + storage::kLibraryFile + ") has " +
         (library.records == 0 ? std::string("no places")
                               : std::to_string(library.records) + " places (0.." +
                                     std::to_string(library.records - 1) + ")") +
         "; a repeat run starts at one of them, or give --start unknown";
}

// The query history against the relocalisation scan: it needs the last scan_seq_len steps'
// images, and they must outlast the scan over the library (docs/firmware.md). "" or the
// refusal; a missing file or a library too long for the scan is a warning.
std::string check_queries(Disk& disk, const storage::RunConfig& c, const RunUse& u) {
  if (!u.needs_queries) return {};
  bool present = false;
  const uint32_t steps = query_steps(disk, &present);
  if (!present) {
    warn(disk.path() + " has no 'queries' file: the firmware refuses to start a repeat run " +
         "without its query history (docs/seqslam_cli.md, \"A repeat card needs queries\")");
    return {};
  }
  if (!u.route) return {};
  const uint16_t seq = scan_seq_len(c.route, c.sequence);
  const std::string where = disk.path() + ":" + storage::kQueriesFile;
  if (storage::query_history_fit(steps, seq, 0, c.route.scan_places) ==
      storage::QueryFit::kTooFewForImages) {
    return where + " holds " + std::to_string(steps) + " query step" + (steps == 1 ? "" : "s") +
           " (512 bytes each), fewer than the " + std::to_string(seq) +
           " the relocalisation scan compares (--scan-seq-len, at most --seq-len): no scan could "
           "ever run, so an unknown start or a lost robot would never be localised; give the "
           "card a larger 'queries' file (queries:256K holds the " +
           std::to_string(profile::kQuerySteps) + " steps the firmware keeps)";
  }
  if (u.teach) return {};  // the library grows during the run: no size to check yet
  // A scan over M places takes ceil(M / scan_places) steps, and its first query image must
  // still be in the history at its last step (measured with the PC firmware: 111 places, 16
  // a step, 10 images: 16 steps complete every scan, 15 abandon every one).
  const LogCount library = count_log(disk, storage::kLibraryFile, storage::kLibraryKind);
  const uint64_t reach = uint64_t{steps - seq + 1u} * c.route.scan_places;
  if (!library.readable ||
      storage::query_history_fit(steps, seq, library.records, c.route.scan_places) ==
          storage::QueryFit::kFits) {
    return {};
  }
  const std::string why =
      where + " holds " + std::to_string(steps) + " query steps: a relocalisation scan (" +
      std::to_string(c.route.scan_places) + " places a step, " + std::to_string(seq) +
      " query images) covers at most (" + std::to_string(steps) + " - " + std::to_string(seq) +
      " + 1) x " + std::to_string(c.route.scan_places) + " = " + std::to_string(reach) +
      " places before its first images are overwritten, and the library has " +
      std::to_string(library.records) + ": every scan would be abandoned (the firmware's 'scan " +
      "card errors'); give a larger 'queries' file or a larger --scan-places";
  // From an unknown start only a scan can localise: nothing ever would be.
  if (c.route.start < 0) return why + " (with --start unknown nothing would be localised)";
  warn(why + " (tracking from --start " + std::to_string(c.route.start) + " still works)");
  return {};
}

// What the firmware refuses at start with its own sentence: warned here, so the card's owner
// learns it before taking the robot out.
void warn_refused_at_start(Disk& disk, const storage::RunConfig& c, const RunUse& u) {
  storage::Region region;
  const std::string refuses = ": the firmware refuses to start with this configuration";
  if (u.repeat && disk.volume().open(storage::kResultsFile, &region) != Status::kOk) {
    warn(disk.path() + " has no 'results' file" + refuses);
  }
  if (u.record && disk.volume().open(storage::kRecordFile, &region) != Status::kOk) {
    warn(disk.path() + " has no 'record' file" + refuses);
  }
  if (u.record && c.record_colour &&
      disk.volume().open(storage::kReplayFile, &region) == Status::kOk) {
    std::vector<uint8_t> buffer(storage::kDreamRecordMax);
    storage::DreamReader replay;
    if (replay.open(region, Span<uint8_t>(buffer.data(), buffer.size())) == Status::kOk &&
        replay.header().colour == storage::ColourFormat::kNone) {
      warn("--record-colour: " + disk.path() + ":" + storage::kReplayFile +
           " has no colour to record (a grey recording)" + refuses);
    }
  }
  if (!u.resume) return;
  const LogCount library = count_log(disk, storage::kLibraryFile, storage::kLibraryKind);
  if (!library.readable || library.records == 0) {
    warn("--modes continue: no library to continue (" +
         (library.readable ? disk.path() + ":library has no places" : library.why) + ")" + refuses);
  }
  const LogCount state = count_log(disk, storage::kStateFile, storage::kStateKind);
  if (!state.readable) {
    warn("--modes continue: no saved run to continue (" + state.why + ")" + refuses);
  }
}

}  // namespace

int check_config_for_card(Disk& disk, const storage::RunConfig& config) {
  // A configuration is one block at the start of the volume file `config`.
  if (std::string error = disk.check_write_limit(storage::kConfigFile, hal::kBlockSize);
      !error.empty()) {
    return fail(error);
  }
  const RunUse use = run_use(config);
  if (std::string refusal = check_start(disk, config, use); !refusal.empty()) {
    return usage_error(refusal);
  }
  if (std::string refusal = check_queries(disk, config, use); !refusal.empty()) {
    return usage_error(refusal);
  }
  warn_refused_at_start(disk, config, use);
  return kExitOk;
}

std::optional<hal::PipelineMapping> card_replay_mapping(const std::string& image) {
  Disk disk;
  storage::Region region;
  if (!disk.open(image, false).empty() ||
      disk.volume().open(storage::kReplayFile, &region) != Status::kOk) {
    return std::nullopt;
  }
  return tools::recorded_mapping(region);
}

}  // namespace seqslam::cli
