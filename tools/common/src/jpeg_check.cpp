// libjpeg's verdict on a JPEG before stb_image decodes it (formats.h, jpeg_problem).
//
// libjpeg reports damaged entropy-coded data (a bad Huffman code, a segment that ends early,
// stray bytes before a marker, a file cut short) as a *warning* and goes on with made-up
// pixels; stb_image reports nothing at all. A flipped byte in a JPEG therefore gave another
// image without a word (49 of 200 single-byte flips of a corridor image). Here every warning
// and error is fatal: the file is decoded to the end by libjpeg, and any message refuses it.
// The pixels still come from stb_image, so valid images decode as before.
#include <csetjmp>
#include <cstdio>
#include <vector>

#include <jpeglib.h>

#include "formats.h"

namespace seqslam::tools::detail {

namespace {

struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands back a pointer to it
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void stop(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

extern "C" void on_jpeg_error(j_common_ptr info) {
  stop(info);
}

// Level -1 is a warning (corrupt data); 0 and above are trace messages.
extern "C" void on_jpeg_message(j_common_ptr info, int level) {
  if (level < 0) stop(info);
}

}  // namespace

std::string jpeg_problem(const uint8_t* data, size_t size) {
  jpeg_decompress_struct info{};
  JpegErrors errors{};
  std::vector<JSAMPLE> row;  // before setjmp: a longjmp back here leaves it intact
  info.err = jpeg_std_error(&errors.manager);
  errors.manager.error_exit = on_jpeg_error;
  errors.manager.emit_message = on_jpeg_message;
  if (setjmp(errors.jump) != 0) {
    jpeg_destroy_decompress(&info);
    return std::string("corrupt JPEG (libjpeg: ") + errors.message + ")";
  }
  jpeg_CreateDecompress(&info, JPEG_LIB_VERSION, sizeof info);
  jpeg_mem_src(&info, data, size);  // size_t is unsigned long here
  jpeg_read_header(&info, TRUE);
  jpeg_start_decompress(&info);
  row.resize(static_cast<size_t>(info.output_width) * static_cast<size_t>(info.output_components));
  while (info.output_scanline < info.output_height) {
    JSAMPROW rows[1] = {row.data()};
    jpeg_read_scanlines(&info, rows, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return {};
}

}  // namespace seqslam::tools::detail
