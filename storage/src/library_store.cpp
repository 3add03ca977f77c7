#include "seqslam/storage/library_store.h"

#include "codec.h"
#include "seqslam/difference.h"
#include "seqslam/messages.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint16_t kImagesVersion = 1;
constexpr uint8_t kPlaceRecord = 1;
constexpr uint32_t kImagesCrcOffset = hal::kBlockSize - 4;

Status fail(LibraryProblem* out, LibraryProblem p, Status s) {
  if (out != nullptr) *out = p;
  return s;
}

uint32_t encode_config(const LibraryConfig& c, uint8_t* out, uint32_t capacity) {
  ByteWriter w(out, capacity);
  w.u16(c.image_size.width);
  w.u16(c.image_size.height);
  codec::put_preprocess(w, c.preprocess);
  codec::put_mapping(w, c.mapping);
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

bool decode_config(const uint8_t* data, uint32_t size, LibraryConfig* c) {
  ByteReader r(data, size);
  c->image_size.width = r.u16();
  c->image_size.height = r.u16();
  c->preprocess = codec::get_preprocess(r);
  c->mapping = codec::get_mapping(r);
  return r.ok();
}

bool uses_patch_normalisation(Preprocessing p) {
  return p == Preprocessing::kPatchNorm || p == Preprocessing::kHistEqPatchNorm ||
         p == Preprocessing::kInvGammaPatchNorm;
}

// Which part of the configuration differs, if any.
LibraryProblem compare(const LibraryConfig& stored, const LibraryConfig& expected) {
  if (stored.image_size != expected.image_size) return LibraryProblem::kImageSize;
  const PreprocessConfig& a = stored.preprocess;
  const PreprocessConfig& b = expected.preprocess;
  if (a.method != b.method) return LibraryProblem::kPreprocessing;
  if (uses_patch_normalisation(a.method) &&
      (a.patch.patch_width != b.patch.patch_width || a.patch.patch_height != b.patch.patch_height ||
       a.patch.epsilon != b.patch.epsilon || a.patch.gain != b.patch.gain)) {
    return LibraryProblem::kPreprocessing;
  }
  if (stored.mapping != expected.mapping) return LibraryProblem::kMapping;
  return LibraryProblem::kNone;
}

}  // namespace

const char* library_problem_text(LibraryProblem p) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("PL", static_cast<uint32_t>(p));
#endif
  switch (p) {
    case LibraryProblem::kNone:
      return "ok";
    case LibraryProblem::kLog:
      return "the library's metadata file failed (see the log problem)";
    case LibraryProblem::kImagesDevice:
      return "the library's images file failed to read or write";
    case LibraryProblem::kImagesHeader:
      return "the images file has no valid header (not a library images file, or damaged)";
    case LibraryProblem::kNotPaired:
      return "the images file belongs to another library (session mismatch)";
    case LibraryProblem::kImageSize:
      return "the library was built for another image size than the firmware's";
    case LibraryProblem::kPreprocessing:
      return "the library was built with other preprocessing (method or patch parameters)";
    case LibraryProblem::kMapping:
      return "the library was built with another pixel-pipeline mapping";
    case LibraryProblem::kBadRecord:
      return "a metadata record of the wrong type or size";
    case LibraryProblem::kOutOfOrder:
      return "place records out of order (indices not consecutive)";
    case LibraryProblem::kImageChecksum:
      return "a place's image is damaged on the card (CRC mismatch)";
    case LibraryProblem::kPixelSum:
      return "a place's stored pixel sum does not match its image";
    case LibraryProblem::kTooManyPlaces:
      return "the library holds more places than this firmware's place capacity";
    case LibraryProblem::kImagesFull:
      return "the images file is full";
  }
  return "unknown library problem";
}

const char* library_problem_reason(LibraryProblem p, LogProblem log) {
  return p == LibraryProblem::kLog ? log_problem_text(log) : library_problem_text(p);
}

Status StoredPlaceImages::setup(hal::BlockDevice& images, ImageSize size, Span<uint8_t> cache) {
  const uint32_t a = size.pixels();
  if (a == 0 || cache.data() == nullptr || cache.size() < a + hal::kBlockSize) {
    return Status::kInvalidArgument;
  }
  const uint64_t room = images.capacity_bytes();
  if (room <= hal::kBlockSize) return Status::kResourceExhausted;
  const uint64_t capacity = (room - hal::kBlockSize) / a;
  images_ = &images;
  cache_ = cache;
  pixels_ = a;
  capacity_ = capacity > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(capacity);
  cache_first_block_ = 0xFFFFFFFFu;
  cache_blocks_ = 0;
  stored_ = 0;
  recovered_tail_ = false;
  blocks_read_ = 0;
  return capacity_ == 0 ? Status::kResourceExhausted : Status::kOk;
}

