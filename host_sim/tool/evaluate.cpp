#include "evaluate.h"

#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>

#include "seqslam/preprocess.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/dream_images.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::sim {

namespace {

struct Pair {
  std::string library, query, truth, description;
};

bool parse_method(const std::string& name, Preprocessing* out) {
  for (int m = 0; m <= 6; ++m) {
    if (name == preprocessing_name(static_cast<Preprocessing>(m))) {
      *out = static_cast<Preprocessing>(m);
      return true;
    }
  }
  return false;
}

}  // namespace

int evaluate(const EvaluateOptions& o) {
  const std::string list = o.dir + "/pairs.csv";
  // A regular file only (a FIFO or device would block or never end; input_file.h).
  if (const std::string why = tools::check_regular_input(list); !why.empty()) {
    std::fprintf(stderr, "seqslam-sim: %s (generate a scenario first)\n", why.c_str());
    return 1;
  }
  std::ifstream in(list);
  if (!in) {
    std::fprintf(stderr, "seqslam-sim: %s: cannot open (generate a scenario first)\n",
                 list.c_str());
    return 1;
  }
  std::vector<Pair> pairs;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (number == 1 || line.empty()) continue;  // header
    std::stringstream ss(line);
    Pair p;
    if (!std::getline(ss, p.library, ',') || !std::getline(ss, p.query, ',') ||
        !std::getline(ss, p.truth, ',') || !std::getline(ss, p.description)) {
      std::fprintf(stderr, "seqslam-sim: %s:%d: expected library,query,ground_truth,description\n",
                   list.c_str(), number);
      return 1;
    }
    pairs.push_back(p);
  }
  if (!o.markdown.empty()) {
    tools::InputFiles inputs;  // --markdown must be none of the files read
    inputs.add(list);
    for (const Pair& p : pairs) {
      for (const std::string* f : {&p.library, &p.query, &p.truth})
        inputs.add(o.dir + "/" + *f);
    }
    const std::string clash = inputs.clash(o.markdown);
    if (!clash.empty()) {
      std::fprintf(stderr, "seqslam-sim: --markdown %s\n", clash.c_str());
      return 2;
    }
  }
  std::vector<Preprocessing> methods;
  for (const std::string& m : o.methods) {
    Preprocessing p;
    if (!parse_method(m, &p)) {
      std::fprintf(stderr, "seqslam-sim: unknown preprocessing '%s'\n", m.c_str());
      return 2;
    }
    methods.push_back(p);
  }
  struct Row {
    std::string text;
    std::string error;
  };
  std::vector<Row> rows(pairs.size() * methods.size());
  parallel_for(rows.size(), o.jobs, [&](size_t job) {
    const Pair& p = pairs[job / methods.size()];
    const Preprocessing method = methods[job % methods.size()];
    Row& row = rows[job];
    const auto lib = tools::load_dream_places(o.dir + "/" + p.library);
    const auto qry = tools::load_dream_places(o.dir + "/" + p.query);
    const auto gt = tools::load_ground_truth(o.dir + "/" + p.truth);
    for (const std::string* e : {&lib.error(), &qry.error(), &gt.error()}) {
      if (!e->empty()) {
        row.error = *e;
        return;
      }
    }
    if (lib.value().images.empty() || qry.value().images.empty()) {
      row.error = p.library + " / " + p.query + ": no places";
      return;
    }
    LocaliserConfig c = o.run.localiser();
    c.image_size = ImageSize{static_cast<uint16_t>(lib.value().images[0].width),
                             static_cast<uint16_t>(lib.value().images[0].height)};
    c.preprocess.method = method;
    const auto matches = tools::run_core(lib.value().images, qry.value().images, c);
    if (!matches) {
      row.error = p.library + " / " + p.query + ": " + matches.error();
      return;
    }
    const tools::GroundTruth& truth = gt.value();
    const tools::PrSummary s = tools::score_matches(
        matches.value(), [&](uint32_t q, uint32_t r) { return truth.is_correct(q, r); },
        [&](uint32_t q) { return truth.has_match(q); });
    const double threshold = tools::to_double(c.sequence.threshold);
    const tools::PrPoint op = s.at_threshold(threshold);
    char buf[512];
    std::snprintf(buf, sizeof buf, "| %s | %s | %zu | %.1f | %.1f | %.3f | %.1f / %.1f |",
                  p.description.c_str(), preprocessing_name(method), s.queries, 100.0 * s.top1,
                  100.0 * s.recall_at_100_precision, s.auc_pr, 100.0 * op.precision,
                  100.0 * op.recall);
    row.text = buf;
  });
  std::string table =
      "| pair (library -> query) | preprocessing | queries | top-1 % | recall at 100 % "
      "precision | AUC-PR | precision / recall % at " +
      std::to_string(tools::to_double(o.run.sequence.threshold)).substr(0, 4) +
      " |\n"
      "|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    if (!r.error.empty()) {
      std::fprintf(stderr, "seqslam-sim: %s\n", r.error.c_str());
      return 1;
    }
    table += r.text + "\n";
  }
  std::printf("%s", table.c_str());
  if (!o.markdown.empty()) {
    const std::string error = tools::write_output(o.markdown, table);
    if (!error.empty()) {
      std::fprintf(stderr, "seqslam-sim: %s\n", error.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace seqslam::sim
