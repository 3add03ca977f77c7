// seqslam results: the firmware's localisation results (volume file `results`) as a table
// or CSV.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "cli_common.h"
#include "seqslam/storage/run_files.h"

namespace seqslam::cli {

namespace {

struct ResultsOptions {
  std::string source;
  std::string csv;
};

// Metres (Q31.32) with 10 decimals and degrees (binary angles) with 8 read back exactly;
// confidence (UQ16.16) as raw / 65536 with 6 decimals.
void print_csv(std::FILE* out, const storage::RunResult& r) {
  std::fprintf(
      out, "%u,%u,%u,%s,%s,%s,%d,%d,%u,%u,%s,%d\n", r.step, r.capture, r.timestamp_us,
      fixed_decimal(r.pose.x.raw(), 32, 10).c_str(), fixed_decimal(r.pose.y.raw(), 32, 10).c_str(),
      angle_degrees(r.pose.heading.bam, 8).c_str(), r.place, r.runner_up, r.cost, r.runner_up_cost,
      fixed_decimal(r.confidence.raw(), 16, 6).c_str(), r.localised ? 1 : 0);
}

void print_row(const storage::RunResult& r) {
  std::printf(
      "%6u %7u %12u %10s %10s %11s %6d %9d %10u %14u %10s %s\n", r.step, r.capture, r.timestamp_us,
      fixed_decimal(r.pose.x.raw(), 32, 3).c_str(), fixed_decimal(r.pose.y.raw(), 32, 3).c_str(),
      angle_degrees(r.pose.heading.bam, 2).c_str(), r.place, r.runner_up, r.cost, r.runner_up_cost,
      fixed_decimal(r.confidence.raw(), 16, 4).c_str(), r.localised ? "yes" : "no");
}

int run_results(const ResultsOptions& o) {
  LogSource source;
  const std::string error = source.open(o.source, storage::kResultsFile);
  if (!error.empty()) return fail(error);
  storage::ResultsReader reader;
  storage::LogProblem problem = storage::LogProblem::kNone;
  if (reader.open(source.device(), &problem) != Status::kOk) {
    return fail(source.name() + ": " + log_open_problem(source.device(), "results", problem));
  }

  const bool csv = !o.csv.empty();
  const bool to_stdout = !csv || o.csv == "-";
  std::FILE* out = stdout;
  if (csv && !to_stdout) {
    out = std::fopen(o.csv.c_str(), "w");
    if (out == nullptr) return fail(o.csv + ": cannot create: " + std::strerror(errno));
  }
  if (csv) {
    std::fprintf(out,
                 "step,capture,timestamp_us,x_m,y_m,heading_deg,place,runner_up,cost,"
                 "runner_up_cost,confidence,localised\n");
  } else {
    std::printf("%6s %7s %12s %10s %10s %11s %6s %9s %10s %14s %10s %s\n", "step", "capture",
                "timestamp_us", "x_m", "y_m", "heading_deg", "place", "runner_up", "cost",
                "runner_up_cost", "confidence", "localised");
  }
  uint32_t count = 0;
  uint32_t localised = 0;
  uint32_t damaged = 0;
  Status end = Status::kOk;
  for (;;) {
    storage::RunResult r;
    const Status s = reader.next(&r);
    if (s == Status::kOk) {
      ++count;
      if (r.localised) ++localised;
      if (csv) {
        print_csv(out, r);
      } else {
        print_row(r);
      }
    } else if (s == Status::kDataLoss || s == Status::kResourceExhausted) {
      ++damaged;
    } else {
      end = s;
      break;
    }
  }
  bool write_failed = false;
  if (out != stdout) {
    write_failed = std::ferror(out) != 0;
    write_failed = std::fclose(out) != 0 || write_failed;
  } else {
    std::fflush(stdout);
  }
  if (write_failed) return fail(o.csv + ": write failed");

  const storage::LogProblem how = reader.end_problem();
  std::string ending = how == storage::LogProblem::kEndClean ? "the log ends cleanly"
                       : how == storage::LogProblem::kEndDamagedTail
                           ? "the log ends with a damaged tail"
                           : std::string("the log ends: ") + storage::log_problem_text(how);
  const std::string summary = std::to_string(count) + " results (" + std::to_string(localised) +
                              " localised), " + std::to_string(damaged) + " damaged records; " +
                              ending;
  if (!csv) {
    std::printf("%s\n", summary.c_str());
  } else if (!to_stdout) {
    std::printf("%s: %s\n", o.csv.c_str(), summary.c_str());
  }

  if (end != Status::kOutOfRange) {
    return fail(source.name() + ": read failed after " + std::to_string(count) + " results (" +
                status_name(end) + ")");
  }
  int code = kExitOk;
  if (how == storage::LogProblem::kEndDamagedTail) {
    warn(source.name() + ": " + storage::log_problem_text(how));
  }
  if (damaged > 0) {
    warn(source.name() + ": " + std::to_string(damaged) +
         " damaged record(s) in the middle of the log were skipped");
    code = kExitFailure;
  }
  if (warn_if_truncated(source)) code = kExitFailure;
  return code;
}

}  // namespace

void add_results_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<ResultsOptions>();
  CLI::App* results =
      app.add_subcommand("results",
                         "Print the firmware's localisation results (one per step) as a table, or "
                         "write them as CSV");
  results
      ->add_option("IMAGE", o->source,
                   "Disk image (reads its volume file 'results'), IMAGE:NAME for another "
                   "volume file, or a standalone results file")
      ->required();
  results
      ->add_option(
          "--csv", o->csv,
          "Write CSV to OUT ('-' = standard output) with the header step,capture,timestamp_us,"
          "x_m,y_m,heading_deg,place,runner_up,cost,runner_up_cost,confidence,localised: "
          "timestamp in microseconds, position in metres (10 decimals) and heading in degrees "
          "(-180..180, 8 decimals) exactly as stored, costs as stored integers, confidence = best "
          "/ runner-up cost (6 decimals, smaller = more certain), localised 1/0")
      ->type_name("OUT");
  results->callback([chosen, o] { *chosen = [o] { return run_results(*o); }; });
}

}  // namespace seqslam::cli
