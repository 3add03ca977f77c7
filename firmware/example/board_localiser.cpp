// The head board's localiser in another firmware (board_localiser.h). The wiring is
// firmware/app's (open_library, open_queries, configure_session) without its files for
// results and recordings, messages and statistics: what an integrator needs, no more.
#include "board_localiser.h"

namespace seqslam::example {

namespace {

Status refuse(Status s, StartIssue why, StartIssue* issue) {
  if (issue != nullptr) *issue = why;
  return s;
}

}  // namespace

Status BoardLocaliser::start(hal::BlockDevice& card, hal::PixelBuffer& camera,
                             const storage::RunConfig& config, StartIssue* issue) {
  if (issue != nullptr) *issue = StartIssue::kNone;
  const bool teach = config.modes == storage::kModeTeach;
  const bool repeat = config.modes == storage::kModeRepeat;
  if ((!teach && !repeat) || config.matcher != LocaliserMatcher::kDiagonal) {
    return refuse(Status::kInvalidArgument, StartIssue::kModes, issue);
  }
  // The firmware's own checks: the settings' ranges and this build's capacities, and the
  // localiser's (what the session would refuse), before anything on the card is written.
  const storage::RunCheck run = storage::check_run_config(config, profile::kRunLimits);
  if (!run.ok()) return refuse(run.status, StartIssue::kSettings, issue);
  const ConfigCheck localiser = check_localiser_config(config.localiser());
  if (!localiser.ok()) return refuse(localiser.status, StartIssue::kSettings, issue);
  config_ = &config;
  camera_ = &camera;
  captures_ = 0;
  Status s = volume_.mount(card);
  if (s != Status::kOk) return refuse(s, StartIssue::kVolume, issue);
  s = volume_.open(storage::kLibraryFile, &meta_);
  if (s == Status::kOk) s = volume_.open(storage::kLibraryImagesFile, &images_file_);
  if (s == Status::kOk && repeat) s = volume_.open(storage::kQueriesFile, &queries_file_);
  if (s != Status::kOk) return refuse(s, StartIssue::kFiles, issue);
  s = camera.configure(config.mapping);
  if (s != Status::kOk) return refuse(s, StartIssue::kCamera, issue);
  s = open_queries(repeat);
  if (s != Status::kOk) return refuse(s, StartIssue::kQueries, issue);
  // The last step that can refuse: teaching, it writes a new library over the card's.
  s = open_library(teach);
  if (s != Status::kOk) return refuse(s, StartIssue::kLibrary, issue);
  // The route search, its storage and the query history: what the session wires for the
  // diagonal matcher (the heuristic would need its own part, session.h).
  session::SessionParts parts;
  parts.library = &library_;
  parts.matcher.route = &route_;
  parts.matcher.route_buffers = route_storage_.buffers();
  parts.matcher.history =
      repeat ? static_cast<QueryHistory*>(&queries_) : static_cast<QueryHistory*>(&teach_history_);
  const session::SessionCheck check = session_.configure(config, session::Search::kRoute, parts);
  return check.ok() ? Status::kOk : refuse(check.status, StartIssue::kLocaliser, issue);
}

// A new library on the card (teach) or the stored one (repeat), images streamed through the
// cache; nothing per place in RAM.
Status BoardLocaliser::open_library(bool teach) {
  storage::LibraryConfig lc;
  lc.image_size = config_->mapping.size();
  lc.preprocess = config_->preprocess;
  lc.mapping = config_->mapping;
  const Span<uint8_t> cache(image_cache_, sizeof image_cache_);
  if (!teach) return images_.load(meta_, images_file_, lc, cache, PlaceLibraryBuffers{}, library_);
  const Status s = images_.create(meta_, images_file_, lc, cache);
  return s != Status::kOk ? s : library_.configure(lc.image_size, images_, PlaceLibraryBuffers{});
}

// Repeat: the query history on the card, one slot of the configured image a step.
Status BoardLocaliser::open_queries(bool repeat) {
  const uint32_t pixels = config_->mapping.size().pixels();
  if (!repeat) {
    return teach_history_.configure(pixels, Span<uint8_t>(query_buffer_),
                                    Span<uint32_t>(&teach_places_, 1));
  }
  return queries_.configure(queries_file_, pixels, Span<uint8_t>(query_buffer_),
                            Span<uint32_t>(query_grew_));
}

Status BoardLocaliser::on_snapshot(const hal::SensorSnapshot& snap, bool* placed,
                                   session::PlaceStep* step) {
  const Status s = handle(snap, placed, step);
  if (config_ != nullptr) session_.work(profile::kScanSlicePlaces);
  return s;
}

Status BoardLocaliser::handle(const hal::SensorSnapshot& snap, bool* placed,
                              session::PlaceStep* step) {
  *placed = false;
  if (config_ == nullptr) return Status::kFailedPrecondition;
  if (!session_.snapshot(snap)) return Status::kOk;  // no place due
  Status s = camera_->capture();
  hal::Frame frame;
  if (s == Status::kOk) s = camera_->read(&frame);
  if (s == Status::kUnavailable) return Status::kOk;  // no frame at this moment
  if (s != Status::kOk) return s;
  *step = session::PlaceStep{};
  *placed = true;
  return session_.place(ImageView{frame.gray, frame.size}, session_.pose(), captures_++, step);
}

}  // namespace seqslam::example
