// The session's optional features, chosen per build with SEQSLAM_APP_* and SEQSLAM_SESSION_*
// definitions of the seqslam_session target: what a configuration may ask for, and what code
// and state the image carries. One place for the defaults, read by the session (session.h)
// and the capacity profile (profile.h).
#pragma once

// Whether this build can run the heuristic sequence matcher (run configuration `matcher`).
// Without it (0) a configuration that asks for it is refused at start, and none of the
// heuristic matcher's code or state is in the image (docs/firmware.md).
#ifndef SEQSLAM_APP_HEURISTIC
#define SEQSLAM_APP_HEURISTIC 1
#endif
// Whether this build can explore (run configuration mode `explore`: pose graph, loop closure,
// occupancy grid). Without it (0) an explore configuration is refused at start and none of
// the mapping code or state is in the image.
#ifndef SEQSLAM_APP_MAPPING
#define SEQSLAM_APP_MAPPING 1
#endif
// The full search outside explore and the slope matcher: the PC's (its tools evaluate both).
#ifndef SEQSLAM_SESSION_FULL_SEARCH
#define SEQSLAM_SESSION_FULL_SEARCH SEQSLAM_APP_MAPPING
#endif
#ifndef SEQSLAM_SESSION_SLOPE
#define SEQSLAM_SESSION_SLOPE 0
#endif
#if SEQSLAM_APP_MAPPING && !SEQSLAM_SESSION_FULL_SEARCH
#error "explore runs the full search: SEQSLAM_SESSION_FULL_SEARCH is needed with mapping"
#endif
