// Reads the places of a dream recording (a standalone .dream file) for host evaluation:
// each place's grey image and, where the recording has them, its odometry pose and its
// ground-truth pose (simulated runs carry one per place).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/odometry.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

struct DreamPlaces {
  std::vector<GrayImage> images;
  std::vector<Pose2> odometry;  // one per place (zero poses in reduced recordings)
  std::vector<Pose2> truth;     // one per place when has_truth
  bool has_truth = false;       // every place has a ground-truth pose
  uint32_t snapshots = 0;
};

// The pipeline mapping a dream recording on `device` was made with (its header's), or nothing
// when the device holds no readable recording.
std::optional<hal::PipelineMapping> recorded_mapping(hal::BlockDevice& device);

// The image size a dream recording was made at (its header's, after the robot's pixel
// pipeline), or nothing when `path` is not a readable recording.
std::optional<ImageSize> recorded_image_size(const std::string& path);

// Errors name the file: unreadable, not a dream recording, damaged records or a damaged end
// (nothing partial is returned as complete).
Outcome<DreamPlaces> load_dream_places(const std::string& path);

}  // namespace seqslam::tools
