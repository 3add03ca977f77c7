// `seqslam slam`'s wheel calibration: the core's calibrate_wheels() on the run's final graph,
// reported against the true constants when given (docs/mapping.md, "Odometry that calibrates
// itself").
#pragma once

#include <optional>
#include <string>

#include "seqslam/pose_graph.h"
#include "seqslam/wheel_calibration.h"
#include "seqslam_tools/slam_figures.h"

namespace seqslam::cli {

struct WheelCalibrationReport {
  Status status = Status::kOk;
  WheelCalibrationResult result;
  OdometryConfig ran;        // the constants the odometry ran with
  OdometryConfig corrected;  // ran with the correction applied
  std::optional<OdometryConfig> truth;
};

// Calibrates from `graph`, whose odometry ran with `ran`.
WheelCalibrationReport calibrate_run(const PoseGraph& graph, const OdometryConfig& ran,
                                     const std::optional<OdometryConfig>& truth);
void print_calibration(const WheelCalibrationReport& r);
// "accepted", or "refused: why" (as print_calibration says it).
const char* calibration_verdict(Status s);
tools::SlamCalibrationFigures calibration_figures(const WheelCalibrationReport& r);

}  // namespace seqslam::cli
