// A dream recording played back as the robot's sensor bus and camera.
//
// On the emulated board and on the PC there is no SpinalCord and no camera: the firmware runs
// unchanged against this replay instead. It implements both HAL interfaces from one dream
// file, in recording order, and never makes data up:
//   - full recordings: next() returns the recorded snapshots; capture() latches the place
//     recorded right after the current snapshot, or reports kUnavailable if none was
//     recorded at that moment (a firmware whose trigger fires elsewhere than the recording's
//     gets no frame - the cause is reported, not hidden). Places the firmware did not
//     capture are skipped and counted.
//   - reduced recordings (no odometry): each recorded place comes as a snapshot carrying
//     only its timestamp, sequence (the place index) and head orientation, and capture()
//     latches that place's image.
// Truth records (ground-truth poses) are not sensor data: they are skipped, not counted.
// configure() accepts only the mapping the recording was made with.
#pragma once

#include <stdint.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/span.h"
#include "seqslam/storage/dream.h"

namespace seqslam::storage {

class DreamReplay final : public hal::SpinalCord, public hal::PixelBuffer {
 public:
  // Opens the recording; `buffer` (kDreamRecordMax bytes) holds the current record.
  // Statuses of DreamReader::open.
  Status open(hal::BlockDevice& device, Span<uint8_t> buffer, DreamProblem* problem = nullptr);

  const DreamHeader& header() const { return reader_.header(); }
  const DreamReader& reader() const { return reader_; }
  // Recorded places the firmware did not capture.
  uint32_t skipped_places() const { return skipped_places_; }
  // Records the reader reported as damaged or invalid (skipped).
  uint32_t bad_records() const { return bad_records_; }

 private:
  Status do_next(hal::SensorSnapshot* out) override;
  Status do_configure(const hal::PipelineMapping& mapping) override;
  Status do_capture() override;
  Status do_read(hal::Frame* out) override;

  // The next item of the recording, skipping (and counting) damaged records.
  Status read_item(DreamItem* out);

  DreamReader reader_{};
  DreamItem item_{};      // the last item read
  bool pending_ = false;  // item_ was read ahead and not yet delivered
  bool ended_ = false;
  bool configured_ = false;
  bool latched_ = false;
  hal::SensorSnapshot current_{};
  hal::Frame frame_{};
  uint32_t skipped_places_ = 0;
  uint32_t bad_records_ = 0;
};

}  // namespace seqslam::storage
