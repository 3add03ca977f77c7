// seqslam graph FILE.g2o|FILE.txt --out OUT.g2o [--truth T] [--json J]: the core's pose-graph
// optimiser (pose_graph.h) on a 2-D pose graph of the SLAM literature, as an outside user of
// the library runs it (issue 35; docs/mapping.md, "Public pose graphs"): the file's edges
// k-1 -> k are the odometry chain fed to add_node() (the chain's poses composed from the
// measurements, node 0 at the file's vertex 0 or the origin), every other edge a loop closure,
// each with the file's information (scaled by one power of two to fit the core's UQ16.16);
// optimise_step() until converged or failed; the result written as g2o, and the figures
// (chi2 with the file's information, ATE against a truth, work, time, exit reason) printed and
// in the JSON.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "reference.h"
#include "seqslam/pose_graph.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/pose_graph_export.h"
#include "seqslam_tools/pose_graph_file.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::cli {

namespace {

struct GraphOptions {
  std::string input;
  std::string out;
  std::string truth;
  std::string json;
  double tolerance_xy = 1e-3;       // metres
  double tolerance_heading = 1e-4;  // radians
  // Each stage certified within 1e-3 of its minimum's objective (the file's chi2 units), with
  // the tree preconditioner (docs/mapping.md: intel and manhattanOlson3500 then end every stage
  // by its tolerance, MIT its finish at the arithmetic's resolution, with the bound stated).
  double tolerance_objective = 1e-3;
  std::string preconditioner = "tree";
  // Measured on the three shared graphs (docs/mapping.md): a fixed cap keeps the work per
  // recomputation linear in the graph, and enough relinearisations reach the optimum.
  int max_iterations = 1000;
  int max_restarts = 30;
  int refine = 30;
  uint32_t budget = 1u << 16;
  bool reference = false;
  bool quiet = false;
  bool trace = false;
};

// The core's storage for one graph, sized to it.
struct CoreGraph {
  std::vector<PoseGraphNode> nodes;
  std::vector<PoseGraphEdge> edges;
  std::vector<PoseGraphSolverSlot> solver;
  std::vector<PoseGraphRefineSlot> refine;
  std::vector<PoseGraphTreeSlot> tree;
  PoseGraph graph;
};

UQ16_16 unsigned_info(double v) {
  return UQ16_16::from_raw(static_cast<uint32_t>(std::llround(std::max(0.0, v) * 65536.0)));
}
Q15_16 signed_info(double v) {
  return Q15_16::from_raw(static_cast<int32_t>(std::llround(v * 65536.0)));
}

// The file's information of `e` times `scale`, in the core's form: g2o's error is
// Z^-1 (X_from^-1 X_to), whose position part is the core's (in from's frame) turned by the
// measured -dtheta, so the same objective has the position rows and columns turned by
// +dtheta: Omega_pos' = R Omega_pos R^T, Omega_pt' = R Omega_pt (tools::information_in_from_frame).
PoseInformation information_of(const tools::GraphEdge& e, double scale) {
  double m[6];
  tools::information_in_from_frame(e, m);
  PoseInformation in;
  in.along = unsigned_info(m[0] * scale);
  in.cross = signed_info(m[1] * scale);
  in.along_heading = signed_info(m[2] * scale);
  in.lateral = unsigned_info(m[3] * scale);
  in.lateral_heading = signed_info(m[4] * scale);
  in.heading = unsigned_info(m[5] * scale);
  return in;
}

Pose2 fixed_pose(const tools::GraphPose& p) {
  return Pose2{Q31_32::from_raw(std::llround(p.x * 4294967296.0)),
               Q31_32::from_raw(std::llround(p.y * 4294967296.0)),
               tools::angle_from_radians(p.theta)};
}

std::string edge_where(const std::string& name, const tools::GraphEdge& e) {
  return name + ":" + std::to_string(e.line) + ": ";
}

// Builds the core graph; "" or the message (naming the file and line).
std::string build(const tools::GraphFile& file, const std::string& name, const GraphOptions& o,
                  CoreGraph* core, tools::GraphFigures* f) {
  long last = 0;
  for (const tools::GraphVertex& v : file.vertices)
    last = std::max(last, v.id);
  for (const tools::GraphEdge& e : file.edges)
    last = std::max(last, std::max(e.from, e.to));
  const size_t n = static_cast<size_t>(last) + 1;
  // The chain: the first edge k-1 -> k of each k.
  std::vector<const tools::GraphEdge*> chain(n, nullptr);
  std::vector<bool> in_chain(file.edges.size(), false);
  for (size_t i = 0; i < file.edges.size(); ++i) {
    const tools::GraphEdge& e = file.edges[i];
    if (e.to == e.from + 1 && chain[static_cast<size_t>(e.to)] == nullptr) {
      chain[static_cast<size_t>(e.to)] = &e;
      in_chain[i] = true;
    }
  }
  for (size_t k = 1; k < n; ++k) {
    if (chain[k] == nullptr) {
      return name + ": node " + std::to_string(k) + " has no odometry edge from node " +
             std::to_string(k - 1) + " (the optimiser needs the chain 0 -> 1 -> ... -> " +
             std::to_string(n - 1) + ")";
    }
  }
  // One power of two for all information: the largest entry just below 2^15 (Q15.16).
  double largest = 0.0;
  for (const tools::GraphEdge& e : file.edges)
    for (const double v : e.info)
      largest = std::max(largest, std::fabs(v));
  const int scale_log2 =
      largest > 0.0 ? static_cast<int>(std::floor(std::log2(32767.0 / largest))) : 0;
  const double scale = std::ldexp(1.0, scale_log2);
  f->information_scale_log2 = scale_log2;

  const size_t edges = file.edges.size();
  core->nodes.assign(n, PoseGraphNode{});
  core->edges.assign(std::max<size_t>(edges, 1), PoseGraphEdge{});
  core->solver.assign(n, PoseGraphSolverSlot{});
  core->refine.assign(o.refine > 0 ? n : 0, PoseGraphRefineSlot{});
  const bool tree = o.preconditioner == "tree";
  core->tree.assign(tree ? n : 0, PoseGraphTreeSlot{});
  PoseGraphConfig c;
  c.tolerance_xy =
      Q31_32::from_raw(std::max<int64_t>(1, std::llround(o.tolerance_xy * 4294967296.0)));
  c.tolerance_heading = Angle{static_cast<uint32_t>(
      std::max<int64_t>(1, std::llround(o.tolerance_heading / (2 * M_PI) * 4294967296.0)))};
  c.tolerance_objective =
      Q31_32::from_raw(std::llround(std::ldexp(o.tolerance_objective * scale, 32)));
  c.max_iterations = static_cast<uint16_t>(o.max_iterations);
  c.max_restarts = static_cast<uint16_t>(o.max_restarts);
  c.refine_restarts = static_cast<uint16_t>(o.refine);
  c.tree_preconditioner = tree;
  PoseGraphBuffers b{Span<PoseGraphNode>(core->nodes.data(), n),
                     Span<PoseGraphEdge>(core->edges.data(), core->edges.size()),
                     Span<PoseGraphSolverSlot>(core->solver.data(), n),
                     Span<PoseGraphRefineSlot>(core->refine.data(), core->refine.size()),
                     Span<PoseGraphTreeSlot>(core->tree.data(), core->tree.size())};
  core->graph.enable_refine();
  if (core->graph.configure(c, b) != Status::kOk) {
    return "the optimiser's settings are out of range (tolerances 2^-32..2^-8 m and up to "
           "0.0245 rad, objective 0..2^30 once scaled, iterations 0..10000, restarts 1..1000, "
           "refine 0..1000)";
  }
  tools::GraphPose pose{};
  for (const tools::GraphVertex& v : file.vertices)
    if (v.id == 0) pose = v.pose;
  for (size_t k = 0; k < n; ++k) {
    if (k > 0) pose = tools::compose(pose, chain[k]->measured);
    const Result<uint32_t> r =
        k == 0 ? core->graph.add_node(fixed_pose(pose), 0)
               : core->graph.add_node(fixed_pose(pose), static_cast<uint32_t>(k),
                                      information_of(*chain[k], scale));
    if (r.ok()) continue;
    const std::string at = k == 0 ? name + ": " : edge_where(name, *chain[k]);
    if (r.status() == Status::kOutOfRange) return at + "an odometry step of 128 m or more";
    return at + "the odometry information (times 2^" + std::to_string(scale_log2) +
           ") must be positive definite with eigenvalues and heading of at least 1/256 (its "
           "range across the file is wider than the optimiser's UQ16.16)";
  }
  for (size_t i = 0; i < edges; ++i) {
    if (in_chain[i]) continue;
    const tools::GraphEdge& e = file.edges[i];
    const RelativePose2 m{Q31_32::from_raw(std::llround(e.measured.x * 4294967296.0)),
                          Q31_32::from_raw(std::llround(e.measured.y * 4294967296.0)),
                          tools::angle_from_radians(e.measured.theta)};
    const Status s = core->graph.add_loop_closure(
        static_cast<uint32_t>(e.from), static_cast<uint32_t>(e.to), m, information_of(e, scale));
    if (s == Status::kOk) continue;
    if (s == Status::kOutOfRange) return edge_where(name, e) + "a measured step of 128 m or more";
    return edge_where(name, e) + "the information, rounded to the optimiser's UQ16.16 (times 2^" +
           std::to_string(scale_log2) + "), is not positive semi-definite";
  }
  f->nodes = static_cast<uint32_t>(n);
  f->edges = static_cast<uint32_t>(edges);
  f->odometry_edges = static_cast<uint32_t>(n - 1);
  f->loop_closures = core->graph.closure_count();
  return "";
}

// Runs the optimiser in slices of o.budget units to its end; --trace prints each residual
// recomputation. The wall time goes into f.
void optimise(const GraphOptions& o, const tools::GraphFile& data, PoseGraph& g,
              tools::GraphFigures* f) {
  const auto t0 = std::chrono::steady_clock::now();
  PoseGraphProgress p;
  Status s = Status::kOk;
  const bool trace = o.trace;
  uint32_t last_restarts = 0;
  do {
    s = g.optimise_step(o.budget, &p);
    ++f->slices;
    if (trace && g.stats().restarts != last_restarts) {
      last_restarts = g.stats().restarts;
      std::fprintf(stderr,
                   "stage %d, residual recomputations %u, CG iterations %u, work %llu, stalls "
                   "%u, rescales %u, bounds %.3g %.3g %.3g, chi2 %.9g\n",
                   static_cast<int>(g.stage()), g.stats().restarts, g.stats().iterations,
                   static_cast<unsigned long long>(
                       g.stats().node_visits + g.stats().closure_visits + g.stats().scalar_steps),
                   g.stats().stalls, g.stats().rescales,
                   std::ldexp(static_cast<double>(g.stats().objective_bound[0]), -32),
                   std::ldexp(static_cast<double>(g.stats().objective_bound[1]), -32),
                   std::ldexp(static_cast<double>(g.stats().objective_bound[2]), -32),
                   tools::graph_chi2(data, tools::graph_poses_of(g)));
    }
  } while (s == Status::kOk && !p.converged);
  f->wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The optimiser's counters, exit and certified bounds (in the file's units) into f.
void record_stats(const PoseGraph& g, tools::GraphFigures* f) {
  const PoseGraphStats& st = g.stats();
  f->work_units = st.node_visits + st.closure_visits + st.scalar_steps;
  f->cg_iterations = st.iterations;
  f->residual_recomputations = st.restarts;
  f->relinearisations = st.relinearisations;
  f->rescales = st.rescales;
  f->max_scale = st.max_scale;
  f->stalls = st.stalls;
  f->exit_reason = g.failed()         ? "failed"
                   : st.exhausted > 0 ? "exhausted"
                   : st.stalls > 0    ? "resolution"
                                      : "tolerance";
  if (!g.failed()) {
    // The certified bounds, in the file's units (the core's information is the file's times
    // 2^information_scale_log2; V times the bound does not depend on it).
    const double unscale = std::ldexp(1.0, -f->information_scale_log2);
    const double b0 = std::ldexp(static_cast<double>(st.objective_bound[0]), -32);
    const double b1 = std::ldexp(static_cast<double>(st.objective_bound[1]), -32);
    f->objective_bound_headings = b0 * unscale;
    f->objective_bound_positions = b1 * unscale;
    if (g.config().refine_restarts > 0) {
      f->objective_bound_finish =
          std::ldexp(static_cast<double>(st.objective_bound[2]), -32) * unscale;
    }
    f->heading_bound_rad =
        std::sqrt(std::ldexp(static_cast<double>(g.chain_variance_sum(true)), -24) * b0);
    f->position_bound_m =
        std::sqrt(std::ldexp(static_cast<double>(g.chain_variance_sum(false)), -24) * b1);
  }
  f->tolerance_xy_m = tools::to_double(g.config().tolerance_xy);
  f->tolerance_heading_rad = tools::to_radians(g.config().tolerance_heading);
  f->tolerance_objective = f->information_scale_log2 >= -64
                               ? tools::to_double(g.config().tolerance_objective) *
                                     std::ldexp(1.0, -f->information_scale_log2)
                               : 0.0;
  f->max_iterations = g.config().max_iterations;
  f->max_restarts = g.config().max_restarts;
  f->refine_restarts = g.config().refine_restarts;
}

// Double-precision Gauss-Newton of the same stored problem (the core's rounded measurements
// and information), started from the fixed-point result; its objective and differences into f.
void add_reference(const PoseGraph& g, const tools::GraphFile& data,
                   const std::vector<tools::GraphPose>& result,
                   const std::vector<tools::GraphPose>& truth, tools::GraphFigures* f) {
  std::vector<reference::PoseRef> start;
  for (const tools::GraphPose& q : result)
    start.push_back({q.x, q.y, q.theta});
  const std::vector<reference::PoseRef> ref =
      reference::pose_graph_gauss_newton(reference::pose_edges_of(g), start, 1.0, 1.0, 50);
  std::vector<tools::GraphPose> rp;
  double dp = 0.0;
  double dh = 0.0;
  for (size_t i = 0; i < ref.size(); ++i) {
    rp.push_back({ref[i].x, ref[i].y, ref[i].theta});
    dp = std::max(dp, std::hypot(ref[i].x - result[i].x, ref[i].y - result[i].y));
    dh = std::max(dh, std::fabs(tools::wrap_angle(ref[i].theta - result[i].theta)));
  }
  f->reference_chi2 = tools::graph_chi2(data, rp);
  f->reference_max_position_difference_m = dp;
  f->reference_max_heading_difference_rad = dh;
  if (!truth.empty()) f->reference_ate_m = tools::absolute_trajectory_error(rp, truth);
}

// The optimised graph (unless the optimiser failed) and the JSON; "" or the error.
std::string write_outputs(const GraphOptions& o, const PoseGraph& g, const tools::GraphFile& data,
                          const std::vector<tools::GraphPose>& result,
                          const tools::GraphFigures& f) {
  if (!g.failed()) {
    const std::string e = tools::write_output(o.out, tools::g2o_text(result, data.edges));
    if (!e.empty()) return e;
  }
  if (!o.json.empty()) return tools::write_output(o.json, tools::graph_figures_json(f));
  return "";
}

void print_figures(const GraphOptions& o, const PoseGraph& g, const tools::GraphFigures& f) {
  std::printf("%s: %s, %u nodes, %u edges (%u loop closures), information x 2^%d\n",
              o.input.c_str(), f.format.c_str(), f.nodes, f.edges, f.loop_closures,
              f.information_scale_log2);
  std::printf("chi2: %.6g chained odometry -> %.6g optimised", f.chi2_initial, f.chi2_final);
  if (f.chi2_file_vertices) std::printf(" (the file's vertices: %.6g)", *f.chi2_file_vertices);
  std::printf("\n");
  if (f.ate_final_m) {
    std::printf("ATE: %.4f m chained odometry -> %.4f m optimised\n", *f.ate_initial_m,
                *f.ate_final_m);
  }
  std::printf(
      "work: %llu units in %llu slices, %u CG iterations, %u residual "
      "recomputations, %u relinearisations, %u rescales (coarsest 2^%u), %.3f s; exit: "
      "%s\n",
      static_cast<unsigned long long>(f.work_units), static_cast<unsigned long long>(f.slices),
      f.cg_iterations, f.residual_recomputations, f.relinearisations, f.rescales, f.max_scale,
      f.wall_time_s, f.exit_reason.c_str());
  if (!g.failed()) {
    std::printf("certified: objective within %.3g (headings), %.3g (positions)",
                *f.objective_bound_headings, *f.objective_bound_positions);
    if (f.objective_bound_finish) std::printf(", %.3g (finish)", *f.objective_bound_finish);
    std::printf(" of each stage's minimum; LAGO within %.3g rad, %.3g m of its exact solution\n",
                *f.heading_bound_rad, *f.position_bound_m);
  }
  if (f.reference_chi2) {
    std::printf(
        "double reference (Gauss-Newton from the result): chi2 %.6g, largest "
        "difference %.3g m, %.3g rad\n",
        *f.reference_chi2, *f.reference_max_position_difference_m,
        *f.reference_max_heading_difference_rad);
  }
}

int run_graph(const GraphOptions& o) {
  tools::InputFiles inputs;
  inputs.add(o.input);
  if (!o.truth.empty()) inputs.add(o.truth);
  if (const int rc = refuse_inputs_as_outputs(inputs, {o.out, o.json}); rc != kExitOk) return rc;
  auto file = tools::load_pose_graph(o.input);
  if (!file) return fail(file.error());
  std::vector<tools::GraphPose> truth;
  if (!o.truth.empty()) {
    auto t = tools::load_pose_graph(o.truth);
    if (!t) return fail(t.error());
    auto traj = tools::graph_trajectory(t.value(), o.truth);
    if (!traj) return fail(traj.error());
    truth = std::move(traj.value());
  }
  tools::GraphFigures f;
  f.input = o.input;
  f.format = file.value().isam ? "isam" : "g2o";
  auto core = std::make_unique<CoreGraph>();
  if (const std::string e = build(file.value(), o.input, o, core.get(), &f); !e.empty()) {
    return fail(e);
  }
  PoseGraph& g = core->graph;
  const tools::GraphFile& data = file.value();
  const std::vector<tools::GraphPose> initial = tools::graph_poses_of(g);
  f.chi2_initial = tools::graph_chi2(data, initial);
  if (!data.vertices.empty()) {
    auto own = tools::graph_trajectory(data, o.input);
    if (own && own.value().size() == initial.size()) {
      f.chi2_file_vertices = tools::graph_chi2(data, own.value());
    }
  }
  if (!truth.empty()) f.ate_initial_m = tools::absolute_trajectory_error(initial, truth);

  optimise(o, data, g, &f);
  record_stats(g, &f);
  const std::vector<tools::GraphPose> result = tools::graph_poses_of(g);
  f.chi2_final = tools::graph_chi2(data, result);
  if (!truth.empty()) f.ate_final_m = tools::absolute_trajectory_error(result, truth);

  if (o.reference && !g.failed()) add_reference(g, data, result, truth, &f);
  if (const std::string e = write_outputs(o, g, data, result, f); !e.empty()) return fail(e);
  if (!o.quiet) print_figures(o, g, f);
  if (g.failed()) {
    return fail(o.input +
                ": the graph is beyond the optimiser's limits (pose_graph.h, "
                "\"Limits\"): no result written");
  }
  return kExitOk;
}

}  // namespace

