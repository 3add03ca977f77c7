// Image sequences on disk: a directory of images or an index file listing them.
#pragma once

#include <string>
#include <vector>

#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

using ImageList = Outcome<std::vector<std::string>>;

// True when `filename` ends in .png, .pgm, .ppm, .jpg, .jpeg or .bmp (ASCII case-insensitive).
bool has_image_extension(const std::string& filename);

// Lists the images of a sequence, in sequence order.
//  * `path` is a directory: every regular file (symbolic links followed) directly inside it
//    whose name has an image extension (see has_image_extension), sorted byte-wise by file
//    name; not recursive. Returned paths are `path` joined with the file name.
//  * `path` is a regular file: an index file, one image path per line. Each line is trimmed
//    of leading/trailing whitespace (so CRLF line ends are fine); blank lines and lines whose
//    first non-blank character is '#' are ignored. Relative paths are resolved against the
//    directory containing the index file; absolute paths are kept. Every listed path must be
//    an existing regular file (any extension). Order is the order of the lines.
// Errors: `path` missing or neither a directory nor a regular file; a directory with no
// images; an index file with no entries; an index line naming a missing file or a non-file
// (the message gives "index:line:"); an index file that is itself an image or is binary.
ImageList list_images(const std::string& path);

struct Sequence {
  std::vector<GrayImage> images;   // all exactly the requested size
  std::vector<std::string> paths;  // the source file of each image, as listed
};

using LoadedSequence = Outcome<Sequence>;

// Lists (list_images), loads (load_gray) and reduces (reduce_to) every image of `path` to
// width x height. The target size is checked before anything is loaded. Errors name the
// failing file.
LoadedSequence load_sequence(const std::string& path, int width, int height);

}  // namespace seqslam::tools
