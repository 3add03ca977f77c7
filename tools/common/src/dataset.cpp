#include "seqslam_tools/dataset.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "file_util.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/reduce.h"

namespace seqslam::tools {
namespace {

namespace fs = std::filesystem;

// Index files are short text; anything larger is not an index.
constexpr uint64_t kMaxIndexBytes = uint64_t{16} << 20;

char ascii_lower(char c) {
  return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}

ImageList list_directory(const std::string& path) {
  std::vector<std::string> names;
  std::error_code ec;
  fs::directory_iterator it(path, ec);
  if (ec) return Error{path + ": cannot list directory: " + ec.message()};
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const std::string name = it->path().filename().string();
    if (!has_image_extension(name)) continue;
    // An image entry that cannot be read (a dangling link, a link loop, a FIFO) is an error,
    // not a gap: skipping it would shift every later image's index (and its ground truth)
    // by one. A subdirectory is not an image of a non-recursive listing.
    std::error_code type_ec;
    if (it->is_directory(type_ec)) continue;
    const std::string why = check_regular_input(it->path().string());
    if (!why.empty()) {
      return Error{why + " (an image entry of the directory " + path +
                   ": remove or repair it, the images are numbered in name order)"};
    }
    names.push_back(name);
  }
  if (ec) return Error{path + ": cannot list directory: " + ec.message()};
  if (names.empty()) {
    return Error{path + ": directory contains no images (.png, .pgm, .ppm, .jpg, .jpeg, .bmp)"};
  }
  std::sort(names.begin(), names.end());  // std::string compares bytes as unsigned char
  std::vector<std::string> paths;
  paths.reserve(names.size());
  for (const std::string& name : names)
    paths.push_back((fs::path(path) / name).string());
  return Outcome<std::vector<std::string>>(std::move(paths));
}

ImageList read_index(const std::string& path) {
  if (has_image_extension(path)) {
    return Error{path +
                 ": is an image file; expected a directory of images or an index file "
                 "(one image path per line)"};
  }
  Outcome<std::string> text = detail::read_file_text(path, kMaxIndexBytes);
  if (!text) return Error{text.error() + " (index files are limited to 16 MiB)"};
  const fs::path base = fs::path(path).parent_path();
  const std::vector<std::string_view> lines = detail::split_lines(text.value());
  std::vector<std::string> paths;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string where = path + ":" + std::to_string(i + 1) + ": ";
    const std::string_view line = detail::trim(lines[i]);
    if (line.empty() || line.front() == '#') continue;
    if (line.find('\0') != std::string_view::npos) {
      return Error{where + "line contains a NUL byte; this is not a text index file"};
    }
    const std::string entry(line);
    const fs::path resolved = fs::path(entry).is_absolute() ? fs::path(entry) : base / entry;
    std::error_code ec;
    const fs::file_status st = fs::status(resolved, ec);
    if (!fs::exists(st)) {
      const std::string why = unreachable_file(resolved.string());
      const bool plain = why == resolved.string() + ": no such file";
      return Error{where + "listed image '" + detail::printable(entry, 200) +
                   (plain ? "' does not exist (looked for '" + resolved.string() + "')"
                          : "' cannot be read: " + why)};
    }
    if (!fs::is_regular_file(st)) {
      return Error{where + "listed image '" + detail::printable(entry, 200) +
                   "' is not a regular file"};
    }
    paths.push_back(resolved.string());
  }
  if (paths.empty()) {
    return Error{path + ": index file lists no images (only blank or '#' comment lines)"};
  }
  return Outcome<std::vector<std::string>>(std::move(paths));
}

}  // namespace

bool has_image_extension(const std::string& filename) {
  static constexpr std::string_view kExtensions[] = {".png", ".pgm",  ".ppm",
                                                     ".jpg", ".jpeg", ".bmp"};
  const std::string_view name(filename);
  for (const std::string_view ext : kExtensions) {
    // A bare ".png" is a hidden file with no extension.
    if (name.size() <= ext.size()) continue;
    const std::string_view tail = name.substr(name.size() - ext.size());
    bool same = true;
    for (size_t i = 0; i < ext.size(); ++i) {
      if (ascii_lower(tail[i]) != ext[i]) {
        same = false;
        break;
      }
    }
    if (same && name[name.size() - ext.size() - 1] != '/') return true;
  }
  return false;
}

ImageList list_images(const std::string& path) {
  if (path.empty()) return Error{"(empty path): no image directory or index file given"};
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) {
    const std::string why = unreachable_file(path);
    return Error{why == path + ": no such file" ? path + ": no such file or directory" : why};
  }
  if (fs::is_directory(st)) return list_directory(path);
  if (fs::is_regular_file(st)) return read_index(path);
  return Error{path + ": is neither a directory nor a regular (index) file"};
}

LoadedSequence load_sequence(const std::string& path, int width, int height) {
  Outcome<seqslam::ImageSize> target = check_reduce_target(width, height);
  if (!target) return Error{path + ": " + target.error()};
  ImageList list = list_images(path);
  if (!list) return Error{list.error()};

  Sequence sequence;
  sequence.images.reserve(list.value().size());
  for (const std::string& file : list.value()) {
    LoadedImage image = load_gray(file);
    if (!image) return Error{image.error()};
    ReducedImage reduced = reduce_to(image.value(), width, height);
    if (!reduced) return Error{file + ": " + reduced.error()};
    sequence.images.push_back(std::move(reduced).value());
  }
  sequence.paths = std::move(list).value();
  return Outcome<Sequence>(std::move(sequence));
}

}  // namespace seqslam::tools
