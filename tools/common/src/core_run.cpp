#include "seqslam_tools/core_run.h"

#include <memory>
#include <string>

// The firmware's capacity profile (kQuerySteps, RouteStorage and the limits behind it):
// run_route() uses the very types the head board uses, so a change there changes the PC's
// route search too.
#include "seqslam/session/profile.h"
#include "seqslam/seqslam.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::tools {
namespace {

bool wrong_size(const GrayImage& img, ImageSize size) {
  return img.width != size.width || img.height != size.height;
}

// Teaches the library's images in order (place i = image i); "" or what failed, naming the image.
std::string teach_library(Localiser& localiser, const std::vector<GrayImage>& library,
                          ImageSize size) {
  uint32_t index = 0;
  for (const GrayImage& img : library) {
    if (wrong_size(img, size)) {
      return "library image " + std::to_string(index) + " has another size";
    }
    const Status s = localiser.teach(ImageView{img.pixels.data(), size}, Pose2{}, index);
    if (s != Status::kOk) {
      return "teaching library image " + std::to_string(index) + " failed: " + status_name(s);
    }
    ++index;
  }
  return {};
}

// Localises query image `index`; "" or what failed, naming the image.
std::string localise_query(Localiser& localiser, const GrayImage& img, size_t index, ImageSize size,
                           Match* out) {
  if (wrong_size(img, size)) return "query image " + std::to_string(index) + " has another size";
  const Status s = localiser.localise(ImageView{img.pixels.data(), size}, out);
  if (s != Status::kOk) {
    return "localising query image " + std::to_string(index) + " failed: " + status_name(s);
  }
  return {};
}

}  // namespace

Outcome<std::vector<CoreMatch>> run_core(const std::vector<GrayImage>& library,
                                         const std::vector<GrayImage>& queries,
                                         const LocaliserConfig& c) {
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) {
    return Error{std::string("invalid configuration: ") + config_issue_text(check.issue)};
  }
  if (library.size() > kCoreRunMaxPlaces) {
    return Error{"the library has " + std::to_string(library.size()) + " images; at most " +
                 std::to_string(kCoreRunMaxPlaces) + " are supported"};
  }
  if (c.sequence.seq_len > kCoreRunMaxSeq) return Error{"sequence length above 100"};
  // The same static-capacity storage the firmware uses, here on the heap of the PC.
  auto lib_storage = std::make_unique<PlaceLibraryStorage<kCoreRunMaxPlaces, kMaxPixels>>();
  auto matcher_storage =
      std::make_unique<DiagonalMatcherStorage<kCoreRunMaxPlaces, kCoreRunMaxSeq>>();
  std::vector<uint32_t> differences(kCoreRunMaxPlaces);
  PlaceLibrary places;
  DiagonalMatcherBuffers mb = matcher_storage->buffers();
  mb.ring = mb.ring.subspan(0, static_cast<size_t>(kCoreRunMaxPlaces) * c.sequence.seq_len);
  if (lib_storage->attach(places, c.image_size) != Status::kOk) {
    return Error{"the image size does not fit the library storage"};
  }
  Localiser localiser;
  const ConfigCheck cfg =
      localiser.configure(c, places, mb, Span<uint32_t>(differences.data(), differences.size()));
  if (!cfg.ok())
    return Error{std::string("configuration refused: ") + config_issue_text(cfg.issue)};
  const std::string taught = teach_library(localiser, library, c.image_size);
  if (!taught.empty()) return Error{taught};
  std::vector<CoreMatch> out;
  out.reserve(queries.size());
  for (const GrayImage& img : queries) {
    Match m;
    const std::string failed = localise_query(localiser, img, out.size(), c.image_size, &m);
    if (!failed.empty()) return Error{failed};
    CoreMatch cm;
    cm.place = m.place;
    cm.confidence = to_double(m.confidence);
    cm.localised = m.localised;
    out.push_back(cm);
  }
  return out;
}

RouteCapacity route_capacity() {
  return RouteCapacity{profile::kMaxSeqLen,    profile::kMaxScanSeqLen, profile::kMaxNormWindow,
                       profile::kMaxExclusion, profile::kWindowSlots,   profile::kQuerySteps};
}

