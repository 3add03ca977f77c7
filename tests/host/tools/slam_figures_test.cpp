// The figures JSON of `seqslam slam` (seqslam_tools/slam_figures.h): written then read back
// unchanged, keys in the documented order, and every kind of bad input refused with a message
// naming the document and the key (or the parse position).
#include "seqslam_tools/slam_figures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace seqslam::tools::test {
namespace {

const char kPath[] = "runs/slam.json";

// Every member set to a distinct value; the groups as asked.
SlamFigures sample(bool truth, bool map) {
  SlamFigures f;
  f.places = 1234;
  f.runs = 2;
  for (uint32_t c = 0; c < kLoopClosureClasses; ++c)
    f.decisions[c] = 100 + c;
  f.rejected_position = 7;
  f.rejected_heading = 8;
  f.rejected_image = 9;
  f.closures = 41;
  f.optimiser_work = uint64_t{1} << 40;  // beyond 32 bits
  f.slices = 17;
  f.final_slices = 3;
  f.max_solve_places = 250;
  f.wheels = "0.52,0.521,0.3";
  f.closure_heading = "image";
  f.hfov_deg = 50.0;
  f.align_length = 15;
  f.align_range = 5;
  f.align_shift = -2;
  f.closures_realigned = 6;
  if (truth) {
    SlamTruthFigures t;
    t.rmse_dead_reckoning_m = 1.2345678901234567;
    t.rmse_corrected_m = 0.1;  // not exact in binary: must still read back equal
    t.rmse_online_m = 1.0 / 3.0;
    t.max_error_dead_reckoning_m = 3.5;
    t.max_error_corrected_m = 0.75;
    t.false_closures = 1;
    t.largest_closure_true_distance_m = 2.0000001;
    t.closure_heading_error_rms_deg = 4.25;
    t.closure_same_heading_error_rms_deg = 12.5;
    t.closure_along_error_rms_m = 0.0625;
    t.closure_gate_along_error_rms_m = 1e-9;
    t.events = {{120, "kidnap", 14}, {500, "known ground again", -1}};
    f.truth = t;
  }
  if (map) {
    SlamMapFigures m;
    m.map_accuracy_corrected = 0.9876543210987654;
    m.map_cells_corrected = 5000000000ull;
    m.map_accuracy_dead_reckoning = 0.5;
    m.map_cells_dead_reckoning = 123456;
    SlamNearPathFigures n;
    n.band_m = 1.0;
    n.corrected = {5000, 400, 30, 3000, 5, 12, 20};
    n.dead_reckoning = {5000, 400, 60, 2500, 2, 9, 11};
    m.near_path = n;
    f.map = m;
  }
  f.unreliable_places = 11;
  f.relocalisations = 4;
  f.align_failures = 2;
  f.heading_failures = 5;
  f.closure_lateral = 0.03;
  return f;
}

std::string parse_error(const std::string& text) {
  const Outcome<SlamFigures> r = parse_slam_figures(text, kPath);
  EXPECT_FALSE(r.ok()) << text;
  return r.error();
}

// `text` with the first occurrence of `from` replaced by `to` (which must be there).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The line holding `"key": ...` removed (the previous line's comma is left: only for keys
// that are not the last of their object).
std::string without_key(std::string text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\":");
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return text;
  const size_t begin = text.rfind('\n', at) + 1;
  const size_t end = text.find('\n', at);
  text.erase(begin, end - begin + 1);
  return text;
}

TEST(SlamFigures, RoundTripWithAndWithoutTruthAndMap) {
  for (const bool truth : {false, true}) {
    for (const bool map : {false, true}) {
      const SlamFigures f = sample(truth, map);
      const std::string text = slam_figures_json(f);
      ASSERT_FALSE(text.empty());
      EXPECT_EQ(text.back(), '\n');
      const Outcome<SlamFigures> back = parse_slam_figures(text, kPath);
      ASSERT_TRUE(back.ok()) << back.error() << "\n" << text;
      EXPECT_TRUE(back.value() == f) << "truth " << truth << ", map " << map << "\n" << text;
      EXPECT_EQ(back.value().truth.has_value(), truth);
      EXPECT_EQ(back.value().map.has_value(), map);
      EXPECT_EQ(slam_figures_json(back.value()), text);
    }
  }
  // The comparison itself sees a difference (else the round trip proves nothing).
  SlamFigures a = sample(true, true), b = a;
  b.truth->events[1].relocalised_after = 3;
  EXPECT_TRUE(a != b);
  b = a;
  b.map->map_cells_dead_reckoning += 1;
  EXPECT_TRUE(a != b);
  b = a;
  b.map->near_path->dead_reckoning.truth_occupied_near_grid += 1;
  EXPECT_TRUE(a != b);
  b = a;
  b.map->near_path.reset();
  EXPECT_TRUE(a != b);
  b = a;
  b.align_failures = 0;
  EXPECT_TRUE(a != b);
  b = a;
  b.heading_failures = 0;
  EXPECT_TRUE(a != b);
  b = a;
  b.closure_lateral = 1.0;
  EXPECT_TRUE(a != b);
}

