// seqslam-sim evaluate: precision/recall of the core's diagonal matcher on every
// library/query pair of a generated scenario, for several preprocessing methods.
#pragma once

#include <string>
#include <vector>

#include "seqslam/localiser.h"

namespace seqslam::sim {

struct EvaluateOptions {
  std::string dir;
  std::vector<std::string> methods = {"none", "he", "pn"};
  LocaliserConfig config;  // image size is taken from the recordings
  std::string markdown;    // also write the table here
  unsigned jobs = 2;
};

// Prints a table; returns a process exit status (0, or 1 with a message on stderr).
int evaluate(const EvaluateOptions& options);

}  // namespace seqslam::sim
