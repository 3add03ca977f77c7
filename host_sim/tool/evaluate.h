// seqslam-sim evaluate: precision/recall of the core's diagonal matcher on every
// library/query pair of a generated scenario, for several preprocessing methods.
#pragma once

#include <string>
#include <vector>

#include "seqslam/localiser.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_tools/settings_cli.h"

namespace seqslam::sim {

struct EvaluateOptions {
  std::string dir;
  std::vector<std::string> methods = {"none", "he", "pn"};
  // S, W, R (the settings table's options; the image size is the recordings', the
  // preprocessing each of `methods`).
  cli::SettingOptions<> settings;
  storage::RunConfig run{};  // the settings given (main.cpp applies them)
  std::string markdown;    // also write the table here
  unsigned jobs = 2;
};

// Prints a table; returns a process exit status (0, or 1 with a message on stderr).
int evaluate(const EvaluateOptions& options);

}  // namespace seqslam::sim
