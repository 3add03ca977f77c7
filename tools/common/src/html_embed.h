// Internal helpers for the self-contained HTML pages (report.cpp, slam_report.cpp): text
// escaping and images as PNG data URIs, so both pages embed the same way.
#pragma once

#include <stdint.h>

#include <string>
#include <string_view>
#include <vector>

namespace seqslam::tools::detail {

// Text for HTML content and attribute values (& < > " ').
std::string html_escape(std::string_view s);

// Standard base64 with '=' padding.
std::string base64(const std::vector<uint8_t>& bytes);

// The 8-bit image (`channels` samples per pixel: 1 grey, 3 RGB, rows top first) as
// "data:image/png;base64,..."; empty if it cannot be encoded (empty image, encoder failure).
std::string png_data_uri(int width, int height, int channels, const std::vector<uint8_t>& pixels);

}  // namespace seqslam::tools::detail
