#include "seqslam_tools/dream_images.h"

#include "seqslam/hal/file_block_device.h"
#include "seqslam/storage/dream.h"

namespace seqslam::tools {

std::optional<hal::PipelineMapping> recorded_mapping(hal::BlockDevice& device) {
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  if (reader.open(device, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) {
    return std::nullopt;
  }
  return reader.header().mapping;
}

std::optional<ImageSize> recorded_image_size(const std::string& path) {
  hal::FileBlockDevice device;
  if (device.open(path, false) != Status::kOk) return std::nullopt;
  const auto mapping = recorded_mapping(device);
  if (!mapping) return std::nullopt;
  return mapping->size();
}

Outcome<DreamPlaces> load_dream_places(const std::string& path) {
  hal::FileBlockDevice device;
  const Status opened = device.open(path, false);
  if (opened == Status::kInvalidArgument) {
    return Error{path +
                 ": not a whole number of 512-byte blocks: the recording was cut short "
                 "(copied incompletely?)"};
  }
  if (opened != Status::kOk) {
    // FileBlockDevice's message names the file already.
    const std::string e = device.error();
    return Error{e.rfind(path, 0) == 0 ? e : path + ": " + e};
  }
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  storage::DreamProblem problem = storage::DreamProblem::kNone;
  if (reader.open(device, Span<uint8_t>(buffer.data(), buffer.size()), &problem) != Status::kOk) {
    return Error{path + ": not a readable dream recording: " +
                 (problem == storage::DreamProblem::kLog
                      ? std::string(storage::log_problem_text(reader.log_problem()))
                      : std::string(storage::dream_problem_text(problem)))};
  }
  DreamPlaces out;
  size_t truths = 0;
  for (;;) {
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kOutOfRange) {
      if (reader.log_problem() != storage::LogProblem::kEndClean) {
        return Error{path + ": the recording ends in a damaged record (" +
                     storage::log_problem_text(reader.log_problem()) + ") after " +
                     std::to_string(out.images.size()) + " places"};
      }
      break;
    }
    if (s != Status::kOk) {
      return Error{path + ": damaged or invalid record after place " +
                   std::to_string(out.images.size()) + " (" +
                   (reader.problem() == storage::DreamProblem::kLog
                        ? std::string(storage::log_problem_text(reader.log_problem())) + ", " +
                              std::to_string(reader.lost_records()) + " records lost"
                        : std::string(storage::dream_problem_text(reader.problem()))) +
                   ", " + status_name(s) + ")"};
    }
    switch (item.type) {
      case storage::DreamRecord::kSnapshot:
        ++out.snapshots;
        break;
      case storage::DreamRecord::kPlace:
      case storage::DreamRecord::kReducedPlace: {
        GrayImage img;
        img.width = item.place.size.width;
        img.height = item.place.size.height;
        img.pixels.assign(item.place.gray, item.place.gray + item.place.size.pixels());
        out.images.push_back(std::move(img));
        out.odometry.push_back(item.place.pose);
        out.truth.push_back(Pose2{});
        break;
      }
      case storage::DreamRecord::kTruth:
        if (item.truth.place_index >= out.truth.size()) {  // the reader checks; be safe
          return Error{path + ": a ground-truth pose names a place that was not read"};
        }
        out.truth[item.truth.place_index] = item.truth.pose;
        ++truths;
        break;
    }
  }
  out.has_truth = !out.images.empty() && truths == out.images.size();
  if (!out.has_truth) out.truth.clear();
  return out;
}

}  // namespace seqslam::tools
