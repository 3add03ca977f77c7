#include "seqslam_tools/image_io.h"

#include <limits.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "file_util.h"
#include "formats.h"

namespace seqslam::tools {
namespace {

enum class Format { kUnknown, kPng, kJpeg, kBmp, kPnm };

struct Signature {
  Format format;
  const char* name;
  const char* bytes;
  size_t length;
};

// JPEG: SOI followed by the 0xFF of the first marker. PNM: 'P' and a digit (decode_pnm rejects
// the variants it does not read with a specific message).
constexpr Signature kSignatures[] = {
    {Format::kPng, "PNG", "\x89PNG\r\n\x1a\n", 8},
    {Format::kJpeg, "JPEG", "\xff\xd8\xff", 3},
    {Format::kBmp, "BMP", "BM", 2},
};

bool starts_with(const std::vector<uint8_t>& bytes, const char* prefix, size_t length) {
  if (bytes.size() < length) return false;
  for (size_t i = 0; i < length; ++i) {
    if (bytes[i] != static_cast<uint8_t>(prefix[i])) return false;
  }
  return true;
}

// True when the whole file is a proper prefix of the signature: a file cut very short.
bool is_cut_signature(const std::vector<uint8_t>& bytes, const Signature& sig) {
  if (bytes.size() >= sig.length) return false;
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (bytes[i] != static_cast<uint8_t>(sig.bytes[i])) return false;
  }
  return true;
}

struct StbFree {
  void operator()(stbi_uc* p) const { stbi_image_free(p); }
};

std::string stb_reason() {
  const char* reason = stbi_failure_reason();
  return reason != nullptr ? reason : "unknown error";
}

Outcome<GrayImage> decode_with_stb(const std::vector<uint8_t>& bytes, const char* format_name) {
  if (bytes.size() > static_cast<size_t>(INT_MAX)) {
    return Error{std::string(format_name) + " file too large to decode"};
  }
  const int length = static_cast<int>(bytes.size());
  int width = 0;
  int height = 0;
  int channels = 0;
  if (stbi_info_from_memory(bytes.data(), length, &width, &height, &channels) == 0) {
    return Error{std::string("cannot decode ") + format_name + " (stb_image: " + stb_reason() +
                 ")"};
  }
  std::string error;
  if (!detail::check_dimensions(width, height, &error)) return Error{error};

  int w = 0;
  int h = 0;
  int n = 0;
  const std::unique_ptr<stbi_uc, StbFree> decoded(
      stbi_load_from_memory(bytes.data(), length, &w, &h, &n, 0));
  if (!decoded) {
    return Error{std::string("cannot decode ") + format_name + " (stb_image: " + stb_reason() +
                 ")"};
  }
  if (w != width || h != height || n < 1 || n > 4) {
    return Error{std::string("cannot decode ") + format_name +
                 " (decoder returned an inconsistent image)"};
  }

  GrayImage image;
  image.width = w;
  image.height = h;
  const size_t count = static_cast<size_t>(w) * static_cast<size_t>(h);
  const size_t step = static_cast<size_t>(n);
  image.pixels.resize(count);
  const stbi_uc* src = decoded.get();
  for (size_t i = 0; i < count; ++i) {
    const stbi_uc* px = src + i * step;
    // 1 = grey, 2 = grey + alpha, 3 = RGB, 4 = RGBA; alpha is ignored.
    image.pixels[i] = step >= 3 ? luma(px[0], px[1], px[2]) : px[0];
  }
  return Outcome<GrayImage>(std::move(image));
}

bool check_saveable(const std::string& path, const GrayImage& image, std::string* error) {
  if (!image.valid()) {
    detail::set_error(error, path + ": cannot save an invalid image (" +
                                 std::to_string(image.width) + "x" + std::to_string(image.height) +
                                 " with " + std::to_string(image.pixels.size()) + " pixel bytes)");
    return false;
  }
  return true;
}

void append_to_vector(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (size > 0) out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

bool GrayImage::valid() const {
  return width >= 1 && height >= 1 && width <= 65535 && height <= 65535 &&
         pixels.size() == static_cast<size_t>(width) * static_cast<size_t>(height);
}

seqslam::ImageView GrayImage::view() const {
  if (!valid()) return seqslam::ImageView{};
  seqslam::ImageView v;
  v.pixels = pixels.data();
  v.size.width = static_cast<uint16_t>(width);
  v.size.height = static_cast<uint16_t>(height);
  return v;
}

uint8_t GrayImage::at(int x, int y) const {
  return pixels[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
}

LoadedImage decode_gray(const std::vector<uint8_t>& bytes, const std::string& name) {
  const std::string prefix = name + ": ";
  if (bytes.empty()) return Error{prefix + "file is empty"};

  if (bytes[0] == 'P') {
    LoadedImage pnm = detail::decode_pnm(bytes.data(), bytes.size());
    if (!pnm) return Error{prefix + pnm.error()};
    return pnm;
  }
  for (const Signature& sig : kSignatures) {
    if (is_cut_signature(bytes, sig)) {
      return Error{prefix + "truncated " + sig.name + " (only " + std::to_string(bytes.size()) +
                   " bytes)"};
    }
    if (!starts_with(bytes, sig.bytes, sig.length)) continue;
    Outcome<detail::Dims> structure = Error{"unchecked"};
    switch (sig.format) {
      case Format::kPng:
        structure = detail::check_png_structure(bytes.data(), bytes.size());
        break;
      case Format::kJpeg:
        structure = detail::check_jpeg_structure(bytes.data(), bytes.size());
        break;
      case Format::kBmp:
        structure = detail::check_bmp_structure(bytes.data(), bytes.size());
        break;
      case Format::kPnm:
      case Format::kUnknown:
        break;
    }
    if (!structure) return Error{prefix + structure.error()};
    // JPEG carries no checksum: libjpeg's corrupt-data warnings are the only sign of damage.
    if (sig.format == Format::kJpeg) {
      const std::string problem = detail::jpeg_problem(bytes.data(), bytes.size());
      if (!problem.empty()) return Error{prefix + problem};
    }
    // PNG through libpng, which verifies the chunk CRCs and the zlib Adler-32 (stb_image does
    // not); JPEG and BMP carry no checksums and stay with stb_image.
    LoadedImage image = sig.format == Format::kPng ? detail::decode_png(bytes.data(), bytes.size())
                                                   : decode_with_stb(bytes, sig.name);
    if (!image) return Error{prefix + image.error()};
    return image;
  }
  return Error{prefix +
               "not a supported image (expected PNG, JPEG, BMP, PGM or PPM; the file signature "
               "'" +
               detail::printable(std::string_view(reinterpret_cast<const char*>(bytes.data()),
                                                  bytes.size() < 8 ? bytes.size() : 8)) +
               "' is not recognised)"};
}

LoadedImage load_gray(const std::string& path) {
  Outcome<std::vector<uint8_t>> bytes = detail::read_file_bytes(path, kMaxImageFileBytes);
  if (!bytes) return Error{bytes.error()};
  return decode_gray(bytes.value(), path);
}

bool save_pgm(const std::string& path, const GrayImage& image, std::string* error) {
  if (!check_saveable(path, image, error)) return false;
  const std::string header =
      "P5\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  std::vector<uint8_t> file(header.begin(), header.end());
  file.insert(file.end(), image.pixels.begin(), image.pixels.end());
  return detail::write_file_bytes(path, file.data(), file.size(), error);
}

bool save_png(const std::string& path, const GrayImage& image, std::string* error) {
  if (!check_saveable(path, image, error)) return false;
  std::vector<uint8_t> encoded;
  if (stbi_write_png_to_func(append_to_vector, &encoded, image.width, image.height, 1,
                             image.pixels.data(), image.width) == 0 ||
      encoded.empty()) {
    detail::set_error(error, path + ": PNG encoding failed");
    return false;
  }
  return detail::write_file_bytes(path, encoded.data(), encoded.size(), error);
}

}  // namespace seqslam::tools
