// seqslam report-slam DIR: the HTML page of a `seqslam slam --out DIR` result (the true,
// corrected and dead-reckoning maps side by side, trajectories and closures over them, the
// figures); tools/common/src/slam_report.cpp renders it, docs/mapping.md explains it.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <string>

#include "cli_common.h"
#include "seqslam_tools/report.h"
#include "seqslam_tools/slam_report.h"

namespace seqslam::cli {

namespace {

struct ReportSlamOptions {
  std::string directory;
  std::string true_map;
  std::string json;
  std::string out;
  std::string title;
};

int run_report_slam(const ReportSlamOptions& o) {
  // Defaults that find what `seqslam slam` and the docs' example leave in DIR.
  std::string true_map = o.true_map;
  std::string json = o.json;
  const std::filesystem::path dir(o.directory);
  std::error_code ec;
  if (true_map.empty() && std::filesystem::exists(dir / "lab_map.yaml", ec)) {
    true_map = (dir / "lab_map.yaml").string();
  }
  if (json.empty() && std::filesystem::exists(dir / "slam.json", ec)) {
    json = (dir / "slam.json").string();
  }
  tools::InputFiles inputs;  // what load_slam_report reads: OUT must be none of them
  for (const char* name : {"trajectory.csv", "closures.csv"})
    inputs.add((dir / name).string());
  inputs.add_map((dir / "map.yaml").string());
  inputs.add_map((dir / "map_odometry.yaml").string());
  if (!true_map.empty()) inputs.add_map(true_map);
  if (!json.empty()) inputs.add(json);
  if (const int rc = refuse_inputs_as_outputs(inputs, {o.out}); rc != kExitOk) return rc;
  auto data = tools::load_slam_report(o.directory, true_map, json);
  if (!data) return fail(data.error());
  auto html = tools::render_slam_report(data.value(), o.title);
  if (!html) return fail(html.error());
  std::string error;
  if (!tools::write_report(o.out, html.value(), &error)) return fail(error);
  std::printf("report: %s\n", o.out.c_str());
  return kExitOk;
}

}  // namespace

void add_report_slam_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<ReportSlamOptions>();
  CLI::App* c = app.add_subcommand(
      "report-slam",
      "HTML page of a `seqslam slam --out DIR` result: the true, corrected and dead-reckoning "
      "maps side by side, the trajectories and closures over them, the figures "
      "(docs/mapping.md)");
  c->add_option("directory", o->directory, "The slam output directory (trajectory.csv, ...)")
      ->required();
  c->add_option("--true-map", o->true_map,
                "True map YAML (map_server; default DIR/lab_map.yaml if there)");
  c->add_option("--json", o->json,
                "The figures of `seqslam slam --json` (default DIR/slam.json "
                "if there)");
  c->add_option("--out", o->out, "The HTML file to write")->required();
  c->add_option("--title", o->title, "Page title");
  c->callback([o, chosen]() { *chosen = [o]() { return run_report_slam(*o); }; });
}

}  // namespace seqslam::cli
