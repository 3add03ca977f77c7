// Localisation benchmark firmware (seqslam_bench): retired instructions per localisation
// step on the RV32IMC board, and the tangent distance and heuristic matcher figures (issue 6).
// The mapping figures (occupancy grid, pose graph, mapping step, closure alignment) are in the
// second image, seqslam_bench_mapping (bench_mapping_main.cpp).
//
// Setting of the issue: 32x16 images, HE, S = 30, W = 50, library sizes M = 100, 450, 1000.
// The library images (M x 512 bytes) and the matcher state (S x M x 2 + 5 M bytes) live in
// the board's external memory region, which models the external storage the head board
// would stream them from; everything else (code, data, stack) is in the 65 456-byte RAM.
// Instruction counts come from minstret under QEMU with -icount shift=0: deterministic.
//
// Output: human-readable lines, then a JSON summary between BEGIN_SUMMARY_JSON and
// END_SUMMARY_JSON that scripts/run-bench.sh writes to build/bench/summary.json.
#include "bench_report.h"
#include "scene.h"
#include "seqslam/board/board.h"
#include "seqslam/seqslam.h"

namespace {

using namespace seqslam;
using bench::now;
using bench::print;
using bench::print_fixed;
using bench::print_u;
using firmware::render_scene;

constexpr uint32_t kMaxPlaces = 1000;
constexpr uint16_t kSeqLen = 30;
constexpr uint32_t kWarmup = kSeqLen;  // steps before every place has a full sequence
constexpr uint32_t kMeasured = 8;      // steps averaged
const ImageSize kSize{32, 16};
constexpr uint32_t kPixels = 512;

SEQSLAM_BOARD_EXTMEM PlaceLibraryStorage<kMaxPlaces, kPixels> g_library_storage;
SEQSLAM_BOARD_EXTMEM DiagonalMatcherStorage<kMaxPlaces, kSeqLen> g_matcher_storage;
SEQSLAM_BOARD_EXTMEM uint32_t g_differences[kMaxPlaces];
PlaceLibrary g_library;
Localiser g_localiser;

struct Figures {
  uint32_t places;
  uint64_t step_mean;  // instructions per Localiser::localise call
  uint64_t step_min;
  uint64_t step_max;
  uint64_t preprocess;   // HE of the query image
  uint64_t differences;  // sad_many over the library
  uint64_t matcher;      // normalisation + sequence update + best/runner-up (the rest)
  uint64_t normalise;    // of which: the local normalisation of the row alone
  uint64_t teach;        // Localiser::teach per place (preprocess + store)
  uint32_t correct;      // measured steps whose best place was right (sanity)
};

bool run(uint32_t places, Figures* f) {
  f->places = places;
  // A library of exactly `places` places in the external-memory storage.
  PlaceLibraryBuffers lb = g_library_storage.buffers();
  lb.info = lb.info.subspan(0, places);
  lb.sums = lb.sums.subspan(0, places);
  const Span<uint8_t> pixels(g_library_storage.pixels, places * kPixels);
  if (g_library_storage.images.configure(kPixels, pixels) != Status::kOk ||
      g_library.configure(kSize, g_library_storage.images, lb) != Status::kOk) {
    return false;
  }
  DiagonalMatcherBuffers mb = g_matcher_storage.buffers();
  mb.ring = mb.ring.subspan(0, places * kSeqLen);
  mb.cost = mb.cost.subspan(0, places);
  mb.run = mb.run.subspan(0, places);
  LocaliserConfig config;  // S = 30, W = 50, R = 10; the 32x16 with HE
  config.image_size = kSize;
  config.preprocess.method = Preprocessing::kHistEq;
  if (!g_localiser.configure(config, g_library, mb, Span<uint32_t>(g_differences, places)).ok()) {
    return false;
  }
  uint8_t raw[kPixels];
  // Library run: every place 2 world columns further.
  uint64_t teach_total = 0;
  for (uint32_t p = 0; p < places; ++p) {
    render_scene(p * 2, kSize, 256, 0, 11, raw);
    const uint64_t t = now();
    if (g_localiser.teach(ImageView{raw, kSize}, Pose2{}, p) != Status::kOk) return false;
    teach_total += now() - t;
  }
  f->teach = teach_total / places;
  uint64_t t0 = 0;
  // Query run from place 100 on (inside every library), darker.
  f->step_mean = 0;
  f->step_min = ~uint64_t{0};
  f->step_max = 0;
  f->correct = 0;
  const uint32_t start = places > 200 ? 100 : 10;
  Match m;
  for (uint32_t k = 0; k < kWarmup + kMeasured; ++k) {
    render_scene((start + k) * 2, kSize, 190, 25, 12, raw);
    t0 = now();
    if (g_localiser.localise(ImageView{raw, kSize}, &m) != Status::kOk) return false;
    const uint64_t t = now() - t0;
    if (k < kWarmup) continue;
    f->step_mean += t;
    f->step_min = t < f->step_min ? t : f->step_min;
    f->step_max = t > f->step_max ? t : f->step_max;
    if (m.place == static_cast<int32_t>(start + k)) ++f->correct;
  }
  f->step_mean /= kMeasured;
  // Components, measured on their own with the same data.
  uint8_t query[kPixels];
  PreprocessConfig pre;
  t0 = now();
  if (preprocess(pre, ImageView{raw, kSize}, MutableImageView{query, kSize}) != Status::kOk) {
    return false;
  }
  f->preprocess = now() - t0;
  t0 = now();
  if (g_library.differences(ImageView{query, kSize}, places, g_differences) != Status::kOk) {
    return false;
  }
  f->differences = now() - t0;
  f->matcher = f->step_mean - f->preprocess - f->differences;
  LocalNormaliser norm;
  if (norm.configure(config.sequence.window, config.sequence.sigma_min, kPixels) != Status::kOk) {
    return false;
  }
  SEQSLAM_BOARD_EXTMEM static uint16_t normalised[kMaxPlaces];
  t0 = now();
  norm.normalise_row(g_differences, places, normalised);
  f->normalise = now() - t0;
  return true;
}

// Issue 6 figures: the tangent distance at 32x16 and the greedy heuristic matcher.
struct OtherFigures {
  uint64_t td_prepare;       // prepare_tangent_image: blur, tangents, Gram matrix (one image)
  uint64_t td_distance;      // tangent_distance of two prepared images
  uint64_t sad;              // a plain SAD of the same pair, for comparison
  uint64_t heuristic_first;  // the first step of a sequence: M distance evaluations
  uint64_t heuristic_next;   // a later step: k distance evaluations (mean)
  uint64_t heuristic_mean;   // mean per step over a sequence of S
  uint32_t heuristic_places;
  int32_t heuristic_place;  // the answer at the sequence's end (sanity)
};

SEQSLAM_BOARD_EXTMEM TangentImage g_td_a;
SEQSLAM_BOARD_EXTMEM TangentImage g_td_b;

// The heuristic matcher's distances: SAD of the query image of step `query` (the bench keeps
// the sequence's S query images) to a library image.
class LibraryDistance final : public PlaceDistance {
 public:
  const uint8_t* queries = nullptr;  // S images back to back
  uint16_t seq_len = 1;

