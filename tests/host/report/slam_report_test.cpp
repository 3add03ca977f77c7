// The SLAM report (seqslam_tools/slam_report.h) on a small synthetic `seqslam slam` output
// written here: the page shows the three maps, the trajectories, the closures and the
// figures; every reader refuses bad input with a message naming the file (and line).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/slam_figures.h"
#include "seqslam_tools/slam_report.h"

namespace seqslam::tools::test {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

// A map of w x h cells at 5 cm: free inside, an occupied border.
OccupancyMapImage box_map(int w, int h, double ox, double oy) {
  OccupancyMapImage m;
  m.resolution = 0.05;
  m.origin_x = ox;
  m.origin_y = oy;
  m.width = w;
  m.height = h;
  m.cells.assign(static_cast<size_t>(w) * static_cast<size_t>(h), CellState::kFree);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (x == 0 || y == 0 || x == w - 1 || y == h - 1) {
        m.cells[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] =
            CellState::kOccupied;
      }
    }
  }
  return m;
}

struct Row {
  double tx, ty, ox, oy, cx, cy;
  const char* decision;
};

// Six places of one run, two closures; maps of different extents (the corrected one smaller
// and shifted, the true one largest).
class SlamDir : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "seqslam_slam_report_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    std::string csv =
        "place,run,true_x,true_y,true_heading_deg,odo_x,odo_y,odo_heading_deg,online_x,online_y,"
        "corrected_x,corrected_y,corrected_heading_deg,decision,matched,confidence,reliable\n";
    for (size_t i = 0; i < rows_.size(); ++i) {
      const Row& r = rows_[i];
      char line[256];
      std::snprintf(line, sizeof line,
                    "%zu,0,%.4f,%.4f,0.00,%.4f,%.4f,0.00,%.4f,%.4f,%.4f,%.4f,"
                    "0.00,%s,-1,1.0000,1\n",
                    i, r.tx, r.ty, r.ox, r.oy, r.cx, r.cy, r.cx, r.cy, r.decision);
      csv += line;
    }
    write_text(dir_ / "trajectory.csv", csv);
    write_text(dir_ / "closures.csv",
               "matched_place,place,true_distance_m\n0,4,0.1000\n1,5,2.0000\n");
    std::string e;
    ASSERT_TRUE(save_map(box_map(40, 30, -0.5, -0.5), (dir_ / "map").string(), &e)) << e;
    ASSERT_TRUE(save_map(box_map(50, 36, -0.7, -0.6), (dir_ / "map_odometry").string(), &e)) << e;
    ASSERT_TRUE(save_map(box_map(70, 50, -1.0, -1.0), (dir_ / "lab_map").string(), &e)) << e;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // A fresh directory for the next case.
  void Reset() {
    TearDown();
    SetUp();
  }

  std::string dir() const { return dir_.string(); }
  std::string true_map() const { return (dir_ / "lab_map.yaml").string(); }

  Outcome<SlamReportData> load(const std::string& json = "") const {
    return load_slam_report(dir(), true_map(), json);
  }
  // The load's error message (fails the test if the load succeeded).
  std::string load_error(const std::string& true_map_yaml, const std::string& json = "") const {
    auto d = load_slam_report(dir(), true_map_yaml, json);
    EXPECT_FALSE(d.ok());
    return d.error();
  }

  std::string figure(const SlamReportData& d, const std::string& key) const {
    for (const SlamFigure& f : d.figures) {
      if (f.key == key) return f.value;
    }
    ADD_FAILURE() << "no figure " << key;
    return "";
  }

  fs::path dir_;
  std::vector<Row> rows_ = {{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, "no_sequence"},
                            {0.2, 0.0, 0.21, 0.01, 0.2, 0.0, "novelty"},
                            {0.4, 0.1, 0.43, 0.05, 0.41, 0.1, "rejected_inconsistent"},
                            {0.6, 0.3, 0.66, 0.2, 0.6, 0.31, "aliasing"},
                            {0.4, 0.4, 0.5, 0.3, 0.42, 0.4, "closure"},
                            {0.2, 0.5, 0.3, 0.45, 0.2, 0.52, "closure"}};
};