TEST(SlamFigures, KeysInTheDocumentedOrder) {
  const std::string text = slam_figures_json(sample(true, true));
  const std::vector<std::string> keys = {
      "places",
      "runs",
      "decisions",
      "no_sequence",
      "closure",
      "pending",
      "rejected_inconsistent",
      "aliasing",
      "novelty",
      "relocalised",
      "rejected_position",
      "rejected_heading",
      "rejected_image",
      "closures",
      "optimiser_work",
      "slices",
      "final_slices",
      "max_solve_places",
      "wheels",
      "closure_heading",
      "hfov_deg",
      "align_length",
      "align_range",
      "align_shift",
      "closures_realigned",
      "has_truth",
      "rmse_dead_reckoning_m",
      "rmse_corrected_m",
      "rmse_online_m",
      "max_error_dead_reckoning_m",
      "max_error_corrected_m",
      "false_closures",
      "largest_closure_true_distance_m",
      "closure_heading_error_rms_deg",
      "closure_same_heading_error_rms_deg",
      "closure_along_error_rms_m",
      "closure_gate_along_error_rms_m",
      "events",
      "place",
      "kind",
      "relocalised_after",
      "place",
      "kind",
      "relocalised_after",
      "has_map",
      "map_accuracy_corrected",
      "map_cells_corrected",
      "map_accuracy_dead_reckoning",
      "map_cells_dead_reckoning",
      "near_path",
      "band_m",
      "corrected",
      "cells",
      "truth_occupied",
      "grid_occupied",
      "grid_free",
      "occupied_occupied",
      "grid_occupied_near_truth",
      "truth_occupied_near_grid",
      "occupied_precision",
      "occupied_recall",
      "balanced_accuracy",
      "occupied_precision_within_1_cell",
      "occupied_recall_within_1_cell",
      "dead_reckoning",
      "cells",
      "truth_occupied",
      "grid_occupied",
      "grid_free",
      "occupied_occupied",
      "grid_occupied_near_truth",
      "truth_occupied_near_grid",
      "occupied_precision",
      "occupied_recall",
      "balanced_accuracy",
      "occupied_precision_within_1_cell",
      "occupied_recall_within_1_cell",
      "unreliable_places",
      "relocalisations",
      "align_failures",
      "heading_failures",
      "closure_lateral",
  };
  // Every key of the text ("name": ), in order.
  std::vector<std::string> found;
  for (size_t at = text.find("\":"); at != std::string::npos; at = text.find("\":", at + 1)) {
    const size_t open = text.rfind('"', at - 1);
    found.push_back(text.substr(open + 1, at - open - 1));
  }
  EXPECT_EQ(found, keys);
  // The start, verbatim: indented by 2, integers as integers, strings quoted.
  const std::string head = "{\n  \"places\": 1234,\n  \"runs\": 2,\n  \"decisions\": {\n    \"no_s";
  EXPECT_EQ(text.substr(0, head.size()), head);
  EXPECT_NE(text.find("\"optimiser_work\": 1099511627776,"), std::string::npos);
  EXPECT_NE(text.find("\"wheels\": \"0.52,0.521,0.3\","), std::string::npos);
  EXPECT_NE(text.find("\"has_truth\": true,"), std::string::npos);
  EXPECT_NE(text.find("\"align_shift\": -2,"), std::string::npos);
  // The rates beside the counts: 5 / 30 and 5 / 400.
  EXPECT_NE(text.find("\"occupied_precision\": 0.16666666666666666,"), std::string::npos);
  EXPECT_NE(text.find("\"occupied_recall\": 0.0125,"), std::string::npos);
  const std::string tail =
      "\n  \"align_failures\": 2,\n  \"heading_failures\": 5,\n  \"closure_lateral\": 0.03\n}\n";
  ASSERT_GE(text.size(), tail.size());
  EXPECT_EQ(text.substr(text.size() - tail.size()), tail);

  // Without the groups: none of their keys, the flags false.
  const std::string plain = slam_figures_json(sample(false, false));
  EXPECT_NE(plain.find("\"has_truth\": false,\n  \"has_map\": false,\n  \"unreliable_places\""),
            std::string::npos)
      << plain;
  for (const char* key : {"rmse_corrected_m", "events", "map_accuracy_corrected"})
    EXPECT_EQ(plain.find(key), std::string::npos) << key;
}