 private:
  Status do_distance(uint32_t query, uint32_t place, uint32_t* out) override {
    ImageView img;
    SEQSLAM_TRY(g_library.image(place, &img));
    const Result<uint32_t> d = sad(ImageView{queries + (query % seq_len) * kPixels, kSize}, img);
    if (!d.ok()) return d.status();
    *out = d.value();
    return Status::kOk;
  }
};

SEQSLAM_BOARD_EXTMEM uint8_t g_heuristic_queries[30 * kPixels];

bool run_other(OtherFigures* f) {
  uint8_t raw[kPixels];
  uint8_t a[kPixels];
  uint8_t b[kPixels];
  PreprocessConfig pre;
  render_scene(200, kSize, 256, 0, 11, raw);
  if (preprocess(pre, ImageView{raw, kSize}, MutableImageView{a, kSize}) != Status::kOk)
    return false;
  render_scene(201, kSize, 190, 25, 12, raw);
  if (preprocess(pre, ImageView{raw, kSize}, MutableImageView{b, kSize}) != Status::kOk)
    return false;
  const Result<BlurKernel> kernel = make_blur_kernel(default_td_sigma(kSize));
  if (!kernel.ok()) return false;
  uint64_t t0 = now();
  if (prepare_tangent_image(ImageView{a, kSize}, kernel.value(), &g_td_a) != Status::kOk) {
    return false;
  }
  f->td_prepare = now() - t0;
  if (prepare_tangent_image(ImageView{b, kSize}, kernel.value(), &g_td_b) != Status::kOk) {
    return false;
  }
  t0 = now();
  const Result<TangentDistance> td = tangent_distance(g_td_a, g_td_b);
  f->td_distance = now() - t0;
  if (!td.ok()) return false;
  t0 = now();
  const Result<uint32_t> plain = sad(ImageView{a, kSize}, ImageView{b, kSize});
  f->sad = now() - t0;
  if (!plain.ok()) return false;

  // The heuristic matcher, k = 5, S = 10, on the M = 450 library that run(450) left behind
  // (the call order in main guarantees it): one whole sequence of S steps.
  const uint32_t places = 450;
  HeuristicConfig hc;  // k = 5, threshold 40 grey levels, guard 5, S = 10, R = 10
  HeuristicMatcher matcher;
  if (matcher.configure(hc, kPixels) != Status::kOk) return false;
  LibraryDistance distance;
  distance.queries = g_heuristic_queries;
  distance.seq_len = hc.seq_len;
  const uint32_t start = 100;
  for (uint32_t k = 0; k < hc.seq_len; ++k) {
    render_scene((start + k) * 2, kSize, 190, 25, 12, raw);
    if (preprocess(pre, ImageView{raw, kSize},
                   MutableImageView{g_heuristic_queries + k * kPixels, kSize}) != Status::kOk) {
      return false;
    }
  }
  uint64_t total = 0;
  uint64_t later = 0;
  HeuristicMatch m;
  for (uint32_t k = 0; k < hc.seq_len; ++k) {
    t0 = now();
    if (matcher.step(distance, places, &m) != Status::kOk) return false;
    const uint64_t t = now() - t0;
    total += t;
    if (k == 0) {
      f->heuristic_first = t;
    } else {
      later += t;
    }
  }
  f->heuristic_next = later / (hc.seq_len - 1);
  f->heuristic_mean = total / hc.seq_len;
  f->heuristic_places = places;
  f->heuristic_place = m.place;
  return true;
}

void print_json_figures(const Figures& f, bool last) {
  print("    {\"places\": ");
  print_u(f.places);
  print(", \"instructions_per_step\": ");
  print_u(f.step_mean);
  print(", \"instructions_per_step_min\": ");
  print_u(f.step_min);
  print(", \"instructions_per_step_max\": ");
  print_u(f.step_max);
  print(", \"instructions_per_library_pixel\": ");
  print_fixed(f.step_mean, static_cast<uint64_t>(f.places) * kPixels, 3);
  print(", \"preprocess_instructions\": ");
  print_u(f.preprocess);
  print(", \"difference_instructions\": ");
  print_u(f.differences);
  print(", \"difference_instructions_per_library_pixel\": ");
  print_fixed(f.differences, static_cast<uint64_t>(f.places) * kPixels, 3);
  print(", \"matcher_instructions\": ");
  print_u(f.matcher);
  print(", \"matcher_instructions_per_place\": ");
  print_fixed(f.matcher, f.places, 1);
  print(", \"normalise_instructions_per_place\": ");
  print_fixed(f.normalise, f.places, 1);
  print(", \"teach_instructions_per_place\": ");
  print_u(f.teach);
  print(", \"correct_of_measured\": ");
  print_u(f.correct);
  print(last ? "}\n" : "},\n");
}

}  // namespace

