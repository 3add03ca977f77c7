#include "file_util.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include <filesystem>
#include <memory>
#include <system_error>
#include <utility>

#include "seqslam_tools/input_file.h"
#include "seqslam_tools/output_file.h"

namespace seqslam::tools::detail {
namespace {

namespace fs = std::filesystem;

struct FileCloser {
  void operator()(FILE* f) const {
    if (f != nullptr) fclose(f);
  }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

std::string errno_text(int err) {
  return std::string(strerror(err));
}

template <typename Container>
Outcome<Container> read_file(const std::string& path, uint64_t max_bytes) {
  // Regular files only; a link loop or a dangling link says so (input_file.h).
  if (std::string why = check_regular_input(path); !why.empty()) return Error{why};

  errno = 0;
  FilePtr f(fopen(path.c_str(), "rb"));
  if (!f) return Error{path + ": cannot open: " + errno_text(errno)};

  Container data;
  char buffer[65536];
  for (;;) {
    const size_t n = fread(buffer, 1, sizeof buffer, f.get());
    if (n > 0) {
      if (data.size() + n > max_bytes) {
        return Error{path + ": file is larger than " + std::to_string(max_bytes) +
                     " bytes; refusing to read it"};
      }
      data.insert(data.end(), buffer, buffer + n);
    }
    if (n < sizeof buffer) {
      if (ferror(f.get()) != 0) return Error{path + ": read error: " + errno_text(errno)};
      break;
    }
  }
  return Outcome<Container>(std::move(data));
}

}  // namespace

Outcome<std::vector<uint8_t>> read_file_bytes(const std::string& path, uint64_t max_bytes) {
  return read_file<std::vector<uint8_t>>(path, max_bytes);
}

Outcome<std::string> read_file_text(const std::string& path, uint64_t max_bytes) {
  return read_file<std::string>(path, max_bytes);
}

bool write_file_bytes(const std::string& path, const void* data, size_t size, std::string* error) {
  // A temporary file renamed over `path` (output_file.h): a failed write leaves no partial
  // file and the old one untouched.
  std::string message = write_output(path, data, size);
  if (message.empty()) return true;
  set_error(error, std::move(message));
  return false;
}

std::string_view trim(std::string_view s) {
  size_t begin = 0;
  size_t end = s.size();
  while (begin < end && is_space(s[begin]))
    ++begin;
  while (end > begin && is_space(s[end - 1]))
    --end;
  return s.substr(begin, end - begin);
}

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start < text.size()) {
    const size_t nl = text.find('\n', start);
    if (nl == std::string_view::npos) {
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, nl - start));
    start = nl + 1;
  }
  return lines;
}

std::string printable(std::string_view s, size_t max_chars) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    }
  }
  return out;
}

void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

}  // namespace seqslam::tools::detail
