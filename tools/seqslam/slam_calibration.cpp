// `seqslam slam`'s wheel calibration (see slam_calibration.h).
#include "slam_calibration.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "cli_common.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::cli {

WheelCalibrationReport calibrate_run(const PoseGraph& graph, const OdometryConfig& ran,
                                     const std::optional<OdometryConfig>& truth) {
  WheelCalibrationReport r;
  r.ran = ran;
  r.truth = truth;
  WheelCalibrationConfig config;
  config.track_width = ran.track_width;
  std::vector<WheelCalibrationSlot> scratch(graph.closure_count());
  r.status = calibrate_wheels(
      graph, config, Span<WheelCalibrationSlot>(scratch.data(), scratch.size()), &r.result);
  r.corrected = apply_wheel_correction(ran, r.result.correction);
  return r;
}

namespace {

// The true factors relative to the constants the odometry ran with, and normalised to their
// mean wheel (what the closures can observe): {k_L, k_R, k_b, mean, difference, track}.
struct TrueFactors {
  double left, right, track, mean, difference, track_rel;
};

TrueFactors true_factors(const OdometryConfig& ran, const OdometryConfig& truth) {
  TrueFactors t{};
  t.left = tools::to_double(truth.circumference_left) / tools::to_double(ran.circumference_left);
  t.right = tools::to_double(truth.circumference_right) / tools::to_double(ran.circumference_right);
  t.track = tools::to_double(truth.track_width) / tools::to_double(ran.track_width);
  t.mean = (t.left + t.right) / 2;
  t.difference = (t.right - t.left) / t.mean;
  t.track_rel = t.track / t.mean - 1;
  return t;
}

}  // namespace

const char* calibration_verdict(Status s) {
  switch (s) {
    case Status::kOk:
      return "accepted";
    case Status::kFailedPrecondition:
      return "refused: too few usable closures";
    case Status::kOutOfRange:
      return "refused: the route cannot tell the two apart, or the estimate is implausible";
    default:
      return "refused: bad settings";
  }
}

void print_calibration(const WheelCalibrationReport& r) {
  const WheelCalibrationResult& c = r.result;
  std::printf(
      "wheel calibration: %s; wheel difference %+.4f %% (sigma %.4f %%), track %+.3f %% (sigma "
      "%.3f %%) from %u closures (%u skipped, %u chain breaks); closure residual %.3f -> %.3f m "
      "RMS; corrected constants %s\n",
      calibration_verdict(r.status), 100 * tools::to_double(c.correction.difference),
      100 * tools::to_double(c.sigma_difference), 100 * tools::to_double(c.correction.track),
      100 * tools::to_double(c.sigma_track), c.closures_used, c.closures_skipped, c.breaks,
      tools::to_double(c.rms_before), tools::to_double(c.rms_after),
      wheel_constants_text(r.corrected).c_str());
  if (!r.truth) return;
  const TrueFactors t = true_factors(r.ran, *r.truth);
  const double d = tools::to_double(c.correction.difference);
  const double k = tools::to_double(c.correction.track);
  std::printf(
      "  against the true constants (normalised to their mean wheel, x%.6f): difference %+.4f "
      "%% (error %.4f %%), track %+.3f %% (error %.3f %%); left %.4f %%, right %.4f %% off "
      "(absolute, with the unobservable mean)\n",
      t.mean, 100 * t.difference, 100 * std::fabs(d - t.difference), 100 * t.track_rel,
      100 * std::fabs(k - t.track_rel), 100 * std::fabs((1 - d / 2) / t.left - 1),
      100 * std::fabs((1 + d / 2) / t.right - 1));
}

tools::SlamCalibrationFigures calibration_figures(const WheelCalibrationReport& r) {
  tools::SlamCalibrationFigures f;
  const WheelCalibrationResult& c = r.result;
  f.accepted = r.status == Status::kOk;
  f.difference = tools::to_double(c.correction.difference);
  f.track = tools::to_double(c.correction.track);
  f.sigma_difference = tools::to_double(c.sigma_difference);
  f.sigma_track = tools::to_double(c.sigma_track);
  f.closures_used = c.closures_used;
  f.closures_skipped = c.closures_skipped;
  f.residual_before_m = tools::to_double(c.rms_before);
  f.residual_after_m = tools::to_double(c.rms_after);
  f.corrected_wheels = wheel_constants_text(r.corrected);
  if (r.truth) {
    const TrueFactors t = true_factors(r.ran, *r.truth);
    f.true_difference = t.difference;
    f.true_track = t.track_rel;
    f.true_mean = t.mean;
  }
  return f;
}

}  // namespace seqslam::cli