TEST_F(SlamDir, PageShowsTheThreeMapsTrajectoriesClosuresAndFigures) {
  auto d = load();
  ASSERT_TRUE(d.ok()) << d.error();
  auto html = render_slam_report(d.value(), "test <run>");
  ASSERT_TRUE(html.ok()) << html.error();
  const std::string& h = html.value();
  for (const char* id :
       {"id=\"map-true\"", "id=\"map-corrected\"", "id=\"map-odometry\"", "id=\"slam-figures\""}) {
    EXPECT_EQ(count(h, id), 1u) << id;
  }
  EXPECT_EQ(count(h, "src=\"data:image/png;base64,"), 3u);
  // Self-contained: no external resource.
  EXPECT_EQ(count(h, "http://") + count(h, "https://"), count(h, "http://www.w3.org/2000/svg"));
  EXPECT_EQ(count(h, "<script"), 0u);
  EXPECT_NE(h.find("test &lt;run&gt;"), std::string::npos);
  // True on every panel; dead reckoning and corrected on the true panel and their own.
  EXPECT_EQ(count(h, "class=\"traj-true\""), 3u);
  EXPECT_EQ(count(h, "class=\"traj-odometry\""), 2u);
  EXPECT_EQ(count(h, "class=\"traj-corrected\""), 2u);
  // Two closures at the true poses and at the corrected poses.
  EXPECT_EQ(count(h, "<title>closure 0 - 4</title>"), 2u);
  EXPECT_EQ(count(h, "<title>closure 1 - 5</title>"), 2u);
  // The corrected polyline holds every corrected pose at (x, -y).
  char p[64];
  for (const Row& r : rows_) {
    std::snprintf(p, sizeof p, "%.3f,%.3f", r.cx, -r.cy);
    EXPECT_NE(h.find(p), std::string::npos) << p;
  }
}

TEST_F(SlamDir, FiguresComputedFromTheFilesWithoutJson) {
  auto d = load();
  ASSERT_TRUE(d.ok()) << d.error();
  double se_dead = 0, se_fixed = 0;
  for (const Row& r : rows_) {
    se_dead += std::pow(r.ox - r.tx, 2) + std::pow(r.oy - r.ty, 2);
    se_fixed += std::pow(r.cx - r.tx, 2) + std::pow(r.cy - r.ty, 2);
  }
  const double n = static_cast<double>(rows_.size());
  char want[32];
  std::snprintf(want, sizeof want, "%.3f", std::sqrt(se_dead / n));
  EXPECT_EQ(figure(d.value(), "rmse_dead_reckoning_m"), want);
  std::snprintf(want, sizeof want, "%.3f", std::sqrt(se_fixed / n));
  EXPECT_EQ(figure(d.value(), "rmse_corrected_m"), want);
  std::snprintf(want, sizeof want, "%.2f", std::sqrt(se_fixed / se_dead));
  EXPECT_EQ(figure(d.value(), "ratio"), want);
  EXPECT_EQ(figure(d.value(), "closures"), "2");
  EXPECT_EQ(figure(d.value(), "false_closures"), "1");  // the 2.0 m one
  EXPECT_EQ(figure(d.value(), "decisions.rejected_inconsistent"), "1");
  EXPECT_EQ(figure(d.value(), "rejected_position"), "");  // only the JSON knows the reason
  // Map accuracy against the true map, as compare_maps gives it.
  const auto truth = load_map(true_map());
  const auto map = load_map(dir() + "/map.yaml");
  ASSERT_TRUE(truth.ok() && map.ok());
  const auto cmp = compare_maps(map.value(), truth.value());
  ASSERT_TRUE(cmp.ok());
  std::snprintf(want, sizeof want, "%.3f", cmp.value().accuracy());
  EXPECT_EQ(figure(d.value(), "map_accuracy_corrected"), want);
  // Obstacles near the true path, as compare_maps_near_path gives them with the default band.
  std::vector<PathPoint> path;
  for (const Row& r : rows_)
    path.push_back({r.tx, r.ty, 0});
  const auto near = compare_maps_near_path(map.value(), truth.value(), path, kDefaultPathBand);
  ASSERT_TRUE(near.ok()) << near.error();
  ASSERT_TRUE(d.value().near_path.has_value());
  EXPECT_EQ(d.value().near_path_source, "computed");
  EXPECT_EQ(d.value().near_path->band_m, kDefaultPathBand);
  EXPECT_TRUE(d.value().near_path->corrected == near.value());
  EXPECT_GT(near.value().cells, 0u);
  std::snprintf(want, sizeof want, "%.3f", near.value().precision());
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_precision"), want);
  std::snprintf(want, sizeof want, "%.3f", near.value().recall());
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_recall"), want);
  std::snprintf(want, sizeof want, "%.3f", near.value().balanced_accuracy());
  EXPECT_EQ(figure(d.value(), "near_path.corrected.balanced_accuracy"), want);
  auto html = render_slam_report(d.value(), "");
  ASSERT_TRUE(html.ok());
  EXPECT_NE(html.value().find("computed from the files"), std::string::npos);
  // Under the corrected and the dead-reckoning map.
  EXPECT_EQ(count(html.value(), "<span class=\"near-path\">Within 1.00 m of the true path"), 2u);
}