Status StoredPlaceImages::create(hal::BlockDevice& metadata, hal::BlockDevice& images,
                                 const LibraryConfig& config, Span<uint8_t> cache,
                                 LibraryProblem* problem) {
  writable_ = false;
  Status s = setup(images, config.image_size, cache);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kImagesDevice, s);
  uint8_t payload[64];
  const uint32_t size = encode_config(config, payload, sizeof payload);
  s = meta_.create(metadata, kLibraryKind, payload, size, &log_problem_);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kLog, s);
  // The images header names the metadata session that owns it.
  uint8_t block[hal::kBlockSize] = {};
  ByteWriter w(block, sizeof block);
  w.bytes(kLibraryImagesMagic, sizeof kLibraryImagesMagic);
  w.u16(kImagesVersion);
  w.u16(0);
  w.u32(meta_.session());
  w.u16(config.image_size.width);
  w.u16(config.image_size.height);
  ByteWriter c(block + kImagesCrcOffset, 4);
  c.u32(crc32(block, kImagesCrcOffset));
  s = images.write(0, 1, block);
  if (s == Status::kOk) s = images.sync();
  if (s != Status::kOk) return fail(problem, LibraryProblem::kImagesDevice, s);
  tail_block_ = 0xFFFFFFFFu;
  writable_ = true;
  return fail(problem, LibraryProblem::kNone, Status::kOk);
}

Status StoredPlaceImages::write_image_bytes(uint64_t offset, const uint8_t* data, uint32_t size) {
  // Sequential appends through a RAM copy of the partly filled last block, as in the record
  // log: a block is rewritten with the same leading bytes plus new ones.
  while (size > 0) {
    const uint32_t block = static_cast<uint32_t>(offset / hal::kBlockSize);
    const uint32_t at = static_cast<uint32_t>(offset % hal::kBlockSize);
    if (block != tail_block_) {
      for (uint8_t& b : tail_)
        b = 0;
      tail_block_ = block;
    }
    const uint32_t n = hal::kBlockSize - at < size ? hal::kBlockSize - at : size;
    for (uint32_t i = 0; i < n; ++i)
      tail_[at + i] = data[i];
    data += n;
    size -= n;
    offset += n;
    if (at + n == hal::kBlockSize || size == 0) {
      SEQSLAM_TRY(images_->write(block, 1, tail_));
    }
  }
  return images_->sync();
}

Status StoredPlaceImages::do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info,
                                    uint32_t pixel_sum) {
  if (!writable_ || index != stored_) return Status::kFailedPrecondition;
  cache_first_block_ = 0xFFFFFFFFu;  // the cache may hold the old last block
  const uint64_t offset = hal::kBlockSize + static_cast<uint64_t>(index) * pixels_;
  Status s = write_image_bytes(offset, pixels, pixels_);
  if (s != Status::kOk) return s;
  uint8_t record[kPlaceRecordBytes];
  ByteWriter w(record, sizeof record);
  w.u32(index);
  w.u32(info.capture);
  codec::put_pose(w, info.pose());
  w.u32(pixel_sum);
  w.u32(crc32(pixels, pixels_));
  const ByteSpan part{record, sizeof record};
  s = meta_.append(kPlaceRecord, &part, 1, &log_problem_);
  if (s != Status::kOk) return s;
  ++stored_;
  return Status::kOk;
}

Status StoredPlaceImages::do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                                  uint32_t* available) {
  const uint64_t start = hal::kBlockSize + static_cast<uint64_t>(first) * pixels_;
  const uint32_t first_block = static_cast<uint32_t>(start / hal::kBlockSize);
  const uint32_t skew = static_cast<uint32_t>(start % hal::kBlockSize);
  const uint32_t cache_blocks = static_cast<uint32_t>(cache_.size()) / hal::kBlockSize;
  // As many whole images as fit in the cache after the skew, at most `count`.
  uint32_t fit = (cache_blocks * hal::kBlockSize - skew) / pixels_;
  if (fit > count) fit = count;
  const uint64_t end = start + static_cast<uint64_t>(fit) * pixels_;
  const uint32_t blocks =
      static_cast<uint32_t>((end + hal::kBlockSize - 1) / hal::kBlockSize) - first_block;
  if (first_block != cache_first_block_ || blocks > cache_blocks_) {
    const Status s = images_->read(first_block, blocks, cache_.data());
    if (s != Status::kOk) {
      cache_first_block_ = 0xFFFFFFFFu;
      return s;
    }
    cache_first_block_ = first_block;
    cache_blocks_ = blocks;
    blocks_read_ += blocks;
  }
  *pixels = cache_.data() + skew;
  *available = fit;
  return Status::kOk;
}

