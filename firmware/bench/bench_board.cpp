// The head board's localiser as it ships (bench_board.h).
#include "bench_board.h"

#include "bench_report.h"
#include "scene.h"
#include "seqslam/board/board.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/hal/sd_card_model.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/seqslam.h"
#include "seqslam/session/profile.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/query_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"

namespace seqslam::bench {
namespace {

using firmware::render_scene;

// The application's defaults (the run configuration's image size and preprocessing).
constexpr ImageSize kSize = storage::RunConfig{}.mapping.size();
constexpr uint32_t kPixels = 512;  // the pixel buffer's capacity
constexpr uint32_t kMaxBoardPlaces = 5000;
// The card's files, block ranges on one RAM card in external memory (the sizes a user would
// give `seqslam disk create` for a 5 000-place route).
constexpr uint32_t kMetaBlocks = 1024;  // library metadata log (~48 bytes a place)
constexpr uint32_t kImageBlocks = kMaxBoardPlaces + 2;
constexpr uint32_t kQueryBlocks = profile::kQuerySteps;
constexpr uint32_t kResultBlocks = 1024;
constexpr uint32_t kCardBlocks = kMetaBlocks + kImageBlocks + kQueryBlocks + kResultBlocks;
SEQSLAM_BOARD_EXTMEM uint8_t g_card_bytes[kCardBlocks * hal::kBlockSize];

hal::FakeBlockDevice g_fake{Span<uint8_t>(g_card_bytes, sizeof g_card_bytes)};

TimedCard g_timed{g_fake};
hal::CountingBlockDevice g_card{g_timed};
storage::Region g_meta{g_card, 0, kMetaBlocks};
storage::Region g_images_file{g_card, kMetaBlocks, kImageBlocks};
storage::Region g_queries_file{g_card, kMetaBlocks + kImageBlocks, kQueryBlocks};
storage::Region g_results_file{g_card, kMetaBlocks + kImageBlocks + kQueryBlocks, kResultBlocks};

// The application's localisation state (app.h: Application's members of the same types and
// capacities), in the 65 456-byte RAM as on the board (ram_bytes counts it).
struct Localisation {
  storage::StoredPlaceImages images;
  PlaceLibrary library;
  storage::StoredQueryHistory history;
  Localiser localiser;
  RouteSearch route;
  profile::RouteStorage route_storage;
  HeuristicMatcher heuristic;
  storage::ResultsWriter results;
  uint8_t image_cache[profile::kImageCacheBytes];
  uint8_t query_buffer[kPixels];
  uint32_t query_grew[profile::kQuerySteps / 32];
};
Localisation g_loc;

// add_step once in the image (outside the measured stretches); the stretch's time in ns.
__attribute__((noinline)) uint64_t record(StepStats& s, const CardCost& c) {
  add_step(s, c.instructions, c.card);
  return card_step_ns(c);
}

// The route search's share of the scan after a step, in the application's slices (one after
// each 10 ms snapshot), measured slice by slice into *f; `step` is the step's own cost.
__attribute__((noinline)) void slices(const CardCost& step, BoardFigures* f) {
  constexpr uint64_t kPeriodNs = uint64_t{hal::kSnapshotPeriodUs} * 1000u;
  if (card_step_ns(step) > kPeriodNs) ++f->pieces_over_period;
  CardCost place = step;
  CardMeter meter(g_card, g_timed);
  while (g_loc.route.pending() > 0) {
    CardCost slice;
    meter.start();
    const uint32_t n = g_loc.localiser.work(profile::kScanSlicePlaces);
    meter.stop(&slice);
    const uint64_t ns = record(f->slices, slice);
    f->streamed += n;
    f->slice_ns += ns;
    if (ns > kPeriodNs) {
      ++f->pieces_over_period;
      ++f->slices_over_period;
    }
    place.instructions += slice.instructions;
    place.card = plus(place.card, slice.card);
  }
  record(f->place_total, place);
}

// One step as the application takes it: localise, then append the result record; then, when
// `f` is given, the slices that follow it.
bool step(const uint8_t* raw, uint32_t capture, Match* m, StepStats* stats,
          BoardFigures* f = nullptr) {
  const hal::CardCounters before = g_card.counters();
  const uint64_t card0 = g_timed.instructions();
  const uint64_t t0 = now();
  if (g_loc.localiser.localise(ImageView{raw, kSize}, m) != Status::kOk) return false;
  storage::RunResult r;
  r.step = m->query;
  r.capture = capture;
  r.place = m->place;
  r.runner_up = m->runner_up;
  r.cost = m->cost;
  r.runner_up_cost = m->runner_up_cost;
  r.confidence = m->confidence;
  r.localised = m->localised;
  if (g_loc.results.append(r) != Status::kOk) return false;
  const uint64_t t = now() - t0 - (g_timed.instructions() - card0);
  const hal::CardCounters c = g_card.since(before);
  if (stats != nullptr) add_step(*stats, t, c);
  if (f != nullptr) slices(CardCost{t, c}, f);
  return true;
}

storage::LibraryConfig library_config() {
  const storage::RunConfig rc;
  storage::LibraryConfig lc;
  lc.image_size = kSize;
  lc.preprocess = rc.preprocess;
  lc.mapping = rc.mapping;
  return lc;
}

// Loads the library of `places` places from the card into g_loc (as the application's repeat
// run does); its cost into *f if given.
bool load(uint32_t places, BoardFigures* f) {
  const hal::CardCounters before = g_card.counters();
  const uint64_t card0 = g_timed.instructions();
  const uint64_t t0 = now();
  const Status s =
      g_loc.images.load(g_meta, g_images_file, library_config(), Span<uint8_t>(g_loc.image_cache),
                        PlaceLibraryBuffers{}, g_loc.library);
  if (f != nullptr) {
    f->load_instructions = now() - t0 - (g_timed.instructions() - card0);
    f->load_ns =
        f->load_instructions * 1000000000u / kCpuHz + hal::card_time_ns(g_card.since(before));
  }
  return s == Status::kOk && g_loc.library.size() == places;
}

bool configure_route() {
  if (g_loc.history.configure(g_queries_file, kSize.pixels(), Span<uint8_t>(g_loc.query_buffer),
                              Span<uint32_t>(g_loc.query_grew)) != Status::kOk) {
    return false;
  }
  storage::RunConfig rc;  // the application's defaults: route search from place 0
  const LocaliserConfig lc = rc.localiser();
  return g_loc.localiser
             .configure(lc, g_loc.library, g_loc.route, g_loc.route_storage.buffers(),
                        g_loc.history)
             .ok() &&
         g_loc.results.create(g_results_file) == Status::kOk;
}

bool configure_heuristic() {
  storage::RunConfig rc;  // the application's defaults with the heuristic chosen
  rc.matcher = LocaliserMatcher::kHeuristic;
  const LocaliserConfig lc = rc.localiser();
  return g_loc.localiser.configure(lc, g_loc.library, g_loc.heuristic, &g_loc.history).ok() &&
         g_loc.results.create(g_results_file) == Status::kOk;
}

bool near(int32_t place, uint32_t truth) {
  return place >= 0 && place + 1 >= static_cast<int32_t>(truth) &&
         place <= static_cast<int32_t>(truth) + 1;
}

}  // namespace

uint32_t board_localiser_ram_bytes() {
  return static_cast<uint32_t>(sizeof(Localisation));
}

uint32_t board_capacity_places() {
  const RouteSearchConfig r;
  return (profile::kQuerySteps - profile::kMaxScanSeqLen) * r.scan_places;
}

bool run_board(uint32_t places, BoardFigures* f) {
  *f = BoardFigures{};
  f->places = places;
  if (places > kMaxBoardPlaces) return false;
  // Teach: a fresh library on the card.
  if (g_loc.images.create(g_meta, g_images_file, library_config(),
                          Span<uint8_t>(g_loc.image_cache)) != Status::kOk ||
      g_loc.library.configure(kSize, g_loc.images, PlaceLibraryBuffers{}) != Status::kOk ||
      !configure_route()) {
    return false;
  }
  uint8_t raw[kPixels];
  uint64_t teach = 0;
  for (uint32_t p = 0; p < places; ++p) {
    render_scene(p * 2, kSize, 256, 0, 11, raw);
    const uint64_t t0 = now();
    if (g_loc.localiser.teach(ImageView{raw, kSize}, Pose2{}, p) != Status::kOk) return false;
    teach += now() - t0;
  }
  f->teach_instructions_per_place = teach / places;
  // Repeat: load, then track from place 0 (S steps to fill the window, then measured).
  if (!load(places, f) || !configure_route()) return false;
  const uint16_t seq = storage::RunConfig{}.sequence.seq_len;
  constexpr uint32_t kTracked = 24;
  Match m;
  uint32_t capture = 0;
  for (uint32_t k = 0; k < seq + kTracked; ++k, ++capture) {
    render_scene(k * 2, kSize, 190, 25, 12, raw);
    // (The first S steps' slices are streamed too, as on the board, but not counted.)
    BoardFigures warm_up;
    if (!step(raw, capture, &m, k >= seq ? &f->tracking : nullptr, k >= seq ? f : &warm_up)) {
      return false;
    }
    if (k >= seq && m.localised && near(m.place, k)) ++f->tracking_correct;
  }
  // A kidnap: from place seq + kTracked back to a quarter of it (most of the library lies
  // ahead whatever M). Every step until the first correct fix there is measured: the scans
  // beside the window find the place, a second scan scan_seq_len steps later confirms it
  // once the prediction has had no fix for lost_after places (route_search.h).
  const uint32_t from = seq + kTracked;
  const uint32_t to = from / 4;
  const uint32_t limit = 3 * (places / RouteSearchConfig{}.scan_places) + 4 * seq + 50;
  for (uint32_t k = 0; k < limit && to + k < places; ++k, ++capture) {
    render_scene((to + k) * 2, kSize, 190, 25, 12, raw);
    if (!step(raw, capture, &m, &f->relocalising, f)) return false;
    if (g_loc.localiser.route_step().scan_completed) ++f->scans;
    if (m.localised && near(m.place, to + k)) {
      f->relocalised_after = k + 1;
      break;
    }
  }
  // The heuristic matcher on the same card: two sequences from place 20 on (each its greedy
  // scan, spread over steps, then the trails).
  if (!load(places, nullptr) || !configure_heuristic()) return false;
  const uint32_t steps = 2 * (places / storage::RunConfig{}.heuristic.scan_places + seq + 1);
  for (uint32_t k = 0; k < steps && 20 + k < places; ++k, ++capture) {
    render_scene((20 + k) * 2, kSize, 190, 25, 12, raw);
    if (!step(raw, capture, &m, &f->heuristic)) return false;
    f->heuristic_place = m.place;
    f->heuristic_truth = 20 + k;
  }
  return true;
}

namespace {

void print_ms(uint64_t ns) {
  print_fixed(ns, 1000000, 2);
}

// The time between two places (20 cm) at 0.35 and 0.15 m/s, in ns.
constexpr uint64_t kPlaceNsFast = 200000000000ull / 350u;
constexpr uint64_t kPlaceNsSlow = 200000000000ull / 150u;

uint64_t mean(uint64_t sum, uint32_t n) {
  return n == 0 ? 0 : sum / n;
}

// The between-places figures of docs/performance.md, "The time between places".
struct PlaceFigures {
  uint64_t cpu_ns = 0;               // a place's step and slices: CPU, mean
  uint64_t card_ns = 0;              // ... the card, mean
  uint64_t max_ns = 0;               // ... both, the slowest place
  uint64_t share_fast_permille = 0;  // the slowest place against the time between places
  uint64_t share_slow_permille = 0;
  uint64_t rate = 0;                // library places a second the slices stream
  uint64_t scan_ns = 0;             // a whole-library scan's own time (M / rate)
  uint32_t scan_places_driven = 0;  // ... spread over this many places (scan_places a place)
};

PlaceFigures place_figures(const BoardFigures& f) {
  PlaceFigures p;
  const StepStats& t = f.place_total;
  p.cpu_ns = mean(t.instructions_sum, t.steps) * 1000000000u / kCpuHz;
  const uint64_t all = mean(t.ns_sum, t.steps);
  p.card_ns = all > p.cpu_ns ? all - p.cpu_ns : 0;
  p.max_ns = t.ns_max;
  p.share_fast_permille = t.ns_max * 1000u / kPlaceNsFast;
  p.share_slow_permille = t.ns_max * 1000u / kPlaceNsSlow;
  p.rate = f.slice_ns == 0 ? 0 : f.streamed * 1000000000u / f.slice_ns;
  p.scan_ns = f.streamed == 0 ? 0 : uint64_t{f.places} * f.slice_ns / f.streamed;
  const uint32_t share = RouteSearchConfig{}.scan_places;
  p.scan_places_driven = (f.places + share - 1) / share;
  return p;
}

}  // namespace

void print_board(const BoardFigures& f) {
  print("M=");
  print_u(f.places);
  print(" (teach ");
  print_u(f.teach_instructions_per_place);
  print(" instructions/place; loading the library ");
  print_ms(f.load_ns);
  print(" ms)\n");
  print_step_stats("tracking      ", f.tracking);
  print_step_stats("relocalising  ", f.relocalising);
  print("    kidnap relocalised after ");
  print_u(f.relocalised_after);
  print(" places (");
  print_u(f.scans);
  print(" scans); tracking fixes correct ");
  print_u(f.tracking_correct);
  print(" of 24\n");
  print_step_stats("heuristic     ", f.heuristic);
  const PlaceFigures p = place_figures(f);
  print_step_stats("scan slices   ", f.slices);
  print("    a place (step and its slices): CPU ");
  print_ms(p.cpu_ns);
  print(" ms, card ");
  print_ms(p.card_ns);
  print(" ms, slowest ");
  print_ms(p.max_ns);
  print(" ms = ");
  print_fixed(p.share_fast_permille, 10, 1);
  print(" % of the time between places at 0.35 m/s, ");
  print_fixed(p.share_slow_permille, 10, 1);
  print(" % at 0.15 m/s\n    longest slice ");
  print_ms(f.slices.ns_max);
  print(" ms; pieces of work longer than a snapshot period: ");
  print_u(f.pieces_over_period);
  print(" (slices ");
  print_u(f.slices_over_period);
  print("); scan rate ");
  print_u(p.rate);
  print(" places/s; a whole-library scan ");
  print_ms(p.scan_ns);
  print(" ms of work over ");
  print_u(p.scan_places_driven);
  print(" places\n");
}

void print_board_json(const BoardFigures& f, bool last) {
  print("      {\"places\": ");
  print_u(f.places);
  // The names for the localised step (the route search while tracking).
  print(", \"card_bytes_per_step\": ");
  print_u(f.tracking.steps == 0 ? 0 : f.tracking.card_bytes_sum / f.tracking.steps);
  print(", \"card_requests_per_step\": ");
  print_fixed(f.tracking.card_requests_sum, f.tracking.steps == 0 ? 1 : f.tracking.steps, 2);
  print(", \"step_ms_at_72mhz\": ");
  print_fixed(f.tracking.steps == 0 ? 0 : f.tracking.ns_sum / f.tracking.steps, 1000000, 3);
  print(", \"ram_bytes\": ");
  print_u(board_localiser_ram_bytes());
  print(",\n       \"teach_instructions_per_place\": ");
  print_u(f.teach_instructions_per_place);
  print(", \"library_load_instructions\": ");
  print_u(f.load_instructions);
  print(", \"library_load_ms\": ");
  print_fixed(f.load_ns, 1000000, 1);
  print(",\n       ");
  print_step_stats_json("tracking", f.tracking, false);
  print("\"tracking_fixes_correct\": ");
  print_u(f.tracking_correct);
  print(",\n       ");
  print_step_stats_json("relocalising", f.relocalising, false);
  print("\"relocalised_after_places\": ");
  print_u(f.relocalised_after);
  print(", \"scans_completed\": ");
  print_u(f.scans);
  print(",\n       ");
  print_step_stats_json("heuristic", f.heuristic, false);
  const PlaceFigures p = place_figures(f);
  print("\"place_cpu_ms\": ");
  print_fixed(p.cpu_ns, 1000000, 3);
  print(", \"place_card_ms\": ");
  print_fixed(p.card_ns, 1000000, 3);
  print(", \"place_max_ms\": ");
  print_fixed(p.max_ns, 1000000, 3);
  print(", \"share_at_035_percent\": ");
  print_fixed(p.share_fast_permille, 10, 1);
  print(", \"share_at_015_percent\": ");
  print_fixed(p.share_slow_permille, 10, 1);
  print(",\n       \"longest_slice_ms\": ");
  print_fixed(f.slices.ns_max, 1000000, 3);
  print(", \"slices\": ");
  print_u(f.slices.steps);
  print(", \"pieces_over_snapshot_period\": ");
  print_u(f.pieces_over_period);
  print(", \"slices_over_snapshot_period\": ");
  print_u(f.slices_over_period);
  print(", \"scan_places_per_second\": ");
  print_u(p.rate);
  print(", \"whole_scan_ms\": ");
  print_fixed(p.scan_ns, 1000000, 1);
  print(", \"whole_scan_places\": ");
  print_u(p.scan_places_driven);
  print(",\n       ");
  print("\"heuristic_last_place\": ");
  print_u(f.heuristic_place < 0 ? 0 : static_cast<uint32_t>(f.heuristic_place));
  print(", \"heuristic_last_truth\": ");
  print_u(f.heuristic_truth);
  print(last ? "}\n" : "},\n");
}

}  // namespace seqslam::bench
