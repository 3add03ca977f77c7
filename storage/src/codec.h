// Field groups shared by several on-card formats (docs/dream_format.md), written and read in
// exactly one place each: the pixel-pipeline mapping (24 bytes), the preprocessing settings
// (8), the odometry configuration (36) and a pose (20). Internal to the storage library.
#pragma once

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/odometry.h"
#include "seqslam/preprocess.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage::codec {

void put_mapping(ByteWriter& w, const hal::PipelineMapping& m);
hal::PipelineMapping get_mapping(ByteReader& r);
void put_preprocess(ByteWriter& w, const PreprocessConfig& p);
PreprocessConfig get_preprocess(ByteReader& r);
void put_odometry(ByteWriter& w, const OdometryConfig& c);
OdometryConfig get_odometry(ByteReader& r);
void put_pose(ByteWriter& w, const Pose2& p);
Pose2 get_pose(ByteReader& r);

}  // namespace seqslam::storage::codec
