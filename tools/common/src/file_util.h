// Internal helpers shared by the host tools: whole-file I/O with messages, text splitting.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <string>
#include <string_view>
#include <vector>

#include "seqslam_tools/outcome.h"

namespace seqslam::tools::detail {

// Reads the whole regular file at `path` (at most max_bytes). Errors start with the path:
// empty path, missing, not a regular file (directories and devices are refused, so a FIFO or
// /dev/zero cannot hang or exhaust memory), unreadable, read error, larger than max_bytes.
Outcome<std::vector<uint8_t>> read_file_bytes(const std::string& path, uint64_t max_bytes);
Outcome<std::string> read_file_text(const std::string& path, uint64_t max_bytes);

// Writes `size` bytes to `path` through a temporary file renamed over it (output_file.h:
// a failed write leaves the old file untouched); false with a message naming the file.
bool write_file_bytes(const std::string& path, const void* data, size_t size, std::string* error);

// ASCII whitespace: space, \t, \n, \v, \f, \r.
constexpr bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}
constexpr bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

std::string_view trim(std::string_view s);

// Splits on '\n'. A final line without a terminator is included; a trailing '\n' does not
// produce an extra empty line. '\r' is left in place (callers trim).
std::vector<std::string_view> split_lines(std::string_view text);

// Renders arbitrary bytes for a message: printable ASCII as is, others as \xNN, cut after
// max_chars with "...".
std::string printable(std::string_view s, size_t max_chars = 60);

// Sets *error if error is non-null.
void set_error(std::string* error, std::string message);

}  // namespace seqslam::tools::detail
