// The firmware application's messages say what is wrong (issue 34): a card that fails to
// write the results file is not told it lacks one, and a replay that is not a recording names
// the log's own problem instead of "(see the log problem)" with none after it.
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "app.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/record_log.h"
#include "seqslam/storage/run_files.h"
#include "synthetic_run.h"

namespace seqslam {
namespace {

// A card whose writes to blocks [first, first + count) fail (a full or failing card there).
class FailingRange final : public hal::BlockDevice {
 public:
  explicit FailingRange(hal::BlockDevice& device) : device_(device) {}
  void fail(uint32_t first, uint32_t count) {
    first_ = first;
    count_ = count;
  }

 private:
  uint32_t do_block_count() const override { return device_.block_count(); }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    return device_.read(first, count, out);
  }
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    if (first < first_ + count_ && first + count > first_) return Status::kDataLoss;
    return device_.write(first, count, data);
  }
  Status do_sync() override { return device_.sync(); }

  hal::BlockDevice& device_;
  uint32_t first_ = 0;
  uint32_t count_ = 0;
};

std::string g_console;
void capture_console(const char* text) {
  g_console += text;
}

struct Card {
  std::vector<uint8_t> bytes = std::vector<uint8_t>(4u << 20, 0);
  hal::FakeBlockDevice fake{Span<uint8_t>(bytes.data(), bytes.size())};
  FailingRange device{fake};
  storage::Volume volume;

  // The volume with `count` of these files (the results file last, so it can be left out).
  void format(uint32_t count) {
    const storage::VolumeFile files[] = {
        {"config", 0, 2},        {"replay", 0, 4096}, {"library", 0, 64},
        {"library.img", 0, 256}, {"queries", 0, 512}, {"results", 0, 64},
    };
    ASSERT_EQ(storage::Volume::format(device, files, count), Status::kOk);
    ASSERT_EQ(volume.mount(device), Status::kOk);
  }
  storage::Region file(const char* name) {
    storage::Region r;
    EXPECT_EQ(volume.open(name, &r), Status::kOk);
    return r;
  }
  Status start(uint8_t modes) {
    storage::RunConfig config = test::synthetic_run_config(modes);
    storage::Region c = file("config");
    EXPECT_EQ(storage::write_run_config(c, config), Status::kOk);
    auto application = std::make_unique<app::Application>();
    g_console.clear();
    return application->start(volume, nullptr, nullptr, capture_console);
  }
};

void write_run(Card& card) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4242, 2048, 16);
  storage::Region replay = card.file("replay");
  test::RunOptions o;
  o.places = 40;
  ASSERT_EQ(test::write_synthetic_run(replay, *world, o), o.places);
}

TEST(FirmwareMessages, AResultsFileTheCardFailsToWriteIsNotAMissingOne) {
  auto card = std::make_unique<Card>();
  card->format(6);
  write_run(*card);
  // The results file is the volume's last: its blocks end the used part of the card.
  uint32_t first = 1;
  for (uint32_t i = 0; i + 1 < card->volume.file_count(); ++i)
    first += card->volume.file(i).block_count;
  card->device.fail(first, 64);
  EXPECT_EQ(card->start(storage::kModeTeach | storage::kModeRepeat), Status::kDataLoss);
  EXPECT_NE(g_console.find(std::string("app: results file: DATA_LOSS - ") +
                           storage::log_problem_text(storage::LogProblem::kDeviceError)),
            std::string::npos)
      << g_console;
  EXPECT_EQ(g_console.find("needs a 'results' file"), std::string::npos) << g_console;
  // Without the file, that is what it says.
  auto bare = std::make_unique<Card>();
  bare->format(5);
  write_run(*bare);
  EXPECT_EQ(bare->start(storage::kModeTeach | storage::kModeRepeat), Status::kNotFound);
  EXPECT_NE(g_console.find("app: results file: NOT_FOUND - the volume needs a "
                           "'results' file"),
            std::string::npos)
      << g_console;
}

TEST(FirmwareMessages, AReplayThatIsNoRecordingNamesTheLogsProblem) {
  auto card = std::make_unique<Card>();
  card->format(6);  // the replay file is all zeros
  EXPECT_EQ(card->start(storage::kModeTeach), Status::kDataLoss);
  EXPECT_NE(g_console.find(std::string("app: replay: DATA_LOSS - ") +
                           storage::log_problem_text(storage::LogProblem::kWrongKind) + "\n"),
            std::string::npos)
      << g_console;
  EXPECT_EQ(g_console.find("see the log problem"), std::string::npos) << g_console;
}

}  // namespace
}  // namespace seqslam
