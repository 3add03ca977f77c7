// Input files read strictly (issue 34): the tools read regular files only (a FIFO, a device
// or /dev/zero could block or never end), and say why a path cannot be read in words that
// fit: a symbolic link loop or a dangling link is not "no such file".
#pragma once

#include <stdint.h>

#include <string>

namespace seqslam::tools {

// Why `path` cannot be reached, for a path stat() fails on: "PATH: no such file", "PATH: a
// dangling symbolic link (to TARGET, which does not exist)", "PATH: a symbolic link loop (Too
// many levels of symbolic links)", "PATH: cannot access: Permission denied", ... ("" when
// stat() succeeds).
std::string unreachable_file(const std::string& path);

// "" when `path` is a regular file (symbolic links followed); else "PATH: why":
// unreachable_file()'s reasons, "is a directory, not a file", "is not a regular file (a
// device, FIFO or socket), which this tool does not read".
std::string check_regular_input(const std::string& path);

// The whole of a tool's own output file read back to resume it (sweep and transforms rows):
// "" with *content the bytes ("" for a path that is not a regular file: nothing to resume),
// or "PATH: cannot read it to resume: why".
std::string read_resume_file(const std::string& path, std::string* content);

// Fields of the tools' own CSV files (resumable sweep and transforms rows), read strictly.
// A whole number: decimal digits, no sign, space or leading zero, within [lo, hi].
bool parse_whole_field(const std::string& s, uint64_t lo, uint64_t hi, uint64_t* out);
// A finite number as "%g"/"%f" print it ("0.5", "1e-05", "-2"): no space, NaN, infinity or
// hexadecimal.
bool parse_finite_field(const std::string& s, double* out);
// The first byte below 0x20 (a NUL in a damaged file), or -1 when there is none.
int control_byte_at(const std::string& s);

}  // namespace seqslam::tools
