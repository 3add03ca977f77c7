// Umbrella header: the whole core API.
#pragma once

#include "seqslam/difference.h"
#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/image.h"
#include "seqslam/limits.h"
#include "seqslam/localiser.h"
#include "seqslam/normalise.h"
#include "seqslam/odometry.h"
#include "seqslam/pixel_pipeline.h"
#include "seqslam/place_library.h"
#include "seqslam/preprocess.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/status.h"
