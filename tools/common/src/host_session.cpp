#include "seqslam_tools/host_session.h"

namespace seqslam::tools {

struct HostSession::Storage {
  std::vector<uint8_t> images;
  std::vector<PlaceInfo> info;
  std::vector<uint32_t> sums;
  // The full search's state and difference row (the slope matcher's too).
  std::vector<uint16_t> ring;
  std::vector<uint32_t> cost;
  std::vector<uint8_t> run;
  std::vector<uint32_t> differences;
  std::vector<uint8_t> velocity;
  // The route search: the firmware's own storage and query history capacity.
  std::unique_ptr<profile::RouteStorage> route = std::make_unique<profile::RouteStorage>();
  std::vector<uint8_t> history_images;
  std::vector<uint32_t> history_places;
#if SEQSLAM_APP_MAPPING
  std::vector<PoseGraphNode> nodes;
  std::vector<PoseGraphEdge> edges;
  std::vector<PoseGraphSolverSlot> solver;
  std::vector<int8_t> cells;
  std::vector<GridSlot> slots;
  std::vector<uint8_t> scratch;
  std::vector<RangeSensor> sensors;
#endif
};

// A library of `places` places whose images are never stored or read.
class HostSession::NoImages final : public PlaceImages {
 public:
  explicit NoImages(uint32_t places) : places_(places) {}