Status StoredPlaceImages::load(hal::BlockDevice& metadata, hal::BlockDevice& images,
                               const LibraryConfig& expected, Span<uint8_t> cache,
                               const PlaceLibraryBuffers& buffers, PlaceLibrary& library,
                               LibraryProblem* problem) {
  writable_ = false;
  Status s = setup(images, expected.image_size, cache);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kImagesDevice, s);
  // Metadata header: the configuration the library was built with.
  LogReader log;
  uint8_t payload[kLogHeaderPayloadMax];
  uint32_t payload_size = 0;
  uint8_t record[kRecordOverhead + kPlaceRecordBytes];
  s = log.open(metadata, kLibraryKind, payload, sizeof payload, &payload_size,
               Span<uint8_t>(record, sizeof record), &log_problem_);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kLog, s);
  LibraryConfig stored;
  if (!decode_config(payload, payload_size, &stored)) {
    return fail(problem, LibraryProblem::kBadRecord, Status::kDataLoss);
  }
  const LibraryProblem mismatch = compare(stored, expected);
  if (mismatch != LibraryProblem::kNone) {
    return fail(problem, mismatch, Status::kFailedPrecondition);
  }
  // Images header: magic, checksum, the same session and image size.
  uint8_t block[hal::kBlockSize] = {};
  s = images.read(0, 1, block);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kImagesDevice, s);
  ByteReader h(block, kImagesCrcOffset);
  const uint8_t* magic = h.bytes(sizeof kLibraryImagesMagic);
  bool magic_ok = true;
  for (uint32_t i = 0; i < sizeof kLibraryImagesMagic; ++i) {
    magic_ok = magic_ok && magic[i] == kLibraryImagesMagic[i];
  }
  const uint16_t version = h.u16();
  h.skip(2);
  const uint32_t session = h.u32();
  const ImageSize size{h.u16(), h.u16()};
  ByteReader c(block + kImagesCrcOffset, 4);
  if (!magic_ok || version != kImagesVersion || c.u32() != crc32(block, kImagesCrcOffset)) {
    return fail(problem, LibraryProblem::kImagesHeader, Status::kDataLoss);
  }
  if (session != log.session()) return fail(problem, LibraryProblem::kNotPaired, Status::kDataLoss);
  if (size != expected.image_size) {
    return fail(problem, LibraryProblem::kImageSize, Status::kFailedPrecondition);
  }
  s = library.configure(expected.image_size, *this, buffers);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kTooManyPlaces, s);

  // Places: consecutive indices, every image checked against its CRC and pixel sum.
  for (;;) {
    RecordView v;
    s = log.next(&v);
    if (s == Status::kOutOfRange) break;
    if (s != Status::kOk) {
      log_problem_ = log.end_problem();
      return fail(problem, LibraryProblem::kLog,
                  s == Status::kResourceExhausted ? Status::kDataLoss : s);
    }
    if (v.type != kPlaceRecord || v.payload_size != kPlaceRecordBytes) {
      return fail(problem, LibraryProblem::kBadRecord, Status::kDataLoss);
    }
    ByteReader r(v.payload, v.payload_size);
    const uint32_t index = r.u32();
    const uint32_t capture = r.u32();
    const PlaceInfo info = PlaceInfo::from(codec::get_pose(r), capture);
    const uint32_t sum = r.u32();
    const uint32_t crc = r.u32();
    if (index != stored_) return fail(problem, LibraryProblem::kOutOfOrder, Status::kDataLoss);
    if (index >= capacity_) return fail(problem, LibraryProblem::kImagesFull, Status::kDataLoss);
    const uint8_t* pixels = nullptr;
    uint32_t available = 0;
    s = view(index, 1, &pixels, &available);
    if (s != Status::kOk) return fail(problem, LibraryProblem::kImagesDevice, s);
    if (crc32(pixels, pixels_) != crc) {
      return fail(problem, LibraryProblem::kImageChecksum, Status::kDataLoss);
    }
    if (seqslam::pixel_sum(pixels, pixels_) != sum) {
      return fail(problem, LibraryProblem::kPixelSum, Status::kDataLoss);
    }
    s = library.adopt(info, sum);
    if (s != Status::kOk) return fail(problem, LibraryProblem::kTooManyPlaces, s);
    ++stored_;
  }
  log_problem_ = log.end_problem();
  recovered_tail_ = log_problem_ == LogProblem::kEndDamagedTail;
  return fail(problem, LibraryProblem::kNone, Status::kOk);
}

}  // namespace seqslam::storage
