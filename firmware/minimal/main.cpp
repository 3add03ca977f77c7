// Minimal firmware: the whole core on the board, with a self-check.
//
// It drives a simulated straight 12 m corridor twice on 10 ms wheel-encoder snapshots:
// odometry integrates the ticks, the spatial trigger captures a place every 20 cm, the
// first lap teaches the library, the second lap (darker light, new sensor noise) localises
// against it. It prints one line per place of the second lap and exits 0 only if nearly all
// places with a full sequence were recognised. This image is also what the link check
// inspects (no heap, no libc, no exceptions, no soft float) and what proves the firmware
// fits the 65 456-byte memory.
#include "scene.h"
#include "seqslam/board/board.h"
#include "seqslam/seqslam.h"

namespace {

using namespace seqslam;
using firmware::render_scene;

constexpr uint32_t kPlaces = 48;
constexpr uint16_t kSeqLen = 10;
const ImageSize kSize{32, 16};

PlaceLibraryStorage<kPlaces, 512> g_library_storage;
DiagonalMatcherStorage<kPlaces, kSeqLen> g_matcher_storage;
uint32_t g_differences[kPlaces];
PlaceLibrary g_library;
Localiser g_localiser;
Odometry g_odometry;
SpatialTrigger g_trigger;

static_assert(decltype(g_library_storage)::kBytes + decltype(g_matcher_storage)::kBytes +
                      sizeof(g_differences) + sizeof(Localiser) <=
                  48 * 1024,
              "minimal firmware state must leave room for code and stack in 64 KB");

void print(const char* s) {
  board::console_print(s);
}

// One lap: returns the number of places with a full sequence and how many were correct.
struct LapResult {
  uint32_t places = 0;
  uint32_t answered = 0;
  uint32_t correct = 0;
};

LapResult drive_lap(bool teach, int32_t gain_q8, int32_t offset, uint32_t noise_seed) {
  LapResult r;
  g_odometry.reset(Pose2{}, 0, 0);
  g_trigger.reset();
  uint32_t left = 0;
  uint32_t right = 0;
  uint8_t raw[512];
  // 0.3 m/s: 23 ticks of a 0.532 m wheel per 10 ms.
  while (r.places < kPlaces) {
    left += 23;
    right += 23;
    if (g_odometry.update(left, right) != Status::kOk) return r;
    if (!g_trigger.update(g_odometry.pose())) continue;
    // The camera sees world column = position in units of 10 cm.
    const int64_t column = g_odometry.pose().x.raw() / (int64_t{429496730});
    render_scene(static_cast<uint32_t>(column), kSize, gain_q8, offset, noise_seed, raw);
    const ImageView image{raw, kSize};
    if (teach) {
      if (g_localiser.teach(image, g_odometry.pose(), r.places) != Status::kOk) return r;
    } else {
      Match m;
      if (g_localiser.localise(image, &m) != Status::kOk) return r;
      if (m.place >= 0) {
        ++r.answered;
        const int32_t err = m.place - static_cast<int32_t>(r.places);
        if (err >= -1 && err <= 1) ++r.correct;
        print("place ");
        board::console_print_u64(r.places);
        print(" -> ");
        board::console_print_i64(m.place);
        print(" confidence_q16 ");
        board::console_print_u64(m.confidence.raw());
        print(m.localised ? " localised\n" : " not localised\n");
      }
    }
    ++r.places;
  }
  return r;
}

}  // namespace

int main() {
  if (g_odometry.configure(OdometryConfig{}) != Status::kOk) return 2;
  if (g_library_storage.attach(g_library, kSize) != Status::kOk) return 2;
  LocaliserConfig config;
  config.image_size = kSize;
  config.sequence.seq_len = kSeqLen;
  config.sequence.window = 20;
  const ConfigCheck check = g_localiser.configure(config, g_library, g_matcher_storage.buffers(),
                                                  Span<uint32_t>(g_differences, kPlaces));
  if (!check.ok()) {
    print(config_issue_text(check.issue));
    print("\n");
    return 2;
  }
  drive_lap(true, 256, 0, 1);
  const LapResult r = drive_lap(false, 170, 20, 2);
  print("recognised ");
  board::console_print_u64(r.correct);
  print(" of ");
  board::console_print_u64(r.answered);
  print(" places with a full sequence\n");
  const board::MemoryUsage mem = board::memory_usage();
  print("ram used ");
  board::console_print_u64(mem.ram_used_bytes);
  print(" of ");
  board::console_print_u64(mem.ram_capacity_bytes);
  print(" bytes, stack high water ");
  board::console_print_u64(board::stack_high_water_bytes());
  print(" bytes\n");
  const bool pass = r.answered >= kPlaces - kSeqLen && r.correct * 10 >= r.answered * 9;
  print(pass ? "SELF-CHECK PASS\n" : "SELF-CHECK FAIL\n");
  return pass ? 0 : 1;
}
