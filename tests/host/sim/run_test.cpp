// Simulated runs (scenario.h generate_run): deterministic files, a .dream that agrees with
// the run's summary, and places exactly where the firmware's capture logic (the core's
// Odometry and SpatialTrigger on the recorded snapshots) puts them.
//
// The route is one short leg along the lab's south lane (6 m: every place is a 346x271
// render; under the sanitizers 2 m with a smaller camera).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam/hal/file_block_device.h"
#include "seqslam/odometry.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/dream.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_tools/dream_images.h"
#include "seqslam_tools/q_format.h"
#include "sim_test_util.h"
#include "test_log.h"

#if defined(__SANITIZE_ADDRESS__)
#define SEQSLAM_SIM_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SEQSLAM_SIM_TEST_SANITIZED 1
#endif
#endif

namespace seqslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
#if defined(SEQSLAM_SIM_TEST_SANITIZED)
// Under the sanitizers a render costs ~15 times as much: 2 m (~10 places) and a camera with
// a quarter of the pixels (the same optics).
constexpr double kLegLength = 2.0;
constexpr uint16_t kCameraWidth = 173;
constexpr uint16_t kCameraHeight = 136;
#else
constexpr double kLegLength = 6.0;  // ~30 places
constexpr uint16_t kCameraWidth = hal::kCameraWidth;
constexpr uint16_t kCameraHeight = hal::kCameraHeight;
#endif

RunSpec short_run(uint64_t seed, unsigned threads) {
  RunSpec spec;
  spec.name = "south";
  spec.light = "noon-lamps";
  spec.seed = seed;
  spec.threads = threads;
  spec.legs = {Leg{{{6.0, lab::kSouthLane}, {6.0 + kLegLength, lab::kSouthLane}}, false}};
  spec.camera.width = kCameraWidth;
  spec.camera.height = kCameraHeight;
  // The plain reduction of this camera's frame to 32x16 (reduction(32, 16) on the robot's).
  spec.mapping.a11 = Q15_16::from_ratio(32, kCameraWidth);
  spec.mapping.a22 = Q15_16::from_ratio(16, kCameraHeight);
  return spec;
}

// Signed heading difference in radians (shorter way round).
double heading_diff(const Pose2& p, double heading) {
  const double h = tools::to_radians(p.heading);
  return std::remainder(h - heading, 2 * kPi);
}

TEST(SimRun, FilesAreDeterministic) {
  test::ScratchDir one("one"), two("two"), threads("threads"), other("other");
  RunSummary s1, s2, s3, s4;
  ASSERT_EQ(generate_run(short_run(7, 1), one.path(), &s1), "");
  ASSERT_EQ(generate_run(short_run(7, 1), two.path(), &s2), "");
  ASSERT_EQ(generate_run(short_run(7, 2), threads.path(), &s3), "");
  ASSERT_EQ(generate_run(short_run(8, 1), other.path(), &s4), "");
  seqslam::test::log_figure("sim.run.short_leg.places", static_cast<double>(s1.places.size()));
  seqslam::test::log_figure("sim.run.short_leg.seconds_per_run", s1.seconds);
  ASSERT_GT(s1.places.size(), 5u);
  bool ok = false;
  const std::vector<char> dream1 = test::read_bytes(one.path() + "/south.dream", &ok);
  ASSERT_TRUE(ok);
  const std::vector<char> truth1 = test::read_bytes(one.path() + "/south.truth.csv", &ok);
  ASSERT_TRUE(ok);
  EXPECT_GT(dream1.size(), s1.places.size() * 512);
  EXPECT_TRUE(dream1 == test::read_bytes(two.path() + "/south.dream")) << "same spec, same dir";
  EXPECT_TRUE(truth1 == test::read_bytes(two.path() + "/south.truth.csv"));
  EXPECT_TRUE(dream1 == test::read_bytes(threads.path() + "/south.dream")) << "2 threads";
  EXPECT_TRUE(truth1 == test::read_bytes(threads.path() + "/south.truth.csv")) << "2 threads";
  EXPECT_FALSE(dream1 == test::read_bytes(other.path() + "/south.dream")) << "other seed";
  EXPECT_EQ(s1.places.size(), s2.places.size());
  EXPECT_EQ(s1.snapshots, s3.snapshots);
  EXPECT_EQ(s1.end_error_m, s2.end_error_m);
}