void add_graph_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<GraphOptions>();
  CLI::App* c = app.add_subcommand(
      "graph",
      "Optimise a 2-D pose graph (g2o VERTEX_SE2/EDGE_SE2 or iSAM ODOMETRY/EDGE2) with the "
      "core's fixed-point optimiser and write the result as g2o (docs/mapping.md)");
  c->add_option("input", o->input, "The graph (g2o or iSAM 2-D text)")->required();
  c->add_option("--out", o->out, "The optimised graph, g2o")->required();
  c->add_option("--truth", o->truth,
                "True trajectory for the ATE: g2o VERTEX_SE2 lines, or an iSAM ground-truth "
                "file whose chained odometry is the trajectory");
  c->add_option("--json", o->json, "The figures as JSON");
  c->add_option("--tolerance-xy", o->tolerance_xy, "Position tolerance, metres")
      ->capture_default_str();
  c->add_option("--tolerance-heading", o->tolerance_heading, "Heading tolerance, radians")
      ->capture_default_str();
  c->add_option("--tolerance-objective", o->tolerance_objective,
                "Each stage also ends once its objective is certified within this of the "
                "stage's minimum (the file's chi2 units; 0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  c->add_option("--preconditioner", o->preconditioner,
                "chain: the odometry chain; tree: the chain with the loop closures stiffer than "
                "it as shortcuts (pose_graph.h)")
      ->capture_default_str()
      ->check(CLI::IsMember({"chain", "tree"}));
  c->add_option("--max-iterations", o->max_iterations,
                "CG iterations per residual recomputation (0: closures x components + 9)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  c->add_option("--max-restarts", o->max_restarts, "Residual recomputations per LAGO stage")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  c->add_option("--refine", o->refine, "Gauss-Newton relinearisations after LAGO (0: LAGO only)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  c->add_option("--budget", o->budget, "Work units per optimise_step call")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 30));
  c->add_flag("--reference", o->reference,
              "Also polish the result with double-precision Gauss-Newton (tools/reference) and "
              "report the difference");
  c->add_flag("--quiet", o->quiet, "Print nothing but errors");
  c->add_flag("--trace", o->trace,
              "Print the stage, counters and chi2 at every residual recomputation (stderr)");
  c->callback([o, chosen]() { *chosen = [o]() { return run_graph(*o); }; });
}

}  // namespace seqslam::cli