// The figures JSON of this run (slam_figures.h): truth and map as asked.
SlamFigures run_figures(bool truth, bool map) {
  SlamFigures f;
  f.places = 6;
  f.runs = 1;
  f.decisions[static_cast<size_t>(LoopClosureClass::kClosure)] = 2;
  f.decisions[static_cast<size_t>(LoopClosureClass::kRejectedInconsistent)] = 1;
  f.rejected_position = 1;
  f.rejected_heading = 0;
  f.rejected_image = 3;
  f.closures = 2;
  f.closure_heading = "image";
  f.hfov_deg = 50;
  if (truth) {
    f.truth.emplace();
    f.truth->rmse_dead_reckoning_m = 0.5;
    f.truth->rmse_corrected_m = 0.125;
    f.truth->false_closures = 0;
    f.truth->events = {{4, "x", -1}};
  }
  if (map) {
    f.map.emplace();
    f.map->map_accuracy_corrected = 0.99;
    f.map->map_accuracy_dead_reckoning = 0.95;
    if (truth) {
      f.map->near_path =
          SlamNearPathFigures{0.5, {100, 10, 8, 80, 6, 7, 9}, {100, 10, 4, 70, 1, 2, 3}};
    }
  }
  return f;
}

TEST_F(SlamDir, FiguresFromTheJson) {
  write_text(dir_ / "slam.json", slam_figures_json(run_figures(true, true)));
  auto d = load((dir_ / "slam.json").string());
  ASSERT_TRUE(d.ok()) << d.error();
  EXPECT_EQ(figure(d.value(), "rmse_dead_reckoning_m"), "0.500");
  EXPECT_EQ(figure(d.value(), "rmse_corrected_m"), "0.125");
  EXPECT_EQ(figure(d.value(), "ratio"), "0.25");
  EXPECT_EQ(figure(d.value(), "false_closures"), "0");
  EXPECT_EQ(figure(d.value(), "rejected_position"), "1");
  EXPECT_EQ(figure(d.value(), "rejected_heading"), "0");
  EXPECT_EQ(figure(d.value(), "rejected_image"), "3");
  EXPECT_EQ(figure(d.value(), "decisions.rejected_inconsistent"), "1");
  EXPECT_EQ(figure(d.value(), "closures"), "2");
  EXPECT_EQ(figure(d.value(), "map_accuracy_corrected"), "0.990");
  EXPECT_EQ(figure(d.value(), "map_accuracy_dead_reckoning"), "0.950");
  // Near the path (band 0.5 m): 6 of 8 called occupied are, 6 of 10 truly occupied found.
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_precision"), "0.750");
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_recall"), "0.600");
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_precision_within_1_cell"), "0.875");
  EXPECT_EQ(figure(d.value(), "near_path.corrected.occupied_recall_within_1_cell"), "0.900");
  EXPECT_EQ(figure(d.value(), "near_path.dead_reckoning.occupied_precision"), "0.250");
  // (0.1 + (90 - 3) / 90) / 2
  EXPECT_EQ(figure(d.value(), "near_path.dead_reckoning.balanced_accuracy"), "0.533");
  for (const SlamFigure& f : d.value().figures)
    EXPECT_EQ(f.source, "json") << f.key;
  auto html = render_slam_report(d.value(), "");
  ASSERT_TRUE(html.ok());
  EXPECT_NE(html.value().find("the slam JSON"), std::string::npos);
  EXPECT_NE(html.value().find("<span class=\"near-path\">Within 0.50 m of the true path: "
                              "occupied precision 0.750, recall 0.600 (within one cell 0.875, "
                              "0.900), balanced accuracy"),
            std::string::npos);
}

