// A small strict PNM (PGM/PPM) reader: plain P2/P3 and binary P5/P6, maxval 1..65535.
#include <string>
#include <utility>
#include <vector>

#include "file_util.h"
#include "formats.h"

namespace seqslam::tools::detail {
namespace {

class PnmReader {
 public:
  PnmReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  size_t pos() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }
  const uint8_t* here() const { return data_ + pos_; }
  void advance(size_t n) { pos_ += n; }
  bool at_end() const { return pos_ >= size_; }
  char peek() const { return static_cast<char>(data_[pos_]); }

  // Whitespace and '#' comments (to the end of the line).
  void skip_separators() {
    while (pos_ < size_) {
      const char c = peek();
      if (is_space(c)) {
        ++pos_;
      } else if (c == '#') {
        while (pos_ < size_ && data_[pos_] != '\n' && data_[pos_] != '\r')
          ++pos_;
      } else {
        break;
      }
    }
  }

  // Reads an unsigned decimal number preceded by separators and followed by a separator or the
  // end of the data.
  bool read_number(const std::string& what, uint32_t* out, std::string* error) {
    skip_separators();
    if (at_end()) {
      *error = "truncated: the data ends before the " + what;
      return false;
    }
    if (!is_digit(peek())) {
      *error = "bad " + what + " at byte " + std::to_string(pos_) +
               ": expected a decimal number, found '" + printable(token()) + "'";
      return false;
    }
    uint64_t value = 0;
    while (!at_end() && is_digit(peek())) {
      value = value * 10 + static_cast<uint64_t>(peek() - '0');
      if (value > 0xffffffffu) {
        *error = "bad " + what + " at byte " + std::to_string(pos_) + ": number too large";
        return false;
      }
      ++pos_;
    }
    if (!at_end() && !is_space(peek()) && peek() != '#') {
      *error = "bad " + what + " at byte " + std::to_string(pos_) +
               ": unexpected character in number ('" + printable(token()) + "')";
      return false;
    }
    *out = static_cast<uint32_t>(value);
    return true;
  }

 private:
  // The bytes from pos_ up to the next whitespace, for messages.
  std::string_view token() const {
    size_t end = pos_;
    while (end < size_ && end - pos_ < 16 && !is_space(static_cast<char>(data_[end])))
      ++end;
    return std::string_view(reinterpret_cast<const char*>(data_ + pos_), end - pos_);
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

std::string pixel_position(size_t sample, size_t channels, size_t width) {
  const size_t pixel = sample / channels;
  return "(" + std::to_string(pixel % width) + ", " + std::to_string(pixel / width) + ")";
}

}  // namespace

Outcome<GrayImage> decode_pnm(const uint8_t* data, size_t size) {
  if (size < 2 || data[0] != 'P') return Error{"not a PNM file"};
  const char kind = static_cast<char>(data[1]);
  if (kind == '1' || kind == '4') return Error{"PBM bitmaps (P1/P4) are not supported"};
  if (kind == '7') return Error{"PAM (P7) files are not supported"};
  if (kind != '2' && kind != '3' && kind != '5' && kind != '6') {
    return Error{"not a PNM file (unknown magic number)"};
  }
  const bool plain = kind == '2' || kind == '3';
  const size_t channels = (kind == '3' || kind == '6') ? 3 : 1;
  const char* const type_name = channels == 3 ? "PPM" : "PGM";

  PnmReader reader(data, size);
  reader.advance(2);
  if (reader.at_end()) return Error{std::string("truncated ") + type_name + " header"};
  if (!is_space(reader.peek()) && reader.peek() != '#') {
    return Error{std::string("bad ") + type_name + " magic number (no separator after P" + kind +
                 ")"};
  }

  std::string error;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t maxval = 0;
  if (!reader.read_number("width", &width, &error) ||
      !reader.read_number("height", &height, &error)) {
    return Error{std::string(type_name) + " header: " + error};
  }
  if (!check_dimensions(width, height, &error)) return Error{error};
  if (!reader.read_number("maxval", &maxval, &error)) {
    return Error{std::string(type_name) + " header: " + error};
  }
  if (maxval == 0 || maxval > 65535) {
    return Error{std::string(type_name) + " header: maxval " + std::to_string(maxval) +
                 " is invalid (must be 1..65535)"};
  }

  // 8-bit value of every legal sample, rounded to nearest.
  std::vector<uint8_t> scale(size_t{maxval} + 1);
  for (uint32_t v = 0; v <= maxval; ++v) {
    scale[v] = static_cast<uint8_t>((uint64_t{v} * 255u + maxval / 2) / maxval);
  }

  const size_t w = width;
  const size_t h = height;
  const size_t samples = w * h * channels;  // <= 16384^2 * 3, no overflow
  std::vector<uint8_t> values;              // 8-bit samples

  if (plain) {
    // Every sample needs at least one byte: reject a short file before allocating.
    if (reader.remaining() < samples) {
      return Error{std::string("truncated ") + type_name +
                   " pixel data: " + std::to_string(samples) + " samples expected, only " +
                   std::to_string(reader.remaining()) + " bytes left"};
    }
    values.resize(samples);
    for (size_t i = 0; i < samples; ++i) {
      uint32_t v = 0;
      if (!reader.read_number(
              "sample " + std::to_string(i) + " (pixel " + pixel_position(i, channels, w) + ")", &v,
              &error)) {
        return Error{std::string(type_name) + " pixel data: " + error};
      }
      if (v > maxval) {
        return Error{std::string(type_name) + " pixel data: sample value " + std::to_string(v) +
                     " at pixel " + pixel_position(i, channels, w) + " exceeds maxval " +
                     std::to_string(maxval)};
      }
      values[i] = scale[v];
    }
  } else {
    // Exactly one whitespace byte separates maxval from the raster.
    if (reader.at_end()) return Error{std::string("truncated ") + type_name + ": no pixel data"};
    if (!is_space(reader.peek())) {
      return Error{std::string(type_name) +
                   " header: expected one whitespace character after maxval"};
    }
    reader.advance(1);
    const size_t bytes_per_sample = maxval > 255 ? 2 : 1;
    const size_t needed = samples * bytes_per_sample;
    if (reader.remaining() < needed) {
      return Error{std::string("truncated ") + type_name +
                   " pixel data: " + std::to_string(needed) + " bytes expected, only " +
                   std::to_string(reader.remaining()) + " present"};
    }
    values.resize(samples);
    const uint8_t* p = reader.here();
    for (size_t i = 0; i < samples; ++i) {
      uint32_t v = p[i * bytes_per_sample];
      if (bytes_per_sample == 2) v = (v << 8) | p[i * 2 + 1];
      if (v > maxval) {
        return Error{std::string(type_name) + " pixel data: sample value " + std::to_string(v) +
                     " at pixel " + pixel_position(i, channels, w) + " exceeds maxval " +
                     std::to_string(maxval)};
      }
      values[i] = scale[v];
    }
  }

  GrayImage image;
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  if (channels == 1) {
    image.pixels = std::move(values);
  } else {
    image.pixels.resize(w * h);
    for (size_t i = 0; i < w * h; ++i) {
      image.pixels[i] = luma(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    }
  }
  return Outcome<GrayImage>(std::move(image));
}

}  // namespace seqslam::tools::detail
