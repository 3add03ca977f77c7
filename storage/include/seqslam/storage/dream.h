// Dream sequences: recordings of a robot run for later replay and analysis (the 2015 thesis's
// name). A dream file is a record log (record_log.h) of kind "SQDREAM1", format version 1:
//
//   header   - variant (full / reduced), camera and pixel-pipeline configuration, wheel
//              constants, trigger spacing, sensor layout (docs/dream_format.md has the bytes);
//   records  - full variant: a snapshot record for every 10 ms SpinalCord snapshot, and a
//              place record whenever an image was captured (right after the snapshot it was
//              captured at: index, timestamp, encoder counts, odometry pose, infrared
//              readings, head orientation, image size and 8-bit grey pixels, optionally the
//              YUV 4:2:2 colour frame);
//              reduced variant: place records with the grey image and head orientation only
//              (public image datasets converted to dream files have nothing else);
//              both variants, optional: a truth record right after a place with the true
//              pose of the robot base there (simulator or motion capture), for evaluation
//              only - it is not sensor data and the replay skips it.
//
// Every record is checksummed; the log's power-loss and stale-data guarantees apply. The
// reader checks order (snapshot bus sequence increasing modulo 2^32, as the bus's counter
// wraps; place indices consecutive, a place follows the snapshot it names, a truth names the
// place before it, at most one per place) and sizes, and says what is wrong with a
// DreamProblem.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/odometry.h"
#include "seqslam/span.h"
#include "seqslam/storage/record_log.h"

namespace seqslam::storage {

inline constexpr LogKind kDreamKind{{'S', 'Q', 'D', 'R', 'E', 'A', 'M', '1'}, 1};

enum class DreamVariant : uint8_t { kFull = 1, kReduced = 2 };
enum class ColourFormat : uint8_t { kNone = 0, kYuv422 = 1 };
enum class DreamRecord : uint8_t { kSnapshot = 1, kPlace = 2, kReducedPlace = 3, kTruth = 4 };

struct InfraredMount {
  int16_t x_mm = 0;  // position on the base, robot frame (x forward, y left)
  int16_t y_mm = 0;
  uint16_t angle = 0;   // pointing direction, 1/65536 turn, counter-clockwise from x
  uint16_t min_mm = 0;  // valid measuring range
  uint16_t max_mm = 0;
};

// The mount as the occupancy grid's sensor model takes it: position in metres, direction as
// a binary angle, the range as stored; a reading of 0 (no echo) is free space up to 100 mm
// short of max_mm (the noise near the range end), or ignored when max_mm <= 100.
RangeSensor range_sensor_of(const InfraredMount& mount);

struct DreamHeader {
  DreamVariant variant = DreamVariant::kFull;
  ColourFormat colour = ColourFormat::kNone;
  uint16_t camera_width = hal::kCameraWidth;
  uint16_t camera_height = hal::kCameraHeight;
  UQ8_8 camera_gamma = UQ8_8::from_ratio(45, 100);
  hal::PipelineMapping mapping{};  // the image size is mapping.xmax x mapping.ymax
  OdometryConfig wheels{};
  Q31_32 spacing = Q31_32::from_ratio(1, 5);  // trigger spacing used while recording
  uint32_t snapshot_period_us = hal::kSnapshotPeriodUs;
  uint8_t infrared_count = 0;
  InfraredMount infrared[hal::kMaxInfrared] = {};
  bool has_head = true;

  ImageSize image_size() const { return mapping.size(); }
};

struct DreamPlace {
  uint32_t index = 0;         // 0, 1, 2, ... in capture order
  uint32_t bus_sequence = 0;  // SpinalCord sequence of the snapshot it was captured at
  uint32_t timestamp_us = 0;
  uint32_t encoder_left = 0;
  uint32_t encoder_right = 0;
  Pose2 pose{};
  int16_t head_pan = 0;
  int16_t head_tilt = 0;
  uint8_t infrared_count = 0;
  uint16_t infrared_mm[hal::kMaxInfrared] = {};
  ImageSize size{};
  const uint8_t* gray = nullptr;  // size.pixels() bytes
  const uint8_t* yuv = nullptr;   // 2 * size.pixels() bytes when the header says kYuv422
};

// Ground truth: the true pose of the robot base at a place (what a motion-capture system or a
// simulator gives), not what the robot measured. Recorded right after the place it names.
struct DreamTruth {
  uint32_t place_index = 0;
  Pose2 pose{};  // x, y in metres, heading; the same frame conventions as DreamPlace::pose
};

// Largest record a dream file can hold in this build; a reader buffer of this size reads all.
inline constexpr uint32_t kDreamRecordMax =
    kRecordOverhead + 52 + 2 * hal::kMaxInfrared + 3 * kMaxPixels;

// What is wrong with a dream file or a write (dream_problem_text gives the sentence).
enum class DreamProblem : uint8_t {
  kNone = 0,
  kLog,            // see log_problem(): device error, not a dream file, version, damage
  kBadHeader,      // header fields out of range (variant, mapping, wheels, sensors)
  kImageTooLarge,  // the images are larger than this build's kMaxPixels
  kUnknownRecord,  // a record type this version does not define
  kWrongVariant,   // a record type that the header's variant does not allow
  kBadRecordSize,  // a record whose size does not match its contents
  kOutOfOrder,     // snapshots not increasing, place indices not consecutive, a place that
                   // does not follow the snapshot it names, or a truth that does not name
                   // the place just before it (or is the second for that place)
  kBadImage,       // a place whose image size differs from the header's
};
const char* dream_problem_text(DreamProblem p);
// The sentence to print for `p`: dream_problem_text(p), or for kLog the log's own problem
// (`log`, e.g. the reader's or writer's log_problem()), so a message never ends in "see the
// log problem" with none after it.
const char* dream_problem_reason(DreamProblem p, LogProblem log);

class DreamWriter {
 public:
  // Starts a recording on `device` (a volume file). Statuses of LogWriter::create, and
  // kInvalidArgument (kBadHeader / kImageTooLarge) for an invalid header.
  Status create(hal::BlockDevice& device, const DreamHeader& header,
                DreamProblem* problem = nullptr);
  // Full variant only (kFailedPrecondition otherwise). Appends one snapshot.
  Status snapshot(const hal::SensorSnapshot& s, DreamProblem* problem = nullptr);
  // Appends a place; its index must be the next one and its image of the header's size
  // (kInvalidArgument, kOutOfOrder / kBadImage). The reduced variant stores only index,
  // timestamp, head orientation and the grey image.
  Status place(const DreamPlace& p, DreamProblem* problem = nullptr);
  // Either variant. Appends the true pose of the place written last: t.place_index must be
  // places() - 1, at most one per place (kInvalidArgument, kOutOfOrder otherwise). Device
  // errors as for place().
  Status truth(const DreamTruth& t, DreamProblem* problem = nullptr);