int main() {
  const uint32_t sizes[] = {100, 450, 1000};
  Figures figures[3];
  print("seqslam benchmark, localisation image (seqslam_bench): 32x16 px, HE, S=30, W=50, ");
  print("R=10 (RV32IMC under QEMU, -icount)\n");
  print("library images and matcher state are in EXTERNAL memory (models external storage);\n");
  print("code, data and stack are in the 65456-byte RAM\n\n");
  for (int i = 0; i < 3; ++i) {
    if (!run(sizes[i], &figures[i])) {
      print("benchmark setup failed\n");
      return 1;
    }
    const Figures& f = figures[i];
    print("M=");
    print_u(f.places);
    print(": ");
    print_u(f.step_mean);
    print(" instructions/step (min ");
    print_u(f.step_min);
    print(", max ");
    print_u(f.step_max);
    print("), ");
    print_fixed(f.step_mean, static_cast<uint64_t>(f.places) * kPixels, 3);
    print(" per library pixel; HE ");
    print_u(f.preprocess);
    print(", differences ");
    print_u(f.differences);
    print(", matcher ");
    print_u(f.matcher);
    print(" (");
    print_fixed(f.matcher, f.places, 1);
    print("/place, of which normalisation ");
    print_fixed(f.normalise, f.places, 1);
    print("/place)\n");
  }
  // The heuristic runs on the M = 450 library: rebuild it (run() for 1000 came last).
  OtherFigures other{};
  if (!run(450, &figures[1]) || !run_other(&other)) {
    print("benchmark setup (tangent distance / heuristic) failed\n");
    return 1;
  }
  print("\ntangent distance 32x16: prepare one image ");
  print_u(other.td_prepare);
  print(", distance of two prepared images ");
  print_u(other.td_distance);
  print(" instructions (a plain SAD: ");
  print_u(other.sad);
  print(")\nheuristic matcher k=5, S=10, M=450: first step of a sequence ");
  print_u(other.heuristic_first);
  print(", later steps ");
  print_u(other.heuristic_next);
  print(", mean ");
  print_u(other.heuristic_mean);
  print(" instructions/step (diagonal at M=450: ");
  print_u(figures[1].step_mean);
  print("); answer place ");
  print_u(other.heuristic_place < 0 ? 0 : static_cast<uint64_t>(other.heuristic_place));
  print(other.heuristic_place == 109 ? " (correct)\n" : " (expected 109)\n");
  const bench::MemoryReport mem = bench::memory_report();
  bench::print_memory(mem);
  print(" (library ");
  print_u(decltype(g_library_storage)::kBytes);
  print(", matcher ");
  print_u(decltype(g_matcher_storage)::kBytes);
  print(", difference row ");
  print_u(sizeof(g_differences));
  print(")\n");

  bench::print_json_begin();
  print("\"image\": \"32x16\", \"preprocess\": \"he\", ");
  print("\"seq_len\": 30, \"window\": 50, \"exclusion\": 10, ");
  bench::print_json_config_end();
  print(",\n  \"steps\": [\n");
  for (int i = 0; i < 3; ++i)
    print_json_figures(figures[i], i == 2);
  print("  ],\n  \"tangent_distance\": {\"image\": \"32x16\", \"prepare_instructions\": ");
  print_u(other.td_prepare);
  print(", \"distance_instructions\": ");
  print_u(other.td_distance);
  print(", \"sad_instructions\": ");
  print_u(other.sad);
  print(", \"prepared_image_bytes\": ");
  print_u(sizeof(TangentImage));
  print("},\n  \"heuristic\": {\"k\": 5, \"seq_len\": 10, \"places\": ");
  print_u(other.heuristic_places);
  print(", \"first_step_instructions\": ");
  print_u(other.heuristic_first);
  print(", \"later_step_instructions\": ");
  print_u(other.heuristic_next);
  print(", \"mean_step_instructions\": ");
  print_u(other.heuristic_mean);
  print(", \"diagonal_step_instructions_same_places\": ");
  print_u(figures[1].step_mean);
  print(", \"matcher_bytes\": ");
  print_u(sizeof(HeuristicMatcher));
  print("},\n  ");
  bench::print_memory_json(mem, "library images and matcher state model external storage");
  bench::print_json_end();
  return 0;
}
