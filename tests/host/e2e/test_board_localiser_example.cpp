// The integrator's example (firmware/example, README "Using the library"): the board's
// localiser driven snapshot by snapshot from a recorded run, the library and the query
// history on a card. Its answers equal the core configured as the firmware configures it
// (CoreRun) on the same images, and a refused start leaves the card's library as it was.
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "board_localiser.h"
#include "core_run.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream_replay.h"
#include "synthetic_run.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 70;

struct Card {
  std::vector<uint8_t> bytes = std::vector<uint8_t>(8u << 20, 0xEE);
  hal::FakeBlockDevice device{Span<uint8_t>(bytes.data(), bytes.size())};
  storage::Volume volume;

  void format(bool with_queries) {
    const storage::VolumeFile files[] = {
        {"replay", 0, 4096}, {"library", 0, 64}, {"library.img", 0, 256}, {"queries", 0, 512}};
    ASSERT_EQ(storage::Volume::format(device, files, with_queries ? 4 : 3), Status::kOk);
    ASSERT_EQ(volume.mount(device), Status::kOk);
  }
  storage::Region file(const char* name) {
    storage::Region r;
    EXPECT_EQ(volume.open(name, &r), Status::kOk);
    return r;
  }
};

test::RunOptions lit_run() {
  test::RunOptions o;
  o.places = kPlaces;
  return o;
}
test::RunOptions dim_run() {  // the same route in other light, with noise
  test::RunOptions o = lit_run();
  o.gain_q8 = 190;
  o.offset = 25;
  o.noise = 6;
  o.noise_seed = 2;
  o.start_count = 0x00001234u;
  return o;
}

// The recording in the card's replay file, snapshot by snapshot through the example, as the
// integrator's main loop would feed it: the steps of the places it took.
std::vector<session::PlaceStep> run_example(Card& card, const storage::RunConfig& config,
                                            Status* start_status,
                                            example::StartIssue* issue = nullptr) {
  std::vector<session::PlaceStep> steps;
  storage::Region replay_file = card.file("replay");
  std::vector<uint8_t> record(storage::kDreamRecordMax);
  storage::DreamReplay replay;
  EXPECT_EQ(replay.open(replay_file, Span<uint8_t>(record.data(), record.size())), Status::kOk);
  auto localiser = std::make_unique<example::BoardLocaliser>();
  *start_status = localiser->start(card.device, replay, config, issue);
  if (*start_status != Status::kOk) return steps;
  hal::SensorSnapshot snap;
  while (replay.next(&snap) == Status::kOk) {
    bool placed = false;
    session::PlaceStep step;
    EXPECT_EQ(localiser->on_snapshot(snap, &placed, &step), Status::kOk);
    if (placed) steps.push_back(step);
  }
  return steps;
}

TEST(BoardLocaliserExample, RepeatEqualsTheCoreConfiguredAsTheFirmware) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4242, 2048, 16);
  auto card = std::make_unique<Card>();
  card->format(true);
  storage::Region replay = card->file("replay");

  ASSERT_EQ(test::write_synthetic_run(replay, *world, lit_run()), kPlaces);
  const auto lit = test::place_images(replay);
  const storage::RunConfig teach = test::synthetic_run_config(storage::kModeTeach);
  Status s;
  const auto taught = run_example(*card, teach, &s);
  ASSERT_EQ(s, Status::kOk);
  ASSERT_EQ(taught.size(), kPlaces);
  for (const session::PlaceStep& step : taught) {
    EXPECT_TRUE(step.taught);
    EXPECT_FALSE(step.matched);
  }

  ASSERT_EQ(test::write_synthetic_run(replay, *world, dim_run()), kPlaces);
  const auto dim = test::place_images(replay);
  const storage::RunConfig repeat = test::synthetic_run_config(storage::kModeRepeat);
  const auto repeated = run_example(*card, repeat, &s);
  ASSERT_EQ(s, Status::kOk);
  ASSERT_EQ(repeated.size(), kPlaces);

  test::CoreRun<kPlaces> core(repeat.localiser());
  ASSERT_TRUE(core.ok());
  ASSERT_TRUE(core.teach(lit));
  uint32_t localised = 0, correct = 0;
  for (size_t i = 0; i < dim.size(); ++i) {
    Match m;
    ASSERT_TRUE(core.localise(dim[i], &m));
    const session::PlaceStep& step = repeated[i];
    ASSERT_TRUE(step.matched && step.routed) << i;
    EXPECT_EQ(step.match.place, m.place) << i;
    EXPECT_EQ(step.match.runner_up, m.runner_up) << i;
    EXPECT_EQ(step.match.cost, m.cost) << i;
    EXPECT_EQ(step.match.confidence.raw(), m.confidence.raw()) << i;
    EXPECT_EQ(step.match.localised, m.localised) << i;
    if (m.localised) ++localised;
    const int32_t err = m.place - static_cast<int32_t>(i);
    if (m.localised && err >= -1 && err <= 1) ++correct;
  }
  // Not vacuous: the repeat localises most of the run, correctly.
  EXPECT_GT(localised, kPlaces / 2);
  EXPECT_EQ(correct, localised);
}

TEST(BoardLocaliserExample, ARefusedStartLeavesTheCardsLibrary) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4242, 2048, 16);
  auto card = std::make_unique<Card>();
  card->format(false);  // no query history: a repeat is refused
  storage::Region replay = card->file("replay");
  ASSERT_EQ(test::write_synthetic_run(replay, *world, lit_run()), kPlaces);
  Status s;
  ASSERT_EQ(run_example(*card, test::synthetic_run_config(storage::kModeTeach), &s).size(),
            kPlaces);
  ASSERT_EQ(s, Status::kOk);
  const std::vector<uint8_t> taught = card->bytes;

  example::StartIssue issue = example::StartIssue::kNone;
  storage::RunConfig c = test::synthetic_run_config(storage::kModeRepeat);
  EXPECT_TRUE(run_example(*card, c, &s, &issue).empty());
  EXPECT_EQ(s, Status::kNotFound);
  EXPECT_EQ(issue, example::StartIssue::kFiles);
  // Teaching again with settings the board cannot run, or another image size than the
  // recording's, is refused before the library is written over.
  c = test::synthetic_run_config(storage::kModeTeach);
  c.sequence.seq_len = profile::kMaxSeqLen + 1;
  EXPECT_TRUE(run_example(*card, c, &s, &issue).empty());
  EXPECT_EQ(issue, example::StartIssue::kSettings);
  c = test::synthetic_run_config(storage::kModeTeach);
  c.mapping = hal::PipelineMapping::reduction(12, 10);
  EXPECT_TRUE(run_example(*card, c, &s, &issue).empty());
  EXPECT_EQ(s, Status::kFailedPrecondition);
  EXPECT_EQ(issue, example::StartIssue::kCamera);
  c = test::synthetic_run_config(storage::kModeTeach | storage::kModeRepeat);
  EXPECT_TRUE(run_example(*card, c, &s, &issue).empty());
  EXPECT_EQ(issue, example::StartIssue::kModes);
  EXPECT_EQ(card->bytes, taught);
}

}  // namespace
}  // namespace seqslam
