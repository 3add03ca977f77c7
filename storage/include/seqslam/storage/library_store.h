// Place libraries on the SD card.
//
// A stored library is two volume files:
//   metadata - a record log of kind "SQLIBRY1": the header holds the configuration the images
//              depend on (image size, preprocessing, pixel-pipeline mapping); one record per
//              place holds its index, capture index, odometry pose, pixel sum and the CRC-32
//              of its image;
//   images   - block 0 a header (kind "SQLIMGS1", the metadata log's session, the image
//              size); from byte 512 the images back to back, image j at 512 + j * A, so the
//              difference kernel can stream contiguous chunks straight from the card.
//
// StoredPlaceImages implements the core's PlaceImages over these files: teaching appends the
// image, then its metadata record (so a power cut loses at most the place being added);
// localising streams the images through a bounded cache (caller-owned, a few KB), so a
// library far larger than the head board's RAM stays on the card.
//
// Loading checks everything: the configuration against the firmware's (a library made for
// another image size, preprocessing or mapping is refused, and the problem names which), the
// pairing of the two files, place order, and every image's CRC.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/place_library.h"
#include "seqslam/preprocess.h"
#include "seqslam/span.h"
#include "seqslam/storage/record_log.h"

namespace seqslam::storage {

inline constexpr LogKind kLibraryKind{{'S', 'Q', 'L', 'I', 'B', 'R', 'Y', '1'}, 1};
// A place's metadata record: index, capture, pose, pixel sum, image CRC.
inline constexpr uint32_t kPlaceRecordBytes = 36;
inline constexpr uint8_t kLibraryImagesMagic[8] = {'S', 'Q', 'L', 'I', 'M', 'G', 'S', '1'};

// What the stored images depend on: a library is only usable with the same settings.
struct LibraryConfig {
  ImageSize image_size{32, 16};
  PreprocessConfig preprocess{};
  hal::PipelineMapping mapping{};
};

enum class LibraryProblem : uint8_t {
  kNone = 0,
  kLog,            // the metadata log failed (see log_problem())
  kImagesDevice,   // the images file failed to read or write
  kImagesHeader,   // the images file has no valid header
  kNotPaired,      // the images file belongs to another library (session mismatch)
  kImageSize,      // stored for another image size than the firmware's
  kPreprocessing,  // stored with other preprocessing (method or PN parameters)
  kMapping,        // stored with another pixel-pipeline mapping
  kBadRecord,      // a metadata record of the wrong size or type
  kOutOfOrder,     // place indices not consecutive
  kImageChecksum,  // a place's image does not match its CRC (damaged on the card)
  kPixelSum,       // a place's stored pixel sum does not match its image
  kTooManyPlaces,  // more places than the library (RAM metadata) can hold
  kImagesFull,     // no room for another image in the images file
};
const char* library_problem_text(LibraryProblem p);
// The sentence to print for `p`: library_problem_text(p), or for kLog the metadata log's own
// problem (`log`: StoredPlaceImages::log_problem()).
const char* library_problem_reason(LibraryProblem p, LogProblem log);

class StoredPlaceImages final : public PlaceImages {
 public:
  // Starts an empty stored library (teaching): writes both headers. `cache` (at least one
  // image plus one block) bounds the memory used to stream images. Statuses of the log writer
  // and the device; kInvalidArgument for a cache or image size that cannot work.
  Status create(hal::BlockDevice& metadata, hal::BlockDevice& images, const LibraryConfig& config,
                Span<uint8_t> cache, LibraryProblem* problem = nullptr);

  // Opens a stored library, configures `library` on this image store with `buffers` and
  // registers the stored places in it. Checks what the header comment says.
  //   kFailedPrecondition - the configuration differs (kImageSize, kPreprocessing, kMapping);
  //   kDataLoss           - damaged or unpaired files (kImagesHeader, kNotPaired, kBadRecord,
  //                         kOutOfOrder, kImageChecksum, kPixelSum, kLog);
  //   kResourceExhausted  - more places than `library` holds (kTooManyPlaces);
  //   device errors.
  // A place cut off by a power loss while teaching (a damaged last record) is not an error:
  // the library ends before it and recovered_tail() reports it.
  Status load(hal::BlockDevice& metadata, hal::BlockDevice& images, const LibraryConfig& expected,
              Span<uint8_t> cache, const PlaceLibraryBuffers& buffers, PlaceLibrary& library,
              LibraryProblem* problem = nullptr);

  // load(), then ready to teach more places after the stored ones (a run continued from the
  // card): the metadata log is continued in its session (LogWriter::reopen) and the images
  // file after the last place; a place a power cut interrupted is overwritten. load()'s
  // statuses, then reopen()'s (kLog).
  Status load_for_teaching(hal::BlockDevice& metadata, hal::BlockDevice& images,
                           const LibraryConfig& expected, Span<uint8_t> cache,
                           const PlaceLibraryBuffers& buffers, PlaceLibrary& library,
                           LibraryProblem* problem = nullptr);

  LogProblem log_problem() const { return log_problem_; }
  bool recovered_tail() const { return recovered_tail_; }
  uint32_t stored() const { return stored_; }
  // Blocks read through the cache so far (to see the streaming cost).
  uint64_t blocks_read() const { return blocks_read_; }

 private:
  uint32_t do_capacity() const override { return capacity_; }
  Status do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info,
                   uint32_t pixel_sum) override;
  Status do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                 uint32_t* available) override;
  Status setup(hal::BlockDevice& images, ImageSize size, Span<uint8_t> cache);
  Status write_image_bytes(uint64_t offset, const uint8_t* data, uint32_t size);

  LogWriter meta_{};
  hal::BlockDevice* images_ = nullptr;
  Span<uint8_t> cache_{};
  uint32_t pixels_ = 0;
  uint32_t capacity_ = 0;
  uint32_t stored_ = 0;
  uint64_t blocks_read_ = 0;
  uint32_t cache_first_block_ = 0xFFFFFFFFu;
  uint32_t cache_blocks_ = 0;
  bool writable_ = false;
  bool recovered_tail_ = false;
  LogProblem log_problem_ = LogProblem::kNone;
  uint32_t tail_block_ = 0xFFFFFFFFu;
  uint8_t tail_[hal::kBlockSize] = {};
};

}  // namespace seqslam::storage
