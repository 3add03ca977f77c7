// libFuzzer target: the host image loader (tools::decode_gray: PNG through libpng with its
// checksums verified, JPEG and BMP through stb_image, PGM/PPM by the project's reader), with
// property oracles rather than "no crash" alone.
//
// File inputs (first byte other than 'G'): the bytes as an image file, and for a PNG the same
// bytes again with every chunk CRC recomputed, so that mutations get past the CRC check into
// the decoder. Properties:
//   1. failure: the message starts with the file name;
//      success: a valid image (width * height pixels) of the header's size (PNG: IHDR; JPEG and
//      BMP: the header as stb_image reads it);
//   2. a PNG that stb_image also decodes has stb_image's pixels (the loader before libpng,
//      with the same grey conversion): the switch to libpng changed no pixel of any file both
//      accept;
//   3. the image re-encoded with the project's PNG writer (save_png's stb_image_write call, in
//      memory) loads again as the same image;
//   4. a PNG that loads has image data that zlib itself accepts: the IDAT chunks' data,
//      concatenated, inflates to its end with a matching Adler-32, and with one IDAT chunk
//      nothing follows the end of the stream (libpng reads the IDAT chunks as one stream, and
//      data after its end inside the chunk is an error).
// Generator inputs ('G' + parameters): a valid PNG that libpng writes from the parameters (any
// colour type and bit depth, palette, tRNS, interlacing, up to 24x24, samples from the input):
//   5. it loads, with the grey levels computed from its samples alone, and as stb_image loads
//      it; then 1-4;
//   6. changed by a burst of 1-4 bytes (position and XOR values from the input) lying inside
//      one chunk's type and data, or inside one chunk's CRC, it does not load: CRC-32 detects
//      every burst of up to 32 bits, and the loader reads every chunk up to IEND, so a success
//      means a checksum went unchecked. A change touching a length field or the signature may
//      in principle make another valid file; for those only 1-4 are required. Or (a flag of
//      the input) the burst is put inside the IDAT data and the chunk's CRC recomputed, so
//      only the zlib stream's own checks remain: property 4 then says it must not load when
//      zlib refuses the stream (bad Adler-32, invalid deflate data, bytes after the end).
#include <stb_image.h>
#include <stb_image_write.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "png_samples.h"
#include "seqslam_tools/image_io.h"

namespace {

using seqslam::tools::decode_gray;
using seqslam::tools::GrayImage;
using seqslam::tools::LoadedImage;
namespace tp = seqslam::test_png;

constexpr char kName[] = "input.img";

[[noreturn]] void violated(const char* property, const std::string& detail) {
  fprintf(stderr, "fuzz_image_loader: property violated: %s: %s\n", property, detail.c_str());
  abort();
}

bool is_png(const std::vector<uint8_t>& bytes) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return bytes.size() >= 8 && memcmp(bytes.data(), kSignature, 8) == 0;
}

std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// The size the file's header declares, when the loader's format detection agrees it is PNG,
// JPEG or BMP.
bool header_size(const std::vector<uint8_t>& bytes, int* width, int* height) {
  if (is_png(bytes)) {
    if (bytes.size() < 24) return false;
    *width = static_cast<int>(tp::be32(bytes.data() + 16));
    *height = static_cast<int>(tp::be32(bytes.data() + 20));
    return true;
  }
  const bool jpeg = bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff;
  const bool bmp = bytes.size() >= 2 && bytes[0] == 'B' && bytes[1] == 'M';
  if (!jpeg && !bmp) return false;
  int channels = 0;
  return stbi_info_from_memory(bytes.data(), static_cast<int>(bytes.size()), width, height,
                               &channels) != 0;
}

