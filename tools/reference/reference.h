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
