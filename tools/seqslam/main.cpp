// seqslam: the host command-line tool for the robot's SD card and recordings.
//
//   seqslam disk create|list|export|import   disk images with a seqslam volume
//   seqslam config write|show                the firmware's run configuration
//   seqslam results                          the firmware's localisation results
//   seqslam convert images-to-dream|dream-to-images
//   seqslam dream info                       what a dream recording holds
//   seqslam explain CODE|--all               the sentences behind the board's message codes
//
// docs/seqslam_cli.md describes every subcommand. Exit status: 0 success, 1 runtime failure
// (bad input file, damaged data, I/O error), 2 usage error.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "cli_common.h"
#include "seqslam/hal/host_file.h"
#include "seqslam_tools/output_file.h"

namespace {

using namespace seqslam::cli;

int run(int argc, char** argv) {
  CLI::App app{
      "Host tool of the seqslam place recogniser: disk images of the robot's SD card, the "
      "firmware's run configuration and results, and dream recordings.",
      "seqslam"};
  app.require_subcommand(1);
  app.set_version_flag("--version", SEQSLAM_VERSION_STRING, "Print the version and exit");
  app.footer(
      "Sizes take the suffixes K, M, G (1024-based). Exit status: 0 success, 1 runtime failure "
      "(bad input file, damaged data, I/O error), 2 usage error. See docs/seqslam_cli.md.");

  Command chosen;
  add_disk_commands(app, &chosen);
  add_config_commands(app, &chosen);
  add_results_command(app, &chosen);
  add_convert_commands(app, &chosen);
  add_dream_commands(app, &chosen);
  add_eval_commands(app, &chosen);
  add_sweep_command(app, &chosen);
  add_tune_command(app, &chosen);
  add_report_command(app, &chosen);
  add_transforms_command(app, &chosen);
  add_slam_command(app, &chosen);
  add_report_slam_command(app, &chosen);
  add_graph_command(app, &chosen);
  add_explain_command(app, &chosen);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  if (!chosen) return usage_error("no command given");
  return chosen();
}

}  // namespace

int main(int argc, char** argv) {
  // A file size limit (ulimit -f) makes writes fail with EFBIG, reported like a full disk
  // (status 1, the file named, no temporary left), instead of a silent death by SIGXFSZ.
  seqslam::hal::ignore_file_size_signal();
  int code = kExitOk;
  try {
    code = run(argc, argv);
  } catch (const std::exception& e) {  // e.g. std::bad_alloc, std::filesystem errors
    code = fail(e.what());
  } catch (...) {
    code = fail("unexpected error");
  }
  // What went to standard output must have arrived (a full disk, /dev/full): else status 1.
  const std::string lost = seqslam::tools::finish_stdout();
  if (!lost.empty()) {
    fail(lost);
    if (code == kExitOk) code = kExitFailure;
  }
  return code;
}