void append(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

enum class Zlib { kRefused, kTrailing, kComplete };

// What zlib makes of the concatenated IDAT data: refused (invalid deflate data, a bad Adler-32
// or no end), complete, or complete with bytes after the end of the stream.
Zlib zlib_verdict(const std::vector<uint8_t>& png, size_t* idat_chunks) {
  std::vector<uint8_t> z;
  *idat_chunks = 0;
  for (const tp::Chunk& c : tp::chunks(png)) {
    if (c.type != "IDAT") continue;
    ++*idat_chunks;
    z.insert(z.end(), png.begin() + static_cast<ptrdiff_t>(c.data()),
             png.begin() + static_cast<ptrdiff_t>(c.crc()));
  }
  z_stream s{};
  if (inflateInit(&s) != Z_OK) abort();
  s.next_in = z.data();
  s.avail_in = static_cast<uInt>(z.size());
  uint8_t buffer[16384];
  int ret = Z_OK;
  while (ret == Z_OK) {
    s.next_out = buffer;
    s.avail_out = sizeof buffer;
    ret = inflate(&s, Z_NO_FLUSH);
  }
  const Zlib verdict = ret != Z_STREAM_END ? Zlib::kRefused
                       : s.avail_in > 0    ? Zlib::kTrailing
                                           : Zlib::kComplete;
  inflateEnd(&s);
  return verdict;
}

// Properties 1-4 for one file; true when it loaded.
bool check_file(const std::vector<uint8_t>& bytes) {
  const LoadedImage loaded = decode_gray(bytes, kName);
  if (!loaded.ok()) {
    if (loaded.error().rfind(std::string(kName) + ": ", 0) != 0) {
      violated("an error names the file", loaded.error());
    }
    return false;
  }
  const GrayImage& image = loaded.value();
  if (!image.valid()) violated("a loaded image is valid", size_text(image.width, image.height));
  int width = 0;
  int height = 0;
  if (header_size(bytes, &width, &height) && (width != image.width || height != image.height)) {
    violated("the decoded size is the header's",
             size_text(image.width, image.height) + " decoded, header " + size_text(width, height));
  }
  if (is_png(bytes)) {
    std::vector<uint8_t> stb;
    if (tp::stb_gray(bytes, &width, &height, &stb) &&
        (width != image.width || height != image.height || stb != image.pixels)) {
      violated("a PNG both decoders accept has stb_image's pixels",
               size_text(image.width, image.height));
    }
    size_t idat_chunks = 0;
    const Zlib zlib = zlib_verdict(bytes, &idat_chunks);
    if (zlib == Zlib::kRefused || (zlib == Zlib::kTrailing && idat_chunks == 1)) {
      violated("a PNG that loads has image data zlib accepts",
               zlib == Zlib::kRefused ? "refused" : "bytes after the end of the stream");
    }
  }
  std::vector<uint8_t> encoded;
  if (stbi_write_png_to_func(append, &encoded, image.width, image.height, 1, image.pixels.data(),
                             image.width) == 0) {
    violated("the project's writer encodes a loaded image", size_text(image.width, image.height));
  }
  const LoadedImage again = decode_gray(encoded, "again.png");
  if (!again.ok()) violated("a re-encoded image loads", again.error());
  if (again.value().width != image.width || again.value().height != image.height ||
      again.value().pixels != image.pixels) {
    violated("a re-encoded image loads as the same image", size_text(image.width, image.height));
  }
  return true;
}

struct Input {
  const uint8_t* data;
  size_t size;
  uint8_t byte() {
    if (size == 0) return 0;
    --size;
    return *data++;
  }
};

// True when [begin, end) lies inside one chunk's type and data or inside its CRC.
bool inside_checked_field(const std::vector<uint8_t>& png, size_t begin, size_t end) {
  for (const tp::Chunk& c : tp::chunks(png)) {
    if (begin >= c.offset + 4 && end <= c.crc()) return true;
    if (begin >= c.crc() && end <= c.end()) return true;
  }
  return false;
}

// Properties 5 and 6.
void check_generated(Input in) {
  static const int kTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                               PNG_COLOR_TYPE_RGB_ALPHA, PNG_COLOR_TYPE_PALETTE};
  const int type = kTypes[in.byte() % 5];
  const std::vector<int> depths = tp::depths_of(type);
  const int depth = depths[in.byte() % depths.size()];
  const uint8_t flags = in.byte();
  const uint32_t width = 1u + in.byte() % 24u;
  const uint32_t height = 1u + in.byte() % 24u;
  const uint32_t seed = in.byte() | (uint32_t{in.byte()} << 8);
  const size_t position = in.byte() | (size_t{in.byte()} << 8);
  const uint8_t burst = in.byte();
  uint8_t change[4];
  for (uint8_t& x : change)
    x = in.byte();
  tp::Spec spec =
      tp::make_spec(type, depth, (flags & 1) != 0, width, height, seed, (flags & 2) != 0);
  const uint32_t limit = type == PNG_COLOR_TYPE_PALETTE ? static_cast<uint32_t>(spec.palette.size())
                         : depth == 16                  ? 65536u
                                                        : (1u << depth);
  for (size_t i = 0; i < spec.samples.size() && in.size >= 2; ++i)
    spec.samples[i] = static_cast<uint16_t>((in.byte() | (uint32_t{in.byte()} << 8)) % limit);

  const std::vector<uint8_t> png = tp::write(spec);
  if (png.empty()) violated("libpng writes a valid spec", std::to_string(type));
  const LoadedImage loaded = decode_gray(png, kName);
  if (!loaded.ok()) violated("a valid PNG loads", loaded.error());
  if (loaded.value().pixels != tp::expected_gray(spec)) {
    violated("a valid PNG has the grey levels of its samples",
             "colour type " + std::to_string(type) + ", " + std::to_string(depth) + " bits");
  }
  if (!check_file(png)) violated("a valid PNG loads", "second decode");

  if ((burst & 0x80) != 0) return;  // no change
  // Anywhere in the file, or (0x40) inside the first IDAT chunk's data with its CRC fixed.
  const bool in_idat = (burst & 0x40) != 0;
  tp::Chunk idat;
  for (const tp::Chunk& c : tp::chunks(png)) {
    if (c.type == "IDAT") {
      idat = c;
      break;
    }
  }
  if (in_idat && idat.length == 0) violated("libpng writes an IDAT chunk", "none");
  const size_t first = in_idat ? idat.data() : 0;
  const size_t limit_end = in_idat ? idat.crc() : png.size();
  const size_t length = 1 + burst % 4u;
  const size_t begin = first + position % (limit_end - first);
  const size_t end = begin + length < limit_end ? begin + length : limit_end;
  std::vector<uint8_t> changed = png;
  bool any = false;
  for (size_t k = begin; k < end; ++k) {
    changed[k] = static_cast<uint8_t>(changed[k] ^ change[k - begin]);
    any = any || change[k - begin] != 0;
  }
  if (!any) return;
  if (in_idat) tp::fix_crc(&changed, idat);
  const bool loaded_changed = check_file(changed);  // property 4 covers the IDAT case
  if (loaded_changed && !in_idat && inside_checked_field(png, begin, end)) {
    violated("a PNG changed inside a CRC-protected field does not load",
             "bytes " + std::to_string(begin) + ".." + std::to_string(end - 1));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 0 && data[0] == 'G') {
    check_generated(Input{data + 1, size - 1});
    return 0;
  }
  std::vector<uint8_t> bytes(data, data + size);
  check_file(bytes);
  if (is_png(bytes)) {
    std::vector<uint8_t> fixed = bytes;
    tp::fix_all_crcs(&fixed);
    if (fixed != bytes) check_file(fixed);
  }
  return 0;
}