std::string route_search_refusal(const LocaliserConfig& c) {
  if (c.matcher != LocaliserMatcher::kDiagonal) {
    return "the route search runs the diagonal matcher only (not the heuristic)";
  }
  // The firmware's own check, with its own limits (profile::kRunLimits), on the run configuration
  // these settings amount to in teach + repeat mode: one decision for the board, `seqslam
  // config write` and this tool. The value and the limit are added for the reader.
  storage::RunConfig run;
  run.modes = storage::kModeTeach | storage::kModeRepeat;
  run.sequence = c.sequence;
  run.max_shift = c.max_shift;
  run.route = c.route;
  const storage::RunCheck check = storage::check_run_config(run, profile::kRunLimits);
  if (check.ok()) return {};
  const auto value_limit = [](uint32_t value, uint32_t limit) {
    return " (it is " + std::to_string(value) + ", at most " + std::to_string(limit) +
           "; firmware/app/app_limits.h)";
  };
  std::string why = storage::run_issue_text(check.issue);
  switch (check.issue) {
    case storage::RunIssue::kSeqLenAboveLimit:
      return why + value_limit(c.sequence.seq_len, profile::kMaxSeqLen);
    case storage::RunIssue::kWindowAboveLimit:
      return why + value_limit(c.sequence.window, profile::kMaxNormWindow);
    case storage::RunIssue::kExclusionAboveLimit:
      return why + value_limit(c.sequence.exclusion, profile::kMaxExclusion);
    case storage::RunIssue::kRouteWindowAboveLimit:
      return why + value_limit(c.route.window, profile::kWindowSlots);
    case storage::RunIssue::kScanSeqLenAboveLimit:
      return why + value_limit(scan_seq_len(c.route, c.sequence), profile::kMaxScanSeqLen);
    case storage::RunIssue::kRouteMaxShift:
      return why + " (it is " + std::to_string(c.max_shift) + ")";
    default:
      return why;
  }
}

Outcome<std::vector<RouteCoreMatch>> run_route(const std::vector<GrayImage>& library,
                                               const std::vector<GrayImage>& queries,
                                               const LocaliserConfig& c,
                                               const RouteRunOptions& options) {
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) {
    return Error{std::string("invalid configuration: ") + config_issue_text(check.issue)};
  }
  const std::string refused = route_search_refusal(c);
  if (!refused.empty()) return Error{refused};
  if (library.empty()) return Error{"the library has no images"};
  const uint32_t pixels = c.image_size.pixels();
  // The library's images in RAM (on the board: on the card; the differences are the same),
  // with or without the per-place metadata.
  std::vector<uint8_t> image_bytes(library.size() * pixels);
  RamPlaceImages images;
  if (images.configure(pixels, Span<uint8_t>(image_bytes.data(), image_bytes.size())) !=
      Status::kOk) {
    return Error{"the image size does not fit the library storage"};
  }
  std::vector<PlaceInfo> info(options.library_ram ? library.size() : 0);
  std::vector<uint32_t> sums(options.library_ram ? library.size() : 0);
  PlaceLibrary places;
  const Status ls = places.configure(c.image_size, images,
                                     PlaceLibraryBuffers{Span<PlaceInfo>(info.data(), info.size()),
                                                         Span<uint32_t>(sums.data(), sums.size())});
  if (ls != Status::kOk) return Error{std::string("library: ") + status_name(ls)};
  // The firmware's route storage and query history capacity (its history is on the card:
  // the same images, one slot a step).
  auto route_storage = std::make_unique<profile::RouteStorage>();
  auto history_storage = std::make_unique<RamQueryHistoryStorage<profile::kQuerySteps, kMaxPixels>>();
  RamQueryHistory history;
  if (history_storage->attach(history, pixels) != Status::kOk) {
    return Error{"the image size does not fit the query history"};
  }
  RouteSearch route;
  Localiser localiser;
  const ConfigCheck cfg = localiser.configure(c, places, route, route_storage->buffers(), history);
  if (!cfg.ok())
    return Error{std::string("configuration refused: ") + config_issue_text(cfg.issue)};
  const std::string taught = teach_library(localiser, library, c.image_size);
  if (!taught.empty()) return Error{taught};
  std::vector<RouteCoreMatch> out;
  out.reserve(queries.size());
  for (const GrayImage& img : queries) {
    RouteCoreMatch rm;
    const std::string failed = localise_query(localiser, img, out.size(), c.image_size, &rm.match);
    if (!failed.empty()) return Error{failed};
    // A scan's storage error does not fail the step (the firmware counts it and the scan
    // retries): it stays in info.scan_status.
    rm.info = localiser.route_step();
    out.push_back(rm);
  }
  return out;
}

}  // namespace seqslam::tools