 private:
  uint32_t do_capacity() const override { return places_; }
  Status do_append(uint32_t, const uint8_t*, const PlaceInfo&, uint32_t) override {
    return Status::kFailedPrecondition;
  }
  Status do_view(uint32_t, uint32_t, const uint8_t**, uint32_t*) override {
    return Status::kFailedPrecondition;
  }
  uint32_t places_;
};

HostSession::HostSession() = default;
HostSession::~HostSession() = default;

std::string session_check_text(const session::SessionCheck& check) {
  switch (check.issue) {
    case session::SessionIssue::kLocaliser:
      return config_issue_text(check.localiser_issue);
#if SEQSLAM_APP_MAPPING
    case session::SessionIssue::kExplorer:
      return std::string("explorer: ") + (check.explorer_issue == ExplorerIssue::kGrid
                                               ? grid_issue_text(check.grid_issue)
                                               : explorer_issue_text(check.explorer_issue));
#endif
    default:
      return session::session_issue_text(check.issue);
  }
}

std::string HostSession::attach_library(const HostSessionOptions& o) {
  const uint32_t pixels = config_->mapping.size().pixels();
  PlaceImages* images = &images_;
  if (o.library_images) {
    storage_->images.assign(static_cast<size_t>(o.places) * pixels, 0);
    if (images_.configure(pixels, Span<uint8_t>(storage_->images.data(),
                                                storage_->images.size())) != Status::kOk) {
      return "the image size does not fit the library storage";
    }
  } else {
    no_images_ = std::make_unique<NoImages>(o.places);
    images = no_images_.get();
  }
  const size_t meta = o.library_ram ? o.places : 0;
  storage_->info.assign(meta, PlaceInfo{});
  storage_->sums.assign(meta, 0);
  const Status s = library_.configure(
      config_->mapping.size(), *images,
      PlaceLibraryBuffers{Span<PlaceInfo>(storage_->info.data(), storage_->info.size()),
                          Span<uint32_t>(storage_->sums.data(), storage_->sums.size())});
  if (s != Status::kOk) return std::string("library: ") + status_name(s);
  return {};
}

// Each matcher's storage, sized for what the configuration runs (the session picks the one).
void HostSession::attach_matchers(const HostSessionOptions& o, session::SessionParts* parts) {
  Storage& st = *storage_;
  session::MatcherParts& m = parts->matcher;
  const size_t places = o.places;
  const size_t seq = config_->sequence.seq_len;
  const bool full = o.search == session::Search::kFull ||
                    (config_->modes & storage::kModeExplore) != 0;
  const LocaliserMatcher matcher = config_->matcher;
  if ((full && matcher == LocaliserMatcher::kDiagonal) || matcher == LocaliserMatcher::kSlope) {
    st.ring.assign(seq * places, 0);
    st.cost.assign(places, 0);
    st.differences.assign(places, 0);
    m.differences = Span<uint32_t>(st.differences.data(), places);
    if (matcher == LocaliserMatcher::kSlope) {
      st.velocity.assign(places, 0);
      m.slope = &slope_;
      m.slope_buffers = SlopeMatcherBuffers{Span<uint16_t>(st.ring.data(), st.ring.size()),
                                            Span<uint32_t>(st.cost.data(), places),
                                            Span<uint8_t>(st.velocity.data(), places)};
    } else {
      st.run.assign(places, 0);
      m.full = DiagonalMatcherBuffers{Span<uint16_t>(st.ring.data(), st.ring.size()),
                                      Span<uint32_t>(st.cost.data(), places),
                                      Span<uint8_t>(st.run.data(), places)};
    }
  }
  // The route search and a budgeted heuristic read earlier query images back from a history
  // of the firmware's capacity (on the robot: the card's `queries` file).
  const bool route = !full && matcher == LocaliserMatcher::kDiagonal;
  const bool budgeted =
      matcher == LocaliserMatcher::kHeuristic && config_->heuristic.scan_places > 0;
  const uint32_t pixels = config_->mapping.size().pixels();
  if (route || budgeted) {
    st.history_images.assign(static_cast<size_t>(profile::kQuerySteps) * pixels, 0);
    st.history_places.assign(profile::kQuerySteps, 0);
    if (history_.configure(
            pixels, Span<uint8_t>(st.history_images.data(), st.history_images.size()),
            Span<uint32_t>(st.history_places.data(), st.history_places.size())) == Status::kOk) {
      m.history = &history_;
    }
  }
  m.route = &route_;
  m.route_buffers = st.route->buffers();
  m.heuristic = &heuristic_;
}

#if SEQSLAM_APP_MAPPING
// Explore: one graph node per place, the odometry chain and up to two closures a place, the
// firmware's resident tiles over a tile store in RAM.
void HostSession::attach_explorer(const HostSessionOptions& o, session::SessionParts* parts) {
  Storage& st = *storage_;
  st.nodes.assign(o.places, PoseGraphNode{});
  st.solver.assign(o.places, PoseGraphSolverSlot{});
  st.edges.assign(3 * static_cast<size_t>(o.places), PoseGraphEdge{});
  st.cells.assign(static_cast<size_t>(profile::kGridSlots) * kGridTileCells, 0);
  st.slots.assign(profile::kGridSlots, GridSlot{});
  st.scratch.assign(config_->mapping.size().pixels(), 0);
  st.sensors = o.sensors;
  ExplorerBuffers& e = parts->explorer;
  e.graph = PoseGraphBuffers{Span<PoseGraphNode>(st.nodes.data(), st.nodes.size()),
                             Span<PoseGraphEdge>(st.edges.data(), st.edges.size()),
                             Span<PoseGraphSolverSlot>(st.solver.data(), st.solver.size())};
  e.grid = OccupancyGridBuffers{Span<int8_t>(st.cells.data(), st.cells.size()),
                                Span<GridSlot>(st.slots.data(), st.slots.size())};
  e.tiles = &tiles_;
  e.sensors = Span<const RangeSensor>(st.sensors.data(), st.sensors.size());
  e.scratch = Span<uint8_t>(st.scratch.data(), st.scratch.size());
}
#endif

std::string HostSession::configure(const storage::RunConfig& config,
                                   const HostSessionOptions& options) {
  if (options.places == 0) return "the library has no places";
  config_ = std::make_unique<storage::RunConfig>(config);
  storage_ = std::make_unique<Storage>();
  const std::string e = attach_library(options);
  if (!e.empty()) return e;
  session::SessionParts parts;
  parts.library = &library_;
  attach_matchers(options, &parts);
#if SEQSLAM_APP_MAPPING
  if ((config.modes & storage::kModeExplore) != 0) attach_explorer(options, &parts);
#endif
  const session::SessionCheck check = session_.configure(*config_, options.search, parts);
  if (!check.ok()) return "configuration refused: " + session_check_text(check);
  return {};
}

}  // namespace seqslam::tools