TEST(SlamFigures, WriterEscapesStrings) {
  SlamFigures f = sample(false, false);
  f.wheels = "a\"b\\c\n";
  f.closure_heading = std::string("bad \xff utf-8");
  const std::string text = slam_figures_json(f);
  EXPECT_NE(text.find("\"wheels\": \"a\\\"b\\\\c\\n\","), std::string::npos) << text;
  const Outcome<SlamFigures> back = parse_slam_figures(text, kPath);
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().wheels, f.wheels);
  EXPECT_EQ(back.value().closure_heading, "bad \xef\xbf\xbd utf-8");  // U+FFFD
}

TEST(SlamFigures, UnknownKeysAndAMissingAlignFailuresAreAccepted) {
  const SlamFigures f = sample(true, false);
  std::string text = slam_figures_json(f);
  text = replaced(text, "{\n", "{\n  \"future\": {\"x\": [1, 2, {\"y\": null}]},\n");
  text = replaced(text, "\"kind\": \"kidnap\",", "\"kind\": \"kidnap\", \"note\": \"new\",");
  text = replaced(text, "\"pending\": 102,", "\"pending\": 102, \"another_class\": 5,");
  // A document of a writer before align_failures, heading_failures and closure_lateral: they
  // read as 0, 0 and 1.
  text = replaced(
      text,
      ",\n  \"align_failures\": 2,\n  \"heading_failures\": 5,\n  \"closure_lateral\": 0.03\n",
      "\n");
  const Outcome<SlamFigures> back = parse_slam_figures(text, kPath);
  ASSERT_TRUE(back.ok()) << back.error() << "\n" << text;
  SlamFigures want = f;
  want.align_failures = 0;
  want.heading_failures = 0;
  want.closure_lateral = 1.0;
  EXPECT_TRUE(back.value() == want);
  // The group keys are ignored when their flag is false.
  std::string no_truth =
      replaced(slam_figures_json(f), "\"has_truth\": true", "\"has_truth\": false");
  const Outcome<SlamFigures> ignored = parse_slam_figures(no_truth, kPath);
  ASSERT_TRUE(ignored.ok()) << ignored.error();
  EXPECT_FALSE(ignored.value().truth.has_value());
}

TEST(SlamFigures, ADocumentWithoutNearPathReadsAsNotMeasured) {
  // As written before the figures near the path existed (or without true poses).
  const SlamFigures f = sample(true, true);
  const std::string text = slam_figures_json(f);
  const size_t begin = text.find(",\n  \"near_path\": {");
  const size_t end = text.find("\n  \"unreliable_places\"");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  const std::string old = text.substr(0, begin) + "," + text.substr(end);
  const Outcome<SlamFigures> back = parse_slam_figures(old, kPath);
  ASSERT_TRUE(back.ok()) << back.error() << "\n" << old;
  ASSERT_TRUE(back.value().map.has_value());
  EXPECT_FALSE(back.value().map->near_path.has_value());
  SlamFigures want = f;
  want.map->near_path.reset();
  EXPECT_TRUE(back.value() == want);
  EXPECT_EQ(slam_figures_json(want), old);
  // The rates are not read: a changed one does not matter (the counts are the figures).
  const Outcome<SlamFigures> rates = parse_slam_figures(
      replaced(text, "\"occupied_recall\": 0.0125", "\"occupied_recall\": 9"), kPath);
  ASSERT_TRUE(rates.ok()) << rates.error();
  EXPECT_TRUE(rates.value() == f);
}

