// Options and input loading shared by seqslam run, eval, sweep and report.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/ground_truth.h"

namespace seqslam::cli {

struct EvalOptions {
  std::string library;
  std::string query;
  std::string size = "32x16";
  std::string preprocess = "he";
  std::string threshold;  // empty: the core's default
  std::string library_range;
  std::string query_range;
  std::string matcher = "diagonal";
  int max_shift = 0;  // bound as int: a uint8_t option would print as a character
  std::string metric = "mad";
  // Heuristic and slope settings, as plain numbers (converted in load_inputs).
  int candidates = HeuristicConfig{}.candidates;
  int guard = HeuristicConfig{}.guard;
  double candidate_threshold = 40.0;  // grey levels per pixel
  double vmin = 0.8;
  double vmax = 1.2;
  int vsteps = 5;
  tools::EvalConfig config;  // filled by load_inputs from the fields above and the options
};

// Registers LIBRARY QUERY and the localiser options (--size, --preprocess, --seq-len,
// --window, --exclusion, --threshold, --max-shift, --matcher, ranges, --threads, --cache).
void add_eval_options(CLI::App* app, EvalOptions* o);

struct Loaded {
  tools::InputSequence library;
  tools::InputSequence query;
  double load_ms = 0.0;
};

// Completes o->config from the options and loads both inputs. Returns kExitOk, or the exit
// status after printing the message (usage errors 2, input errors 1).
int load_inputs(EvalOptions& o, Loaded* out);

struct GroundTruthRef {
  const tools::GroundTruth* truth = nullptr;
};

// Writes the HTML report of one evaluation (report.cpp). Returns an exit status.
int write_report(const std::string& path, const tools::EvalResult& result,
                 const tools::InputSequence& library, const tools::InputSequence& query,
                 const tools::GroundTruth& truth);

// A library/query pair with its ground truth (a file, identity:TOL or poses:METRES).
struct PairSpec {
  std::string library, query, truth, label;
};

// Appends the pairs of a seqslam-sim pairs.csv (library,query,ground_truth,description;
// paths relative to the file's directory). Returns "" or an error naming the file and line.
std::string read_pairs_file(const std::string& path, std::vector<PairSpec>* out);

}  // namespace seqslam::cli
