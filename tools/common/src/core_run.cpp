#include "seqslam_tools/core_run.h"

#include <memory>
#include <string>

// The firmware's capacity profile (kQuerySteps, RouteStorage and the limits behind it):
// run_route() uses the very types the head board uses, so a change there changes the PC's
// route search too.
#include "seqslam/session/profile.h"
#include "seqslam/seqslam.h"
#include "seqslam_tools/host_session.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::tools {
namespace {

bool wrong_size(const GrayImage& img, ImageSize size) {
  return img.width != size.width || img.height != size.height;
}

// Teaches the library's images in order (place i = image i); "" or what failed, naming the image.
std::string teach_library(session::Session& session, const std::vector<GrayImage>& library,
                          ImageSize size) {
  uint32_t index = 0;
  for (const GrayImage& img : library) {
    if (wrong_size(img, size)) {
      return "library image " + std::to_string(index) + " has another size";
    }
    const Status s = session.teach(ImageView{img.pixels.data(), size}, Pose2{}, index);
    if (s != Status::kOk) {
      return "teaching library image " + std::to_string(index) + " failed: " + status_name(s);
    }
    ++index;
  }
  return {};
}

// Localises query image `index` as the run's place `index`; "" or what failed, naming it.
std::string localise_query(session::Session& session, const GrayImage& img, size_t index,
                           ImageSize size, session::PlaceStep* out) {
  if (wrong_size(img, size)) return "query image " + std::to_string(index) + " has another size";
  const Status s = session.place(ImageView{img.pixels.data(), size}, Pose2{},
                                 static_cast<uint32_t>(index), out);
  if (s != Status::kOk) {
    return "localising query image " + std::to_string(index) + " failed: " + status_name(s);
  }
  return {};
}

}  // namespace

storage::RunConfig repeat_config(const LocaliserConfig& c) {
  storage::RunConfig r;
  r.modes = storage::kModeRepeat;
  r.trigger = storage::TriggerMode::kEveryFrame;
  r.mapping = hal::PipelineMapping::reduction(c.image_size.width, c.image_size.height);
  r.preprocess = c.preprocess;
  r.sequence = c.sequence;
  r.max_shift = c.max_shift;
  r.recent_exclusion = c.recent_exclusion;
  r.matcher = c.matcher;
  r.heuristic = c.heuristic;
  r.route = c.route;
  r.slope = c.slope;
  return r;
}

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
  // The session (the firmware's wiring) with its storage on the PC's heap, the whole library
  // every step.
  HostSession host;
  HostSessionOptions options;
  options.search = session::Search::kFull;
  options.places = static_cast<uint32_t>(library.empty() ? 1 : library.size());
  const std::string e = host.configure(repeat_config(c), options);
  if (!e.empty()) return Error{e};
  const std::string taught = teach_library(host.session(), library, c.image_size);
  if (!taught.empty()) return Error{taught};
  std::vector<CoreMatch> out;
  out.reserve(queries.size());
  for (const GrayImage& img : queries) {
    session::PlaceStep step;
    const std::string failed = localise_query(host.session(), img, out.size(), c.image_size, &step);
    if (!failed.empty()) return Error{failed};
    CoreMatch cm;
    cm.place = step.match.place;
    cm.confidence = to_double(step.match.confidence);
    cm.localised = step.match.localised;
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
  // The session as the head board runs it: the route search on the firmware's storage and
  // query history capacity (its history is on the card: the same images, one slot a step),
  // with or without the per-place metadata in RAM.
  HostSession host;
  HostSessionOptions o;
  o.search = session::Search::kRoute;
  o.places = static_cast<uint32_t>(library.size());
  o.library_ram = options.library_ram;
  const std::string e = host.configure(repeat_config(c), o);
  if (!e.empty()) return Error{e};
  const std::string taught = teach_library(host.session(), library, c.image_size);
  if (!taught.empty()) return Error{taught};
  std::vector<RouteCoreMatch> out;
  out.reserve(queries.size());
  for (const GrayImage& img : queries) {
    session::PlaceStep step;
    const std::string failed = localise_query(host.session(), img, out.size(), c.image_size, &step);
    if (!failed.empty()) return Error{failed};
    // A scan's storage error does not fail the step (the firmware counts it and the scan
    // retries): it stays in info.scan_status.
    out.push_back(RouteCoreMatch{step.match, step.route});
  }
  return out;
}

}  // namespace seqslam::tools
