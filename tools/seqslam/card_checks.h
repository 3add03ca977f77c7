// A run configuration against the card it is written to (issue 34): `seqslam config write`
// checks the values that depend on the card's data before it touches the card.
//
// Refused (nothing written), because the firmware would run them without a word and lose
// the run:
//   * a repeat run's start place (--start) beyond the card's library;
//   * a query history (the volume file `queries`) too small for the relocalisation scan to
//     ever start (fewer steps than the scan's sequence of query images), or, from an unknown
//     start, too small for a scan over the card's library to finish;
//   * a card the file size limit (ulimit -f) would not let it write.
// Warned about (written), because the firmware refuses them at start with its own sentence
// or runs them with a counter saying what failed: a file the run needs missing (`results`,
// `record`, `queries`), a library too long for the scan to finish before its query images
// are overwritten (from a known start: tracking still works), --record-colour with a replay
// that has no colour, --modes continue without a library or a saved state.
#pragma once

#include <optional>
#include <string>

#include "cli_common.h"
#include "seqslam/hal/pixel_buffer.h"

namespace seqslam::storage {
struct RunConfig;
}

namespace seqslam::cli {

// Prints the warnings; returns kExitOk, or the refusal's status (kExitUsage for a value out of
// the card's range, kExitFailure for the file size limit) with its message printed.
int check_config_for_card(Disk& disk, const storage::RunConfig& config);

// The mapping of the recording in the card's `replay` file (the images a replay run will
// give), or none when the card has no readable recording there.
std::optional<hal::PipelineMapping> card_replay_mapping(const std::string& image);

}  // namespace seqslam::cli
