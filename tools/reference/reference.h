// The double-precision reference of the whole localisation pipeline: the test oracle.
//
// Written for clarity, not speed, straight from the equations of the 2025 thesis (and the
// definitions in include/seqslam/*.h where the thesis leaves a choice open): plain loops,
// doubles, std::vector, and *direct* summation of sequence costs (eq. 4.12) instead of the
// core's incremental update, so the two implementations share no algorithmic shortcut.
// Host only: the oracle of the tests, and `seqslam eval --reference`.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "seqslam/localiser.h"
#include "seqslam/pose_graph.h"

namespace seqslam::reference {

using Image = std::vector<uint8_t>;

struct Params {
  int width = 32;
  int height = 16;
  Preprocessing method = Preprocessing::kHistEq;
  int patch_width = 4;
  int patch_height = 4;
  double pn_epsilon = 1.0;
  double pn_gain = 32.0;
  int max_shift = 0;
  int seq_len = 30;
  int window = 50;
  double sigma_min = 1.0;
  int exclusion = 10;
  double threshold = 0.85;
  int recent_exclusion = 50;

  // The same settings as a core configuration (fixed-point values converted exactly).
  static Params from(const LocaliserConfig& config);
};

Image equalise_histogram(const Image& in);
Image patch_normalise(const Params& p, const Image& in);
Image inverse_gamma(const Image& in);
Image preprocess(const Params& p, const Image& in);

// MAD in grey levels (eq. 4.5), or the shift-tolerant minimum over |dx| <= max_shift.
double mad(const Params& p, const Image& a, const Image& b);

// D+ of one difference row given in MAD grey levels (normalise.h defines it).
std::vector<double> normalise(const Params& p, const std::vector<double>& mad_row);

struct Match {
  int place = -1;
  double cost = 0.0;
  int runner_up = -1;
  double runner_up_cost = 0.0;
  double confidence = 1.0;
  bool localised = false;
};

// Best place, runner-up outside +-R and confidence over the places with a full sequence.
// The confidence uses the costs minus `offset` (sequence_matcher.h: S times the smallest
// normalised difference seen since reset online; S times the global minimum in batch).
Match select(const Params& p, const std::vector<double>& cost, const std::vector<bool>& valid,
             double offset);

class Pipeline {
 public:
  explicit Pipeline(const Params& p) : p_(p) {}

  void teach(const Image& raw);
  Match localise(const Image& raw);
  // Loop-closure mode: match against places older than recent_exclusion, then add.
  Match observe(const Image& raw);
  void reset_sequence() {
    first_row_ = rows_.size();
    min_value_ = std::numeric_limits<double>::infinity();
  }

  const std::vector<double>& last_costs() const { return last_costs_; }
  const std::vector<bool>& last_valid() const { return last_valid_; }
  const std::vector<double>& last_mad_row() const { return last_mad_; }
  size_t library_size() const { return library_.size(); }

 private:
  Match step(const Image& query, size_t places);

  Params p_;
  std::vector<Image> library_;
  std::vector<std::vector<double>> rows_;  // D+ rows of all steps
  size_t first_row_ = 0;
  double min_value_ = std::numeric_limits<double>::infinity();  // smallest D+ since reset
  std::vector<double> last_costs_;
  std::vector<bool> last_valid_;
  std::vector<double> last_mad_;
};

// OpenSeqSLAM-style batch processing for comparison (docs/normalisation.md): every row is
// z-scored (as normalise() without the offset), then the whole matrix is shifted so its global
// minimum is 0, then eq. 4.12 and eqs. 4.14-4.16 are applied per query. `mad_matrix[i][j]` is
// the MAD of query i to library place j.
std::vector<Match> batch_match(const Params& p, const std::vector<std::vector<double>>& mad_matrix);

// Slope search of time-sampled SeqSLAM (slope_matcher.h), online: `rows[i]` is the D+ row of
// query i since the last reset (rows may differ in length), `velocities` the velocities in
// places per query step (pass the core's UQ8_8 values / 256 to compare exactly). For each
// query i >= S-1, place j and velocity v, the trajectory cost is the direct sum
// sum_{k<S} rows[i-k][floor(j - v k + 1/2)], defined iff every cell exists; the place's cost
// is the minimum over v; select() with the offset S times the smallest D+ of rows 0..i.
std::vector<Match> slope_match(const Params& p, const std::vector<std::vector<double>>& rows,
                               const std::vector<double>& velocities);

}  // namespace seqslam::reference

