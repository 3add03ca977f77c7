// The settings table (storage/run_config.h) and what is derived from it: the card's codec, the
// range check, every subcommand's options and `config show` (tools/common settings_cli.h).
//
// ExampleSettings shows what adding a setting takes: one entry in a table plus its use. It
// extends the run configuration's table with an example threshold; the generic machinery gives
// it an option with its range and default, a config show row, bytes on the card and a place
// in the check, with no other code.
#include <CLI/CLI.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "seqslam/storage/run_config.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/settings_codec.h"
#include "seqslam_tools/settings_cli.h"

namespace seqslam {
namespace {

using storage::RunConfig;
using storage::Setting;
using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------
// The example: one new setting.

struct ExampleConfig : RunConfig {
  UQ16_16 example_threshold = UQ16_16::from_ratio(1, 2);  // its use would go here
};

struct ExampleSettings {
  template <class V, class C>
  void operator()(V& v, C& c) const {
    storage::visit_run_settings(v, c);
    v(c.example_threshold,  // the entry: name, range, scope, card version, help
      storage::setting("example-threshold", 0, UQ16_16::from_int(1).raw(),
                       storage::kScopeSequence, 5, "An example threshold (0..1)"));
  }
};

// The table's settings, in order.
struct Names {
  std::vector<std::string> names;
  std::vector<Setting> settings;
  template <class T>
  void operator()(const T&, const Setting& s) {
    names.push_back(s.name);
    settings.push_back(s);
  }
  void pad(uint32_t) {}
};

template <class Table, class Config>
Names names_of() {
  Names n;
  const Config c{};
  Table{}(n, c);
  return n;
}

// Parses `args` with the table's options on a fresh CLI11 app: "" or CLI11's error.
template <class Table, class Config>
std::string parse(const std::vector<std::string>& args, Config* out) {
  CLI::App app;
  cli::SettingOptions<Table, Config> options;
  options.add(&app, Config{}, {});
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  options.apply(out);
  return {};
}

TEST(ExampleSetting, HasAnOptionWithItsRangeAndDefault) {
  ExampleConfig c;
  EXPECT_EQ(parse<ExampleSettings>({"--example-threshold", "0.25"}, &c), "");
  EXPECT_EQ(c.example_threshold.raw(), UQ16_16::from_ratio(1, 4).raw());
  ExampleConfig untouched;
  EXPECT_EQ(parse<ExampleSettings>({"--seq-len", "12"}, &untouched), "");
  EXPECT_EQ(untouched.example_threshold.raw(), UQ16_16::from_ratio(1, 2).raw());
  EXPECT_EQ(untouched.sequence.seq_len, 12u);
  ExampleConfig refused;
  EXPECT_THAT(parse<ExampleSettings>({"--example-threshold", "2"}, &refused),
              HasSubstr("is not within 0..1"));
  CLI::App app;
  cli::SettingOptions<ExampleSettings, ExampleConfig> options;
  options.add(&app, ExampleConfig{}, {});
  EXPECT_THAT(app.help(), HasSubstr("--example-threshold X"));
  EXPECT_THAT(app.help(), HasSubstr("An example threshold (0..1). Default 0.5"));
}

TEST(ExampleSetting, IsAConfigShowRowAndAnOption) {
  ExampleConfig c;
  c.example_threshold = UQ16_16::from_ratio(3, 4);
  bool found = false;
  for (const cli::SettingRow& r : cli::setting_rows<ExampleSettings>(c)) {
    if (r.name == "example-threshold") {
      found = true;
      EXPECT_EQ(r.value, "0.75");
    }
  }
  EXPECT_TRUE(found);
  const std::string options = cli::setting_options_text<ExampleSettings>(c, 0xFFFF, true);
  EXPECT_THAT(options, HasSubstr("--example-threshold 0.75"));
  // The options written reproduce the configuration.
  std::vector<std::string> args;
  std::string word;
  for (const char ch : options + " ") {
    if (ch != ' ') {
      word += ch;
    } else if (!word.empty()) {
      args.push_back(word);
      word.clear();
    }
  }
  ExampleConfig back;
  ASSERT_EQ(parse<ExampleSettings>(args, &back), "");
  EXPECT_EQ(back.example_threshold.raw(), c.example_threshold.raw());
}

TEST(ExampleSetting, IsOnTheCardAfterTheOthers) {
  ExampleConfig c;
  c.example_threshold = UQ16_16::from_ratio(1, 8);
  uint8_t base[storage::kLogHeaderPayloadMax];
  uint8_t extended[storage::kLogHeaderPayloadMax];
  const uint32_t n = storage::encode_settings(storage::RunSettings{}, c, base, sizeof base);
  const uint32_t m = storage::encode_settings(ExampleSettings{}, c, extended, sizeof extended);
  ASSERT_EQ(m, n + 4);  // a UQ16.16 is four bytes
  EXPECT_EQ(std::vector<uint8_t>(base, base + n), std::vector<uint8_t>(extended, extended + n));
  ExampleConfig back;
  ASSERT_TRUE(storage::decode_settings(ExampleSettings{}, extended, m, &back));
  EXPECT_EQ(back.example_threshold.raw(), c.example_threshold.raw());
  // A card without it is too short for this table.
  EXPECT_FALSE(storage::decode_settings(ExampleSettings{}, extended, n, &back));
}

TEST(ExampleSetting, IsInTheCheck) {
  ExampleConfig c;
  EXPECT_EQ(storage::first_setting_out_of_range(ExampleSettings{}, c), -1);
  c.example_threshold = UQ16_16::from_ratio(3, 2);
  const Names n = names_of<ExampleSettings, ExampleConfig>();
  const int16_t at = storage::first_setting_out_of_range(ExampleSettings{}, c);
  ASSERT_GE(at, 0);
  EXPECT_EQ(n.names[static_cast<size_t>(at)], "example-threshold");
  EXPECT_EQ((cli::setting_name<ExampleSettings, ExampleConfig>(at)), "example-threshold");
}

// ---------------------------------------------------------------------------------------
// The run configuration's own table.

TEST(RunSettings, NamesAreUniqueAndEveryEntryIsComplete) {
  const Names n = names_of<storage::RunSettings, RunConfig>();
  std::set<std::string> unique(n.names.begin(), n.names.end());
  EXPECT_EQ(unique.size(), n.names.size());
  for (const Setting& s : n.settings) {
    EXPECT_LE(s.min, s.max) << s.name;
    EXPECT_NE(s.help, nullptr) << s.name;
    EXPECT_NE(s.scope, 0u) << s.name;
  }
}

TEST(RunSettings, CardSettingsComeInVersionOrderBeforeThePcOnes) {
  const Names n = names_of<storage::RunSettings, RunConfig>();
  uint8_t last = 1;
  bool pc_only = false;
  for (const Setting& s : n.settings) {
    if (s.since == storage::kPcOnly) {
      pc_only = true;
      continue;
    }
    EXPECT_FALSE(pc_only) << s.name << " is on the card after a PC-only setting";
    EXPECT_GE(s.since, last) << s.name;
    EXPECT_LE(s.since, storage::kRunConfigVersion) << s.name;
    last = s.since;
  }
}

TEST(RunSettings, DefaultsAreWithinTheRangesAndTheCardHoldsVersion4Layout) {
  EXPECT_EQ(storage::first_setting_out_of_range(storage::RunSettings{}, RunConfig{}), -1);
  EXPECT_TRUE(storage::check_run_settings(RunConfig{}).ok());
  uint8_t payload[storage::kLogHeaderPayloadMax];
  // 140 bytes: the version-4 layout docs/dream_format.md documents.
  EXPECT_EQ(storage::encode_settings(storage::RunSettings{}, RunConfig{}, payload, sizeof payload),
            140u);
}

TEST(RunSettings, EveryValueReadsBackFromItsText) {
  RunConfig c;
  c.sequence.threshold = UQ16_16::from_raw(12345);
  c.route.growth = UQ8_8::from_raw(77);
  c.explore.gate.heading_base = Angle::from_degrees(17, 3);
  c.explore.hfov = Angle{0x12345678u};
  c.route.start = -1;
  c.spacing = Q31_32::from_ratio(7, 31);
  const std::string options = cli::setting_options_text(c, 0xFFFF, false);
  std::vector<std::string> args;
  std::string word;
  for (const char ch : options + " ") {
    if (ch != ' ') {
      word += ch;
    } else if (!word.empty()) {
      args.push_back(word);
      word.clear();
    }
  }
  RunConfig back;
  ASSERT_EQ((parse<storage::RunSettings, RunConfig>(args, &back)), "") << options;
  uint8_t a[storage::kLogHeaderPayloadMax];
  uint8_t b[storage::kLogHeaderPayloadMax];
  const uint32_t n = storage::encode_settings(storage::RunSettings{}, c, a, sizeof a);
  ASSERT_EQ(storage::encode_settings(storage::RunSettings{}, back, b, sizeof b), n);
  EXPECT_EQ(std::vector<uint8_t>(a, a + n), std::vector<uint8_t>(b, b + n));
  EXPECT_EQ(back.explore.gate.heading_base.bam, c.explore.gate.heading_base.bam);
  EXPECT_EQ(back.explore.hfov.bam, c.explore.hfov.bam);
}

TEST(RunSettings, BadValuesNameTheRange) {
  RunConfig c;
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--seq-len", "0"}, &c)),
              HasSubstr("'0' is not within 1..100 places"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--threshold", "1.5"}, &c)),
              HasSubstr("'1.5' is not within 0..1"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--route-growth", "0.001"}, &c)),
              HasSubstr("below half the smallest step of UQ8.8 (1/256 = 0.00390625)"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--matcher", "spiral"}, &c)),
              HasSubstr("'spiral' is not one of diagonal, heuristic, slope"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--modes", "teach,fly"}, &c)),
              HasSubstr("'fly' is not one of teach"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--heading-base", "181"}, &c)),
              HasSubstr("'181' is not within 0..180 deg"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--start", "-2"}, &c)),
              HasSubstr("is not a library place"));
  EXPECT_THAT((parse<storage::RunSettings, RunConfig>({"--seq-len", "nan"}, &c)),
              HasSubstr("is not a whole number"));
}

}  // namespace
}  // namespace seqslam