TEST(SlamFigures, CalibrationRoundTripsAndBadValuesAreNamed) {
  SlamFigures f = sample(true, true);
  SlamCalibrationFigures c;
  c.accepted = true;
  c.difference = -0.000311;
  c.track = 0.00387;
  c.sigma_difference = 3e-6;
  c.sigma_track = 9e-5;
  c.closures_used = 289;
  c.closures_skipped = 2;
  c.residual_before_m = 1.056;
  c.residual_after_m = 0.205;
  c.corrected_wheels = "0.532082806,0.532187152,0.475836012";
  f.calibration = c;
  // Without the true constants, then with them.
  for (int truth = 0; truth < 2; ++truth) {
    if (truth == 1) {
      f.calibration->true_difference = -0.0003;
      f.calibration->true_track = 0.00435;
      f.calibration->true_mean = 1.00065;
    }
    const std::string text = slam_figures_json(f);
    const Outcome<SlamFigures> back = parse_slam_figures(text, kPath);
    ASSERT_TRUE(back.ok()) << back.error();
    EXPECT_TRUE(back.value() == f);
  }
  const std::string text = slam_figures_json(f);
  const struct {
    std::string from, to, want;
  } cases[] = {
      {"\"accepted\": true", "\"accepted\": 1", "calibration.accepted"},
      {"\"closures_used\": 289", "\"closures_used\": -1", "calibration.closures_used"},
      {"\"track\": 0.00387", "\"track\": \"x\"", "calibration.track"},
      {"\"true_mean\": 1.00065", "\"true_meen\": 1.00065", "calibration.true_mean"},
  };
  for (const auto& k : cases) {
    const Outcome<SlamFigures> bad = parse_slam_figures(replaced(text, k.from, k.to), kPath);
    ASSERT_FALSE(bad.ok()) << k.to;
    EXPECT_NE(bad.error().find(k.want), std::string::npos) << bad.error();
    EXPECT_EQ(bad.error().rfind(kPath, 0), 0u) << bad.error();
  }
}