TEST(SimRun, DreamAgreesWithSummaryAndFirmwareCaptures) {
  test::ScratchDir dir;
  RunSummary s;
  ASSERT_EQ(generate_run(short_run(3, 1), dir.path(), &s), "");
  const std::string path = dir.path() + "/south.dream";
  ASSERT_GT(s.places.size(), 5u);
  EXPECT_EQ(s.name, "south");
  EXPECT_EQ(s.light, "noon-lamps");
  EXPECT_NEAR(s.length_m, kLegLength, 0.3);
  EXPECT_LE(s.max_lateral_m, 0.5 + 0.1);

  // The places as the tools read them.
  const tools::Outcome<tools::DreamPlaces> loaded = tools::load_dream_places(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const tools::DreamPlaces& places = loaded.value();
  ASSERT_EQ(places.images.size(), s.places.size());
  ASSERT_TRUE(places.has_truth);
  EXPECT_EQ(places.snapshots, s.snapshots);
  double worst_truth_m = 0.0;
  for (size_t i = 0; i < s.places.size(); ++i) {
    const PlaceTruth& t = s.places[i];
    EXPECT_EQ(t.index, i);
    EXPECT_EQ(places.images[i].width, 32);
    EXPECT_EQ(places.images[i].height, 16);
    EXPECT_NEAR(tools::to_double(places.truth[i].x), t.truth.x, 1e-6) << "place " << i;
    EXPECT_NEAR(tools::to_double(places.truth[i].y), t.truth.y, 1e-6) << "place " << i;
    EXPECT_NEAR(heading_diff(places.truth[i], t.truth.heading), 0.0, 1e-6) << "place " << i;
    EXPECT_NEAR(tools::to_double(places.odometry[i].x), t.odometry.x, 1e-6) << "place " << i;
    EXPECT_NEAR(tools::to_double(places.odometry[i].y), t.odometry.y, 1e-6) << "place " << i;
    EXPECT_NEAR(heading_diff(places.odometry[i], t.odometry.heading), 0.0, 1e-6);
    worst_truth_m =
        std::max(worst_truth_m, std::hypot(tools::to_double(places.truth[i].x) - t.truth.x,
                                           tools::to_double(places.truth[i].y) - t.truth.y));
    // A rendered image, not an empty buffer.
    uint8_t lo = 255, hi = 0;
    for (uint8_t p : places.images[i].pixels) {
      lo = std::min(lo, p);
      hi = std::max(hi, p);
    }
    EXPECT_GT(hi - lo, 20) << "place " << i;
  }
  seqslam::test::log_figure("sim.run.truth_pose_roundtrip_worst_m", worst_truth_m);
  // Places 20 cm apart by odometry, i.e. about 20 cm apart in truth too.
  for (size_t i = 1; i < s.places.size(); ++i) {
    const double d = std::hypot(s.places[i].truth.x - s.places[i - 1].truth.x,
                                s.places[i].truth.y - s.places[i - 1].truth.y);
    EXPECT_NEAR(d, 0.2, 0.02) << "place " << i;
  }

  // The recording replayed through the firmware's capture logic: a place record right after
  // every snapshot that triggers, none elsewhere, each with that snapshot's sequence and the
  // odometry pose bit for bit, then its truth record.
  hal::FileBlockDevice device;
  ASSERT_EQ(device.open(path, false), Status::kOk) << device.error();
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  ASSERT_EQ(reader.open(device, Span<uint8_t>(buffer.data(), buffer.size())), Status::kOk);
  const storage::DreamHeader& h = reader.header();
  EXPECT_EQ(h.variant, storage::DreamVariant::kFull);
  EXPECT_TRUE(h.mapping == short_run(3, 1).mapping);
  if (kCameraWidth == hal::kCameraWidth && kCameraHeight == hal::kCameraHeight) {
    EXPECT_TRUE(h.mapping == hal::PipelineMapping::reduction(32, 16));
  }
  EXPECT_EQ(h.mapping.xmax, 32);
  EXPECT_EQ(h.mapping.ymax, 16);
  EXPECT_EQ(h.camera_width, kCameraWidth);
  EXPECT_EQ(h.camera_height, kCameraHeight);
  EXPECT_EQ(h.infrared_count, 6);
  Odometry odometry;
  ASSERT_EQ(odometry.configure(h.wheels), Status::kOk);
  SpatialTrigger trigger;
  ASSERT_EQ(trigger.configure(h.spacing), Status::kOk);
  EXPECT_EQ(h.spacing, SpatialTrigger::kDefaultSpacing);
  const OdometryConfig firmware{};
  EXPECT_EQ(h.wheels.circumference_left, firmware.circumference_left);
  EXPECT_EQ(h.wheels.circumference_right, firmware.circumference_right);
  EXPECT_EQ(h.wheels.track_width, firmware.track_width);
  bool first = true;
  bool place_due = false;
  hal::SensorSnapshot trigger_snapshot{};
  Pose2 trigger_pose{};
  uint32_t snapshots = 0, place_count = 0, truths = 0;
  for (;;) {
    storage::DreamItem item;
    const Status st = reader.next(&item);
    if (st == Status::kOutOfRange) break;
    ASSERT_EQ(st, Status::kOk) << storage::dream_problem_text(reader.problem());
    switch (item.type) {
      case storage::DreamRecord::kSnapshot: {
        ASSERT_FALSE(place_due) << "snapshot " << trigger_snapshot.sequence
                                << " triggers a capture but no place follows it";
        const hal::SensorSnapshot& snap = item.snapshot;
        if (first) {
          odometry.reset(Pose2{}, snap.encoder_left, snap.encoder_right);
          first = false;
        } else {
          ASSERT_EQ(odometry.update(snap.encoder_left, snap.encoder_right), Status::kOk);
        }
        if (trigger.update(odometry.pose())) {
          place_due = true;
          trigger_snapshot = snap;
          trigger_pose = odometry.pose();
        }
        ++snapshots;
        break;
      }
      case storage::DreamRecord::kPlace: {
        ASSERT_TRUE(place_due) << "place " << item.place.index
                               << " follows a snapshot that does not trigger";
        const storage::DreamPlace& p = item.place;
        EXPECT_EQ(p.index, place_count);
        EXPECT_EQ(p.bus_sequence, trigger_snapshot.sequence);
        EXPECT_EQ(p.timestamp_us, trigger_snapshot.timestamp_us);
        EXPECT_EQ(p.encoder_left, trigger_snapshot.encoder_left);
        EXPECT_EQ(p.encoder_right, trigger_snapshot.encoder_right);
        EXPECT_EQ(p.pose.x.raw(), trigger_pose.x.raw());
        EXPECT_EQ(p.pose.y.raw(), trigger_pose.y.raw());
        EXPECT_EQ(p.pose.heading.bam, trigger_pose.heading.bam);
        EXPECT_EQ(p.size.width, 32);
        EXPECT_EQ(p.size.height, 16);
        ASSERT_LT(place_count, s.places.size());
        EXPECT_EQ(p.timestamp_us, s.places[place_count].timestamp_us);
        place_due = false;
        ++place_count;
        break;
      }
      case storage::DreamRecord::kTruth:
        EXPECT_EQ(item.truth.place_index + 1, place_count);
        ++truths;
        break;
      case storage::DreamRecord::kReducedPlace:
        ADD_FAILURE() << "a reduced place in a full recording";
        break;
    }
  }
  EXPECT_EQ(reader.log_problem(), storage::LogProblem::kEndClean);
  EXPECT_FALSE(place_due);
  EXPECT_EQ(snapshots, s.snapshots);
  EXPECT_EQ(place_count, s.places.size());
  EXPECT_EQ(place_count, trigger.captures());
  EXPECT_EQ(truths, place_count);

  // The truth table: a header and one row per place, matching the summary (4 decimals).
  std::ifstream csv(dir.path() + "/south.truth.csv");
  ASSERT_TRUE(csv);
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "place,timestamp_us,true_x,true_y,true_heading_deg,odo_x,odo_y,odo_heading_deg");
  size_t rows = 0;
  while (std::getline(csv, line)) {
    unsigned index = 0, time = 0;
    double tx = 0, ty = 0, th = 0, ox = 0, oy = 0, oh = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%u,%u,%lf,%lf,%lf,%lf,%lf,%lf", &index, &time, &tx, &ty,
                          &th, &ox, &oy, &oh),
              8)
        << line;
    ASSERT_LT(rows, s.places.size());
    const PlaceTruth& p = s.places[rows];
    EXPECT_EQ(index, p.index);
    EXPECT_EQ(time, p.timestamp_us);
    EXPECT_NEAR(tx, p.truth.x, 6e-5);
    EXPECT_NEAR(ty, p.truth.y, 6e-5);
    EXPECT_NEAR(ox, p.odometry.x, 6e-5);
    EXPECT_NEAR(oy, p.odometry.y, 6e-5);
    EXPECT_NEAR(std::remainder(th - p.truth.heading * 180 / kPi, 360.0), 0.0, 6e-4);
    ++rows;
  }
  EXPECT_EQ(rows, s.places.size());
}

TEST(SimRun, BadSpecsAreErrors) {
  test::ScratchDir dir;
  RunSummary s;
  RunSpec spec = short_run(1, 1);
  spec.light = "twilight";
  EXPECT_NE(generate_run(spec, dir.path(), &s), "");
  spec = short_run(1, 1);
  spec.mapping.xmax = 0;
  EXPECT_NE(generate_run(spec, dir.path(), &s), "");
  spec = short_run(1, 1);
  spec.legs.clear();
  EXPECT_NE(generate_run(spec, dir.path(), &s), "");
  spec = short_run(1, 1);
  EXPECT_NE(generate_run(spec, dir.path() + "/no/such/dir", &s), "");
}

}  // namespace
}  // namespace seqslam::sim