  const LogWriter& log() const { return log_; }
  LogProblem log_problem() const { return log_problem_; }
  uint32_t places() const { return places_; }

 private:
  Status append(DreamRecord type, const ByteSpan* parts, uint32_t count, DreamProblem* problem);

  LogWriter log_{};
  DreamHeader header_{};
  LogProblem log_problem_ = LogProblem::kNone;
  uint32_t places_ = 0;
  bool truth_written_ = false;  // for the place written last
  bool open_ = false;
};

struct DreamItem {
  DreamRecord type = DreamRecord::kSnapshot;
  hal::SensorSnapshot snapshot{};  // for kSnapshot
  DreamPlace place{};              // for kPlace and kReducedPlace (pixels in the reader's buffer)
  DreamTruth truth{};              // for kTruth
};

class DreamReader {
 public:
  // Opens the recording on `device`; `buffer` receives each record (kDreamRecordMax bytes
  // read everything this build can use). Statuses of LogReader::open (kLog), and kDataLoss
  // (kBadHeader) / kOutOfRange (kImageTooLarge) for a header this build cannot use.
  Status open(hal::BlockDevice& device, Span<uint8_t> buffer, DreamProblem* problem = nullptr);

  // The next snapshot, place or truth. kOk; kOutOfRange at the end (log_problem() says whether the
  // end is clean or a record cut by a power loss); kDataLoss for a damaged record (the next
  // call continues) or invalid contents (problem() says which; the item is skipped);
  // kResourceExhausted for a record beyond the buffer; device errors.
  Status next(DreamItem* out);

  const DreamHeader& header() const { return header_; }
  DreamProblem problem() const { return problem_; }
  // Why open() failed at the log level, or, after open(), how the log ended (see LogReader).
  LogProblem log_problem() const { return opened_ ? log_.end_problem() : open_problem_; }
  // Records the log reports lost (damaged stretches, a cut file; record_log.h).
  uint32_t lost_records() const { return opened_ ? log_.lost_records() : 0; }
  uint64_t problem_offset() const { return log_.problem_offset(); }
  uint32_t places() const { return places_; }
  uint32_t snapshots() const { return snapshots_; }
  // Truth records read (places with a ground-truth pose).
  uint32_t truths() const { return truths_; }
  // Snapshots the bus dropped while recording (gaps in the bus sequence).
  uint32_t missed_snapshots() const { return missed_; }

 private:
  Status decode(const RecordView& v, DreamItem* out);

  LogReader log_{};
  DreamHeader header_{};
  LogProblem open_problem_ = LogProblem::kNone;
  bool opened_ = false;
  DreamProblem problem_ = DreamProblem::kNone;
  uint32_t places_ = 0;
  uint32_t snapshots_ = 0;
  uint32_t missed_ = 0;
  uint32_t truths_ = 0;
  uint32_t truth_place_ = 0;  // the place the last truth named, if have_truth_
  bool have_truth_ = false;
  uint32_t last_bus_sequence_ = 0;
  bool have_snapshot_ = false;
  // Set after the log reported a damaged record: the next place may follow a lost place or
  // the lost snapshot it was captured at, so those two checks are waived for it; a truth
  // read before that place may name a lost place.
  bool after_damage_ = false;
};

// Encodes / decodes the header payload (exposed for tools and tests).
uint32_t encode_dream_header(const DreamHeader& h, uint8_t* out, uint32_t capacity);
Status decode_dream_header(const uint8_t* data, uint32_t size, DreamHeader* out,
                           DreamProblem* problem);

}  // namespace seqslam::storage