TEST_F(SlamDir, JsonWithoutTruthOrMapLeavesThoseFiguresToTheFiles) {
  write_text(dir_ / "slam.json", slam_figures_json(run_figures(false, false)));
  auto d = load((dir_ / "slam.json").string());
  ASSERT_TRUE(d.ok()) << d.error();
  for (const char* key : {"rmse_dead_reckoning_m", "rmse_corrected_m", "ratio", "false_closures",
                          "map_accuracy_corrected", "map_accuracy_dead_reckoning",
                          "near_path.corrected.occupied_recall"}) {
    for (const SlamFigure& f : d.value().figures) {
      if (f.key == key) {
        EXPECT_EQ(f.source, "computed") << key;
      }
    }
  }
  EXPECT_EQ(figure(d.value(), "false_closures"), "1");  // from closures.csv, not the JSON's
  EXPECT_EQ(figure(d.value(), "rejected_position"), "1");
  EXPECT_FALSE(figure(d.value(), "near_path.corrected.occupied_recall").empty());
  // A JSON with the map but written before the figures near the path: computed from the files.
  SlamFigures old = run_figures(true, true);
  old.map->near_path.reset();
  write_text(dir_ / "slam.json", slam_figures_json(old));
  auto o = load((dir_ / "slam.json").string());
  ASSERT_TRUE(o.ok()) << o.error();
  EXPECT_EQ(o.value().near_path_source, "computed");
  ASSERT_TRUE(o.value().near_path.has_value());
  EXPECT_EQ(o.value().near_path->band_m, kDefaultPathBand);
}

TEST_F(SlamDir, WithoutTrueMapOrTruth) {
  // No ground truth: true columns empty; no true map.
  std::string csv = "place,run,true_x,true_y,odo_x,odo_y,corrected_x,corrected_y,decision\n";
  csv += "0,0,,,0,0,0,0,no_sequence\n1,0,,,0.2,0,0.2,0,novelty\n";
  write_text(dir_ / "trajectory.csv", csv);
  write_text(dir_ / "closures.csv", "matched_place,place,true_distance_m\n0,1,\n");
  auto d = load_slam_report(dir(), "", "");
  ASSERT_TRUE(d.ok()) << d.error();
  EXPECT_EQ(figure(d.value(), "rmse_corrected_m"), "");
  EXPECT_EQ(figure(d.value(), "map_accuracy_corrected"), "");
  EXPECT_FALSE(d.value().near_path.has_value());
  auto html = render_slam_report(d.value(), "");
  ASSERT_TRUE(html.ok()) << html.error();
  EXPECT_EQ(count(html.value(), "class=\"traj-true\""), 0u);
  EXPECT_EQ(count(html.value(), "class=\"traj-corrected\""), 1u);
  EXPECT_NE(html.value().find("No true map given"), std::string::npos);
  EXPECT_EQ(count(html.value(), "src=\"data:image/png;base64,"), 3u);
  EXPECT_EQ(count(html.value(), "class=\"near-path\""), 0u);
}

TEST_F(SlamDir, MissingFilesAreRefused) {
  for (const char* name : {"trajectory.csv", "closures.csv", "map.yaml", "map_odometry.yaml"}) {
    Reset();
    fs::remove(dir_ / name);
    const std::string e = load_error(true_map());
    EXPECT_NE(e.find(name), std::string::npos) << name << ": " << e;
  }
  Reset();
  EXPECT_NE(load_error((dir_ / "nothing.yaml").string()).find("nothing.yaml"), std::string::npos);
  EXPECT_NE(load_error(true_map(), (dir_ / "none.json").string()).find("none.json"),
            std::string::npos);
}

TEST_F(SlamDir, MalformedTrajectoryNamesTheLine) {
  const std::string header =
      "place,run,true_x,true_y,odo_x,odo_y,corrected_x,corrected_y,decision\n";
  const struct {
    std::string text;
    std::string want;
  } cases[] = {
      {header + "0,0,0,0,0,0,0,0,novelty\n1,0,0,0,0,0,0\n", "trajectory.csv:3: 7 fields"},
      {header + "0,0,0,0,zero,0,0,0,novelty\n", "trajectory.csv:2: odo_x is not a number"},
      {header + "0,0,0,0,0,0,0,0,novelty\n2,0,0,0,0,0,0,0,novelty\n",
       "trajectory.csv:3: place must be 1"},
      {header + "0,x,0,0,0,0,0,0,novelty\n", "trajectory.csv:2: run is not"},
      {header + "0,0,0,0,nan,0,0,0,novelty\n", "trajectory.csv:2: odo_x is not a number"},
      {"place,run,odo_x\n0,0,0\n", "trajectory.csv:1: the header has no column"},
      {header, "trajectory.csv: no places"},
      {"", "trajectory.csv: empty"},
  };
  for (const auto& c : cases) {
    write_text(dir_ / "trajectory.csv", c.text);
    const std::string e = load_error(true_map());
    EXPECT_NE(e.find(c.want), std::string::npos) << e;
  }
}