// ---- Occupancy grid (occupancy_grid.h) ----
namespace seqslam::reference {

struct GridCellRef {
  long col = 0;
  long row = 0;
  bool operator==(const GridCellRef& o) const { return col == o.col && row == o.row; }
};

// Every cell the segment from (x0, y0) to (x1, y1) passes through or touches, in the order
// the segment reaches them: coordinates in cells, cell (c, r) = [c, c+1) x [r, r+1).
// Amanatides-Woo traversal in double from the start point's cell (floor) to the end point's,
// the crossing parameters computed directly from each boundary (no accumulated error); where
// the segment crosses a cell corner (x and y crossings within `tie` of each other in the
// segment parameter t in [0, 1]) both side cells are listed before the diagonal one, so a
// cell the segment only touches at a corner is included. A near-tie (not exactly a corner)
// adds a cell the segment misses by less than `tie` of its length: the list is then a
// superset, never a subset, of the exact one.
std::vector<GridCellRef> grid_supercover(double x0, double y0, double x1, double y1,
                                         double tie = 1e-9);

}  // namespace seqslam::reference

// ---- Pose graph (pose_graph.h) ----
namespace seqslam::reference {

// A pose in metres and radians (solutions carry unwrapped headings).
struct PoseRef {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

// An edge: the pose of `to` seen from `from` (dx along from's heading, dy to its left, dtheta
// the turn, any representative), with position and heading information weights.
struct PoseEdgeRef {
  int from = 0;
  int to = 0;
  double dx = 0.0;
  double dy = 0.0;
  double dtheta = 0.0;
  double info_xy = 1.0;  // position information (along from's heading)
  double info_heading = 1.0;
  double info_lateral = -1.0;  // position information across from's heading; < 0: info_xy
  // The other terms of the symmetric 3x3 information in from's frame (along, across,
  // heading): position along-across, along-heading, across-heading. The linear solve uses the
  // position block and the heading; Gauss-Newton the whole matrix.
  double info_cross = 0.0;
  double info_along_heading = 0.0;
  double info_lateral_heading = 0.0;
};

// The edges of a core PoseGraph in double (metres, radians, information weights as stored,
// the whole 3x3 matrix), odometry edges first.
std::vector<PoseEdgeRef> pose_edges_of(const PoseGraph& graph);

// The two-stage linear least-squares problem of pose_graph.h solved directly (dense Cholesky
// of the weighted graph Laplacians, node 0 fixed at `anchor`):
//  1. headings: min sum info_heading (theta_to - theta_from - dtheta')^2, where dtheta' is
//     dtheta plus the multiple of 2 pi that brings it closest to the odometry chain's turn
//     between the two nodes (the chain's own edges are taken as they are);
//  2. positions: min sum r^T R(theta_from) diag(info_xy, info_lateral) R(theta_from)^T r with
//     r = p_to - p_from - R(theta_from) (dx, dy) and those headings (x and y apart when every
//     edge weighs both directions alike, one dense system for both otherwise).
// edges[k-1] must be the odometry edge k-1 -> k for k = 1..nodes-1; further edges are loop
// closures. Returns the `nodes` poses.
std::vector<PoseRef> pose_graph_linear(int nodes, const std::vector<PoseEdgeRef>& edges,
                                       const PoseRef& anchor);

// The same two-stage problem solved iteratively, for graphs too large for the dense solve
// (10 000 nodes): each stage by conjugate gradients preconditioned by the odometry chain
// (in double), to a relative residual of 1e-15 (or 20 000 iterations). Same contract.
std::vector<PoseRef> pose_graph_linear_iterative(int nodes, const std::vector<PoseEdgeRef>& edges,
                                                 const PoseRef& anchor);

// The full nonlinear problem for comparison: min sum e^T W e with
// e = (R(theta_from)^T (p_to - p_from) - (dx, dy), wrap(theta_to - theta_from - dtheta)) and
// W = the 3x3 information with its position rows and columns divided by sqrt(var_xy) and its
// heading's by sqrt(var_heading) (var_*: variance
// per unit of information, i.e. of 1 m of odometry: m^2 and rad^2), node 0 fixed at
// initial[0]. Gauss-Newton from `initial` until the largest update is below 1e-12 or after
// `iterations`; each linear system by conjugate gradients preconditioned with the exact
// block-tridiagonal solve of the odometry chain's part, to a relative residual of 1e-14.
std::vector<PoseRef> pose_graph_gauss_newton(const std::vector<PoseEdgeRef>& edges,
                                             const std::vector<PoseRef>& initial, double var_xy,
                                             double var_heading, int iterations = 20);

}  // namespace seqslam::reference