TEST(SlamFigures, BadInputNamesThePathAndTheKeyOrPosition) {
  const std::string good = slam_figures_json(sample(true, true));
  // Cut before "has_map": the end comes on that key's line, after its indent.
  const std::string truncated = good.substr(0, good.find("\"has_map\""));
  const std::string truncated_at =
      "line " + std::to_string(std::count(truncated.begin(), truncated.end(), '\n') + 1) +
      ", column 3";
  const struct {
    std::string text;
    std::vector<std::string> want;  // each must be in the message
  } cases[] = {
      {"", {"not JSON", "line 1, column 1", "unexpected end of input"}},
      {"   \n", {"not JSON", "line 2"}},
      {truncated, {"not JSON", truncated_at, "unexpected end of input"}},
      {"{\n  \"places\": 6,\n  \"closures\" 2\n}\n", {"not JSON", "line 3, column", "':'"}},
      {"{\"places\": 6} x", {"not JSON", "line 1, column 15", "expected end of input"}},
      {"{\"places\": nan}", {"not JSON", "line 1, column"}},
      {"[]", {"must be an object, found an array"}},
      {"\"figures\"", {"must be an object, found a string"}},
      {"{}", {"missing key 'places'"}},
      {std::string(100, '[') + std::string(100, ']'), {"nested deeper than 32"}},
      {replaced(good, "\"places\": 1234", "\"places\": \"1234\""),
       {"'places' must be a whole number", "found a string"}},
      {replaced(good, "\"places\": 1234", "\"places\": -1"),
       {"'places' must be a whole number from 0 to 4294967295, found -1"}},
      {replaced(good, "\"closures\": 41", "\"closures\": 1.5"),
       {"'closures' must be a whole number", "found 1.5"}},
      {replaced(good, "\"runs\": 2", "\"runs\": 4294967296"),
       {"'runs' must be a whole number from 0 to 4294967295, found 4294967296"}},
      {replaced(good, "\"slices\": 17", "\"slices\": 1e30"), {"'slices'", "found 1e+30"}},
      {replaced(good, "\"optimiser_work\": 1099511627776",
                "\"optimiser_work\": 18446744073709551616"),
       {"'optimiser_work' must be a whole number from 0 to 18446744073709551615"}},
      {replaced(good, "\"novelty\": 105", "\"novelty\": -5"), {"'decisions.novelty'", "found -5"}},
      {replaced(good, "\"decisions\": {", "\"decisions\": [], \"x\": {"),
       {"'decisions' must be an object, found an array"}},
      {without_key(good, "aliasing"), {"missing key 'decisions.aliasing'"}},
      {without_key(good, "runs"), {"missing key 'runs'"}},
      {without_key(good, "has_truth"), {"missing key 'has_truth'"}},
      {without_key(good, "has_map"), {"missing key 'has_map'"}},
      {replaced(good, "\"has_map\": true", "\"has_map\": 1"),
       {"'has_map' must be true or false, found 1"}},
      {replaced(good, "\"wheels\": \"0.52,0.521,0.3\"", "\"wheels\": 0.52"),
       {"'wheels' must be a string, found 0.52"}},
      {replaced(good, "\"hfov_deg\": 50.0", "\"hfov_deg\": \"wide\""),
       {"'hfov_deg' must be a finite number, found a string"}},
      {replaced(good, "\"hfov_deg\": 50.0", "\"hfov_deg\": 1e999"),
       {"not JSON: number overflow parsing '1e999'"}},
      {replaced(good, "\"align_length\": 15", "\"align_length\": 2147483648"),
       {"'align_length' must be a whole number from -2147483648 to 2147483647"}},
      {replaced(good, "\"align_failures\": 2", "\"align_failures\": -2"),
       {"'align_failures' must be a whole number", "found -2"}},
      {replaced(good, "\"heading_failures\": 5", "\"heading_failures\": 0.5"),
       {"'heading_failures' must be a whole number", "found 0.5"}},
      {replaced(good, "\"closure_lateral\": 0.03", "\"closure_lateral\": 1.5"),
       {"'closure_lateral' must be a number from 0 to 1, found 1.5"}},
      {replaced(good, "\"closure_lateral\": 0.03", "\"closure_lateral\": -0.1"),
       {"'closure_lateral' must be a number from 0 to 1, found -0.1"}},
      {replaced(good, "\"closure_lateral\": 0.03", "\"closure_lateral\": \"weak\""),
       {"'closure_lateral' must be a finite number, found a string"}},
      {without_key(good, "rmse_online_m"),
       {"has_truth is true but key 'rmse_online_m' is missing"}},
      {without_key(good, "map_cells_dead_reckoning"),
       {"has_map is true but key 'map_cells_dead_reckoning' is missing"}},
      {replaced(good, "\"rmse_corrected_m\": 0.1", "\"rmse_corrected_m\": null"),
       {"'rmse_corrected_m' must be a finite number, found null"}},
      {replaced(good, "\"events\": [", "\"events\": {\"a\": 1}, \"x\": ["),
       {"'events' must be an array, found an object"}},
      {replaced(good, "\"kind\": \"known ground again\"", "\"kind\": 3"),
       {"'events[1].kind' must be a string, found 3"}},
      {replaced(good, "\"relocalised_after\": -1", "\"relocalised_after\": -2"),
       {"'events[1].relocalised_after' must be a whole number from -1 to 2147483647"}},
      {replaced(good, "\"place\": 120", "\"place\": -120"), {"'events[0].place'", "found -120"}},
      {replaced(good, "\"events\": [", "\"events\": [7, "),
       {"'events[0]' must be an object, found 7"}},
      {replaced(good, "\"events\": [", "\"events\": [{}, "), {"missing key 'events[0].place'"}},
      {replaced(good, "\"near_path\": {", "\"near_path\": 1, \"x\": {"),
       {"'near_path' must be an object, found 1"}},
      {without_key(good, "band_m"), {"missing key 'near_path.band_m'"}},
      {replaced(good, "\"band_m\": 1.0", "\"band_m\": 0"),
       {"'near_path.band_m' must be more than 0"}},
      {without_key(good, "grid_free"), {"missing key 'near_path.corrected.grid_free'"}},
      {replaced(good, "\"occupied_occupied\": 2", "\"occupied_occupied\": -2"),
       {"'near_path.dead_reckoning.occupied_occupied' must be a whole number", "found -2"}},
      {replaced(good, "\"occupied_occupied\": 5", "\"occupied_occupied\": 31"),
       {"'near_path.corrected' counts that no comparison gives"}},
  };
  for (const auto& c : cases) {
    const std::string e = parse_error(c.text);
    EXPECT_EQ(e.rfind(std::string(kPath) + ": ", 0), 0u) << e;
    for (const std::string& w : c.want)
      EXPECT_NE(e.find(w), std::string::npos) << "want '" << w << "' in: " << e;
  }
}

TEST(SlamFigures, TooLargeIsRefusedBeforeParsing) {
  const std::string big(kMaxSlamFiguresBytes + 1, ' ');
  const std::string e = parse_error(big);
  EXPECT_NE(e.find(std::string(kPath) + ": "), std::string::npos) << e;
  EXPECT_NE(e.find("more than the"), std::string::npos) << e;
}

}  // namespace
}  // namespace seqslam::tools::test