TEST_F(SlamDir, MalformedClosuresNameTheLine) {
  const std::string header = "matched_place,place,true_distance_m\n";
  const struct {
    std::string text;
    std::string want;
  } cases[] = {
      {header + "0,9,0.1\n", "closures.csv:2: places must be indices below 6"},
      {header + "0,-1,0.1\n", "closures.csv:2: places must be indices"},
      {header + "0,1,0.1\n0,2\n", "closures.csv:3: 2 fields"},
      {header + "0,1,far\n", "closures.csv:2: true_distance_m is not a distance"},
      {"a,b\n", "closures.csv:1: the header has no column 'matched_place'"},
  };
  for (const auto& c : cases) {
    write_text(dir_ / "closures.csv", c.text);
    const std::string e = load_error(true_map());
    EXPECT_NE(e.find(c.want), std::string::npos) << e;
  }
}

TEST_F(SlamDir, BadMapsAreRefused) {
  // A map image that is not an image.
  write_text(dir_ / "map.pgm", "P5\n40 30\n255\nshort");
  EXPECT_NE(load_error(true_map()).find("map.yaml: image:"), std::string::npos);
  Reset();
  // A YAML without origin.
  write_text(dir_ / "map_odometry.yaml", "image: map_odometry.pgm\nresolution: 0.05\n");
  EXPECT_NE(load_error(true_map()).find("map_odometry.yaml: missing key 'origin'"),
            std::string::npos);
  Reset();
  // Another resolution than the corrected map's: the panels could not share a scale.
  std::string e;
  OccupancyMapImage coarse = box_map(10, 10, 0, 0);
  coarse.resolution = 0.1;
  ASSERT_TRUE(save_map(coarse, (dir_ / "lab_map").string(), &e)) << e;
  EXPECT_NE(load_error(true_map()).find("lab_map.yaml: resolution 0.1000 m differs"),
            std::string::npos);
  Reset();
  // Too many cells to draw.
  write_text(dir_ / "map.yaml", "image: big.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  write_text(dir_ / "big.pgm", "P5\n8000 4000\n255\n" + std::string(8000u * 4000u, '\xfe'));
  EXPECT_NE(load_error(true_map()).find("more than the report draws"), std::string::npos);
}

TEST_F(SlamDir, BadJsonNamesTheLineOrTheKey) {
  const std::string good = slam_figures_json(run_figures(true, true));
  const std::string other_run = slam_figures_json([] {
    SlamFigures f = run_figures(true, true);
    f.places = 7;
    return f;
  }());
  std::string no_runs = good;
  no_runs.erase(no_runs.find("  \"runs\": 1,\n"), 13);
  std::string closures_text = good;
  closures_text.replace(closures_text.find("\"closures\": 2"), 13, "\"closures\": \"2\"");
  const struct {
    std::string text;
    std::string want;
  } cases[] = {
      {"{\n  \"places\": 6,\n  \"closures\" 2\n}\n",
       "slam.json: not JSON: parse error at line 3, column "},
      {"{\n  \"places\": 6,\n  \"rmse\": abc\n}\n",
       "slam.json: not JSON: parse error at line 3, column 11"},
      {"{\n  \"places\": 6\n", "slam.json: not JSON: parse error at line 3, column 1"},
      {"{\"places\": 6} x", "slam.json: not JSON: parse error at line 1, column 15"},
      {"[6]", "slam.json: not a figures JSON: the document must be an object"},
      {no_runs, "slam.json: missing key 'runs'"},
      {closures_text, "slam.json: 'closures' must be a whole number"},
      {other_run, "slam.json: places 7, but"},
  };
  for (const auto& c : cases) {
    write_text(dir_ / "slam.json", c.text);
    const std::string e = load_error(true_map(), (dir_ / "slam.json").string());
    EXPECT_NE(e.find(c.want), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace seqslam::tools::test
