// Message texts on a board whose RAM holds code, data and stack together.
//
// The *_text() functions of the core and storage (config_issue_text, log_problem_text, ...)
// name what went wrong in a sentence. On the head board those sentences would take about 5 KB
// of its 65 456 bytes (docs/size.md), so builds with SEQSLAM_MESSAGE_TEXTS = 0 (the target
// family; CMake sets it) return a short code instead: a family and the enumerator's value,
// e.g. "PL10" for LibraryProblem 10. On the PC `seqslam explain PL10` prints the sentence,
// and docs/messages.md lists them all (seqslam explain --all).
//
// Families: CI ConfigIssue, RI RouteIssue, HI HeuristicIssue, GI GridIssue, EI ExplorerIssue
// (core); LP LogProblem, DP DreamProblem, PL LibraryProblem, VP VolumeProblem, MP MapProblem, RC
// RunIssue (storage); SE SessionIssue, FW FirmwareIssue (session).
#pragma once

#include <stdint.h>

#ifndef SEQSLAM_MESSAGE_TEXTS
#define SEQSLAM_MESSAGE_TEXTS 1
#endif

namespace seqslam {

// "<family><value>" in a static buffer, valid until the next call (the board prints it at
// once; it has one thread). `family` is two letters.
const char* message_code(const char* family, uint32_t value);

}  // namespace seqslam
