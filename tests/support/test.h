// The one include for test sources: GoogleTest on the host (SEQSLAM_TEST_GTEST, defined by
// seqslam_add_unit_test), minitest on the bare-metal target. Write tests against the common
// subset documented in minitest.h.
#pragma once

#if defined(SEQSLAM_TEST_GTEST)
#include <gtest/gtest.h>
#else
#include "minitest.h"
#endif
