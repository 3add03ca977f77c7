// The session (session/session.h) with its storage on the PC's heap: what the PC tools run
// instead of wiring the pipeline themselves. The firmware runs the same Session with static
// storage on its card (firmware/app); here the library's images and metadata, the matchers'
// state and, for explore, the graph, the grid's resident tiles and the tile store are vectors
// sized for the run. The route search keeps the firmware's own storage types
// (profile::RouteStorage, profile::kQuerySteps of query history), so the PC's route search is
// the head board's.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "seqslam/session/profile.h"
#include "seqslam/session/session.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_tools/ram_tile_store.h"

namespace seqslam::tools {

struct HostSessionOptions {
  session::Search search = session::Search::kFull;
  uint32_t places = 0;  // library places the storage holds (>= 1)
  // Keep the library's per-place metadata (poses, pixel sums) in RAM, as the full search
  // needs; false: none, as the head board's route search (the results are the same).
  bool library_ram = true;
  // false: the library holds no images (the PC's bulk evaluation computes the differences
  // itself and steps the localiser with them: Localiser::localise_differences).
  bool library_images = true;
  // Explore: the range sensors' mounts (the recording's header) and the graph's capacity.
  std::vector<RangeSensor> sensors;
};

class HostSession {
 public:
  HostSession();
  ~HostSession();
  HostSession(const HostSession&) = delete;
  HostSession& operator=(const HostSession&) = delete;

  // Allocates the storage `config` needs (its image size, matcher and modes) for
  // options.places places and configures the session on it. "" or what was refused, named.
  std::string configure(const storage::RunConfig& config, const HostSessionOptions& options);

  session::Session& session() { return session_; }
  const session::Session& session() const { return session_; }
  PlaceLibrary& library() { return library_; }
  const storage::RunConfig& config() const { return *config_; }
#if SEQSLAM_APP_MAPPING
  const RamTileStore& tiles() const { return tiles_; }
#endif

 private:
  struct Storage;
  std::string attach_library(const HostSessionOptions& o);
  void attach_matchers(const HostSessionOptions& o, session::SessionParts* parts);
#if SEQSLAM_APP_MAPPING
  void attach_explorer(const HostSessionOptions& o, session::SessionParts* parts);
#endif

  std::unique_ptr<storage::RunConfig> config_;  // the session refers to it
  std::unique_ptr<Storage> storage_;
  PlaceLibrary library_;
  RamPlaceImages images_;
  class NoImages;
  std::unique_ptr<NoImages> no_images_;
  RouteSearch route_;
  RamQueryHistory history_;
  HeuristicMatcher heuristic_;
  SlopeMatcher slope_;
#if SEQSLAM_APP_MAPPING
  RamTileStore tiles_;
#endif
  session::Session session_;
};

// A SessionCheck as a sentence naming the refused setting.
std::string session_check_text(const session::SessionCheck& check);

}  // namespace seqslam::tools
