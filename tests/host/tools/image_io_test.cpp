#include "seqslam_tools/image_io.h"

#include <jpeglib.h>
#include <stb_image_write.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "png_samples.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

using test::TempDir;
using test::write_file;
using ::testing::HasSubstr;

GrayImage make_image(int width, int height) {
  GrayImage image;
  image.width = width;
  image.height = height;
  image.pixels.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] = static_cast<uint8_t>((i * 37 + 11) % 256);
  }
  return image;
}

void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

// An in-memory PNG of `channels` interleaved 8-bit samples per pixel.
std::vector<uint8_t> encode_png(int width, int height, int channels,
                                const std::vector<uint8_t>& samples) {
  std::vector<uint8_t> out;
  EXPECT_NE(0, stbi_write_png_to_func(append_bytes, &out, width, height, channels, samples.data(),
                                      width * channels));
  return out;
}

std::string corridor_image(const char* traverse, int index) {
  char name[32];
  snprintf(name, sizeof name, "/%07d.jpg", index);
  return test::corridor_dir() + "/" + traverse + name;
}

// Loads `bytes` written to a file called `name` and expects failure with `what` in the
// message (which must also name the file).
void expect_load_fails(const TempDir& dir, const std::string& name, const std::string& bytes,
                       const std::string& what) {
  const std::string path = dir.file(name);
  write_file(path, bytes);
  const LoadedImage result = load_gray(path);
  EXPECT_FALSE(result.ok()) << name;
  EXPECT_THAT(result.error(), HasSubstr(path)) << name;
  EXPECT_THAT(result.error(), HasSubstr(what)) << name;
  EXPECT_EQ(result.value().pixels.size(), 0u);
}

TEST(ImageIo, LumaUsesIntegerBt601Weights) {
  EXPECT_EQ(luma(0, 0, 0), 0);
  EXPECT_EQ(luma(255, 255, 255), 255);
  EXPECT_EQ(luma(255, 0, 0), 77);     // (19635 + 128) >> 8 = 77
  EXPECT_EQ(luma(0, 255, 0), 149);    // (38250 + 128) >> 8 = 149
  EXPECT_EQ(luma(0, 0, 255), 29);     // (7395 + 128) >> 8 = 29
  EXPECT_EQ(luma(10, 200, 30), 124);  // (770 + 30000 + 870 + 128) >> 8 = 31768 >> 8 = 124
}

TEST(ImageIo, LoadsCorridorJpeg) {
  const LoadedImage image = load_gray(corridor_image("ref", 0));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_TRUE(image.error().empty());
  EXPECT_EQ(image.value().width, 160);
  EXPECT_EQ(image.value().height, 120);
  EXPECT_EQ(image.value().pixels.size(), 160u * 120u);
  EXPECT_TRUE(image.value().valid());
  const seqslam::ImageView view = image.value().view();
  EXPECT_EQ(view.pixels, image.value().pixels.data());
  EXPECT_EQ(view.size.width, 160);
  EXPECT_EQ(view.size.height, 120);
  // A real photo: not a constant image.
  uint8_t lo = 255;
  uint8_t hi = 0;
  for (const uint8_t p : image.value().pixels) {
    lo = p < lo ? p : lo;
    hi = p > hi ? p : hi;
  }
  EXPECT_LT(lo + 40, hi);
}

TEST(ImageIo, LoadsEveryCorridorImage) {
  for (const char* traverse : {"ref", "query"}) {
    for (int i = 0; i <= 110; ++i) {
      const LoadedImage image = load_gray(corridor_image(traverse, i));
      ASSERT_TRUE(image.ok()) << image.error();
      EXPECT_EQ(image.value().width, 160);
      EXPECT_EQ(image.value().height, 120);
    }
  }
}

TEST(ImageIo, ColourPngConvertsToLumaAndIgnoresAlpha) {
  TempDir dir;
  // 2x2 RGB: red, green / blue, (10, 200, 30).
  const std::vector<uint8_t> rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 200, 30};
  write_file(dir.file("rgb.png"), encode_png(2, 2, 3, rgb));
  const LoadedImage a = load_gray(dir.file("rgb.png"));
  ASSERT_TRUE(a.ok()) << a.error();
  EXPECT_EQ(a.value().pixels, (std::vector<uint8_t>{77, 149, 29, luma(10, 200, 30)}));

  // The same colours with varying alpha (0 included): alpha does not matter.
  const std::vector<uint8_t> rgba = {255, 0, 0, 0, 0, 255, 0, 128, 0, 0, 255, 255, 10, 200, 30, 7};
  write_file(dir.file("rgba.png"), encode_png(2, 2, 4, rgba));
  const LoadedImage b = load_gray(dir.file("rgba.png"));
  ASSERT_TRUE(b.ok()) << b.error();
  EXPECT_EQ(b.value().pixels, a.value().pixels);

  // Grey + alpha keeps the grey level.
  const std::vector<uint8_t> ga = {0, 255, 100, 0, 200, 9, 255, 255};
  write_file(dir.file("ga.png"), encode_png(2, 2, 2, ga));
  const LoadedImage c = load_gray(dir.file("ga.png"));
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c.value().pixels, (std::vector<uint8_t>{0, 100, 200, 255}));
}

TEST(ImageIo, LoadsBmp) {
  TempDir dir;
  const std::vector<uint8_t> rgb = {255, 0, 0, 0,  255, 0,  0,   0,   255,
                                    1,   2, 3, 90, 90,  90, 255, 255, 255};
  ASSERT_NE(0, stbi_write_bmp(dir.file("a.bmp").c_str(), 3, 2, 3, rgb.data()));
  const LoadedImage image = load_gray(dir.file("a.bmp"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().width, 3);
  EXPECT_EQ(image.value().height, 2);
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{77, 149, 29, luma(1, 2, 3), 90, 255}));
}

TEST(ImageIo, LoadsJpegWrittenByStb) {
  TempDir dir;
  const std::vector<uint8_t> grey(size_t{16} * 8, 128);
  ASSERT_NE(0, stbi_write_jpg(dir.file("g.jpg").c_str(), 16, 8, 1, grey.data(), 100));
  const LoadedImage image = load_gray(dir.file("g.jpg"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().width, 16);
  EXPECT_EQ(image.value().height, 8);
  for (const uint8_t p : image.value().pixels)
    EXPECT_NEAR(p, 128, 2);
}

TEST(ImageIo, PngRoundTrip) {
  TempDir dir;
  const GrayImage image = make_image(7, 5);
  std::string error;
  ASSERT_TRUE(save_png(dir.file("a.png"), image, &error)) << error;
  const LoadedImage back = load_gray(dir.file("a.png"));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().width, 7);
  EXPECT_EQ(back.value().height, 5);
  EXPECT_EQ(back.value().pixels, image.pixels);
}

TEST(ImageIo, PgmRoundTripAndExactFormat) {
  TempDir dir;
  GrayImage image;
  image.width = 3;
  image.height = 2;
  image.pixels = {0, 1, 2, 253, 254, 255};
  std::string error;
  ASSERT_TRUE(save_pgm(dir.file("a.pgm"), image, &error)) << error;
  EXPECT_EQ(test::to_string(test::read_file(dir.file("a.pgm"))),
            std::string("P5\n3 2\n255\n\x00\x01\x02\xfd\xfe\xff", 17));
  const LoadedImage back = load_gray(dir.file("a.pgm"));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().pixels, image.pixels);
}

TEST(ImageIo, SaveRejectsInvalidImageAndUnwritablePath) {
  TempDir dir;
  GrayImage bad;
  bad.width = 4;
  bad.height = 4;
  bad.pixels.resize(15);
  std::string error;
  EXPECT_FALSE(save_pgm(dir.file("bad.pgm"), bad, &error));
  EXPECT_THAT(error, HasSubstr("bad.pgm"));
  EXPECT_THAT(error, HasSubstr("invalid image"));
  error.clear();
  EXPECT_FALSE(save_png(dir.file("bad.png"), bad, &error));
  EXPECT_THAT(error, HasSubstr("invalid image"));
  EXPECT_FALSE(save_png(dir.file("bad.png"), GrayImage{}, nullptr));  // null error is fine

  const GrayImage good = make_image(2, 2);
  const std::string nowhere = dir.file("no/such/dir/x.pgm");
  error.clear();
  EXPECT_FALSE(save_pgm(nowhere, good, &error));
  EXPECT_THAT(error, HasSubstr(nowhere));
  error.clear();
  EXPECT_FALSE(save_png(dir.file("no/such/dir/x.png"), good, &error));
  EXPECT_THAT(error, HasSubstr("x.png"));
}

TEST(ImageIo, InvalidImageGivesEmptyView) {
  GrayImage image = make_image(3, 3);
  EXPECT_TRUE(image.valid());
  EXPECT_EQ(image.at(2, 1), image.pixels[5]);
  image.pixels.pop_back();
  EXPECT_FALSE(image.valid());
  EXPECT_EQ(image.view().pixels, nullptr);
  EXPECT_EQ(image.view().size.pixels(), 0u);
  EXPECT_FALSE(GrayImage{}.valid());
  GrayImage wide;
  wide.width = 70000;
  wide.height = 1;
  wide.pixels.resize(70000);
  EXPECT_FALSE(wide.valid());  // does not fit the core's 16-bit sizes
}

// ---- PGM / PPM ---------------------------------------------------------------------------

TEST(ImageIo, PlainPgmWithComments) {
  TempDir dir;
  write_file(dir.file("a.pgm"),
             "P2 # magic\n# a comment line\n3 # width\n2\n# before maxval\n255\n"
             "0 10 20\n# inside the raster\n30 40 255\n");
  const LoadedImage image = load_gray(dir.file("a.pgm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().width, 3);
  EXPECT_EQ(image.value().height, 2);
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{0, 10, 20, 30, 40, 255}));
}

TEST(ImageIo, PnmMaxvalScaling) {
  TempDir dir;
  // maxval 1000 (plain): v -> (v * 255 + 500) / 1000: 500 -> 128, 1 -> 0, 2 -> 1, 1000 -> 255.
  write_file(dir.file("a.pgm"), "P2\n4 1\n1000\n500 1 2 1000\n");
  LoadedImage image = load_gray(dir.file("a.pgm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{128, 0, 1, 255}));

  // Binary 16-bit, big-endian: 0, 65535, 32896 (= 128 * 257) -> 0, 255, 128.
  write_file(dir.file("b.pgm"), std::string("P5\n3 1\n65535\n\x00\x00\xff\xff\x80\x80", 19));
  image = load_gray(dir.file("b.pgm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{0, 255, 128}));

  // maxval 15 scales up: 15 -> 255, 7 -> (1785 + 7) / 15 = 119, 0 -> 0.
  write_file(dir.file("c.pgm"), std::string("P5 3 1 15\n\x0f\x07\x00", 13));
  image = load_gray(dir.file("c.pgm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{255, 119, 0}));
}

TEST(ImageIo, PpmPlainAndBinaryConvertToLuma) {
  TempDir dir;
  write_file(dir.file("a.ppm"), "P3\n# colour\n2 1\n255\n255 0 0  10 200 30\n");
  LoadedImage image = load_gray(dir.file("a.ppm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{77, luma(10, 200, 30)}));

  write_file(dir.file("b.ppm"), std::string("P6\n2 1\n255\n\xff\x00\x00\x0a\xc8\x1e", 17));
  image = load_gray(dir.file("b.ppm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{77, luma(10, 200, 30)}));

  // 16-bit colour: full-scale green.
  write_file(dir.file("c.ppm"), std::string("P6\n1 1\n65535\n\x00\x00\xff\xff\x00\x00", 19));
  image = load_gray(dir.file("c.ppm"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{149}));
}

TEST(ImageIo, FormatIsDetectedFromContentNotExtension) {
  TempDir dir;
  write_file(dir.file("really_a_pgm.png"), "P2\n1 1\n255\n42\n");
  const LoadedImage image = load_gray(dir.file("really_a_pgm.png"));
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(image.value().pixels, (std::vector<uint8_t>{42}));
}

// ---- bad input ---------------------------------------------------------------------------

TEST(ImageIoBad, MissingDirectoryAndEmpty) {
  TempDir dir;
  const LoadedImage missing = load_gray(dir.file("nope.png"));
  EXPECT_FALSE(missing.ok());
  EXPECT_THAT(missing.error(), HasSubstr("nope.png"));
  EXPECT_THAT(missing.error(), HasSubstr("no such file"));

  const LoadedImage directory = load_gray(dir.path());
  EXPECT_FALSE(directory.ok());
  EXPECT_THAT(directory.error(), HasSubstr("is a directory"));

  EXPECT_FALSE(load_gray("").ok());
  expect_load_fails(dir, "empty.png", "", "empty");
}

TEST(ImageIoBad, UnreadableFile) {
  if (geteuid() == 0) GTEST_SKIP() << "running as root: permissions are not enforced";
  TempDir dir;
  const GrayImage image = make_image(2, 2);
  ASSERT_TRUE(save_pgm(dir.file("locked.pgm"), image, nullptr));
  ASSERT_EQ(0, chmod(dir.file("locked.pgm").c_str(), 0));
  const LoadedImage result = load_gray(dir.file("locked.pgm"));
  EXPECT_FALSE(result.ok());
  EXPECT_THAT(result.error(), HasSubstr("cannot open"));
}

TEST(ImageIoBad, DeviceIsNotRead) {
  // /dev/zero would never end; it must be refused, not read.
  const LoadedImage result = load_gray("/dev/zero");
  EXPECT_FALSE(result.ok());
  EXPECT_THAT(result.error(), HasSubstr("not a regular file"));
}

TEST(ImageIoBad, TextFileRenamedPng) {
  TempDir dir;
  expect_load_fails(dir, "notes.png", "These are my notes, not a picture.\n",
                    "not a supported image");
  expect_load_fails(dir, "bm.bmp", "BM is how this text starts\n", "BMP");
  expect_load_fails(dir, "p.pgm", "Pasta recipe\n", "PNM");
}

TEST(ImageIoBad, TruncatedPngAtEveryLength) {
  TempDir dir;
  const std::string png = test::to_string(encode_png(3, 3, 3, std::vector<uint8_t>(27, 99)));
  for (size_t n = 1; n < png.size(); ++n) {
    const std::string path = dir.file("cut.png");
    write_file(path, png.substr(0, n));
    const LoadedImage result = load_gray(path);
    EXPECT_FALSE(result.ok()) << "cut at " << n;
    EXPECT_THAT(result.error(), HasSubstr("truncated")) << "cut at " << n;
  }
}

TEST(ImageIoBad, TruncatedJpeg) {
  TempDir dir;
  const std::string jpeg = test::to_string(test::read_file(corridor_image("query", 7)));
  ASSERT_GT(jpeg.size(), 1000u);
  for (size_t n = 1; n < jpeg.size(); n += (n < 700 ? 7 : 101)) {
    const std::string path = dir.file("cut.jpg");
    write_file(path, jpeg.substr(0, n));
    const LoadedImage result = load_gray(path);
    EXPECT_FALSE(result.ok()) << "cut at " << n;
    EXPECT_THAT(result.error(), HasSubstr("truncated")) << "cut at " << n;
  }
  // Cutting only the final EOI marker is caught too.
  expect_load_fails(dir, "no_eoi.jpg", jpeg.substr(0, jpeg.size() - 2), "EOI");
}

TEST(ImageIoBad, TruncatedBmp) {
  TempDir dir;
  const std::vector<uint8_t> rgb(size_t{8} * 8 * 3, 50);
  ASSERT_NE(0, stbi_write_bmp(dir.file("full.bmp").c_str(), 8, 8, 3, rgb.data()));
  const std::string bmp = test::to_string(test::read_file(dir.file("full.bmp")));
  for (size_t n = 1; n < bmp.size(); n += 5) {
    expect_load_fails(dir, "cut.bmp", bmp.substr(0, n), "truncated");
  }
}

TEST(ImageIoBad, TruncatedPgm) {
  TempDir dir;
  expect_load_fails(dir, "short.pgm", std::string("P5\n4 4\n255\n0123456789", 21), "truncated");
  expect_load_fails(dir, "no_raster.pgm", "P5\n4 4\n255", "truncated");
  expect_load_fails(dir, "short_plain.pgm", "P2\n2 2\n255\n1 2 3\n", "truncated");
  expect_load_fails(dir, "header_only.pgm", "P5\n4", "truncated");
  expect_load_fails(dir, "magic_only.pgm", "P5", "truncated");
  expect_load_fails(dir, "short16.pgm", std::string("P5 2 1 65535\n\x00\x01\x02", 16), "truncated");
}

TEST(ImageIoBad, PgmHeaderErrors) {
  TempDir dir;
  expect_load_fails(dir, "maxval0.pgm", std::string("P5\n2 2\n0\n\0\0\0\0", 13), "maxval 0");
  expect_load_fails(dir, "maxval_big.pgm", "P2\n1 1\n65536\n0\n", "maxval 65536");
  expect_load_fails(dir, "zero.pgm", "P5\n0 4\n255\n", "is zero or negative");
  expect_load_fails(dir, "letters.pgm", "P2\n2 x\n255\n", "height");
  expect_load_fails(dir, "overflow.pgm", "P2\n99999999999 1\n255\n", "too large");
  expect_load_fails(dir, "sample.pgm", "P2\n2 1\n100\n50 101\n", "exceeds maxval");
  expect_load_fails(dir, "sample5.pgm", std::string("P5\n2 1\n100\n\x10\xff", 13),
                    "exceeds maxval");
  expect_load_fails(dir, "garbage.pgm", "P2\n1 1\n255\n12ab\n", "unexpected character");
  expect_load_fails(dir, "negative.pgm", "P2\n1 1\n255\n-3\n", "expected a decimal number");
  expect_load_fails(dir, "pbm.pbm", "P1\n1 1\n1\n", "PBM");
  expect_load_fails(dir, "pam.pam", "P7\nWIDTH 1\n", "PAM");
  expect_load_fails(dir, "p5x.pgm", "P5x 1 1 255\n\x01", "magic");
}

TEST(ImageIoBad, HugeDimensionsWithoutData) {
  TempDir dir;
  // Absurd: rejected from the header.
  expect_load_fails(dir, "huge.pgm", "P5\n100000 100000\n255\n", "absurd");
  expect_load_fails(dir, "huge_plain.ppm", "P3\n20000 1\n255\n", "absurd");
  // Plausible but with no data: rejected before allocating the raster.
  expect_load_fails(dir, "big.pgm", "P5\n16384 16384\n65535\n", "truncated");
  expect_load_fails(dir, "big_plain.pgm", "P2\n16384 16384\n255\n1 2 3\n", "truncated");

  // A PNG whose IHDR claims 100000 x 5: rejected by the structure walk.
  std::string png = test::to_string(encode_png(1, 1, 1, {7}));
  ASSERT_GT(png.size(), 24u);
  std::string huge = png;
  huge[16] = 0;
  huge[17] = 0x01;
  huge[18] = static_cast<char>(0x86);
  huge[19] = static_cast<char>(0xA0);  // width 100000
  expect_load_fails(dir, "huge.png", huge, "absurd");

  // A PNG claiming 16384 x 16384 with a one-pixel IDAT: complete container, missing pixels.
  std::string big = png;
  big[16] = 0;
  big[17] = 0;
  big[18] = 0x40;
  big[19] = 0;  // width 16384
  big[20] = 0;
  big[21] = 0;
  big[22] = 0x40;
  big[23] = 0;  // height 16384
  expect_load_fails(dir, "big.png", big, "cannot hold a 16384x16384 image");

  // BMP claiming 100000 pixels wide.
  const std::vector<uint8_t> rgb(3, 1);
  ASSERT_NE(0, stbi_write_bmp(dir.file("one.bmp").c_str(), 1, 1, 3, rgb.data()));
  std::string bmp = test::to_string(test::read_file(dir.file("one.bmp")));
  ASSERT_GT(bmp.size(), 26u);
  bmp[18] = static_cast<char>(0xA0);
  bmp[19] = static_cast<char>(0x86);
  bmp[20] = 0x01;
  bmp[21] = 0;
  expect_load_fails(dir, "huge.bmp", bmp, "absurd");
  // ... and 16000 wide with one pixel of data.
  bmp[18] = static_cast<char>(0x80);
  bmp[19] = 0x3E;
  bmp[20] = 0;
  expect_load_fails(dir, "wide.bmp", bmp, "truncated");
}

TEST(ImageIoBad, JpegWithHugeFrameHeader) {
  TempDir dir;
  std::string jpeg = test::to_string(test::read_file(corridor_image("ref", 3)));
  // Find the SOF0/SOF2 marker and patch its height and width.
  size_t sof = std::string::npos;
  for (size_t i = 2; i + 9 < jpeg.size(); ++i) {
    const auto m = static_cast<uint8_t>(jpeg[i + 1]);
    if (static_cast<uint8_t>(jpeg[i]) == 0xFF && (m == 0xC0 || m == 0xC1 || m == 0xC2)) {
      sof = i;
      break;
    }
  }
  ASSERT_NE(sof, std::string::npos);
  std::string huge = jpeg;
  huge[sof + 5] = static_cast<char>(0xFF);
  huge[sof + 6] = static_cast<char>(0xFF);  // height 65535
  expect_load_fails(dir, "huge.jpg", huge, "absurd");
  std::string zero = jpeg;
  zero[sof + 7] = 0;
  zero[sof + 8] = 0;  // width 0
  expect_load_fails(dir, "zero.jpg", zero, "is zero or negative");
  // 16000 x 16000 with the ~8 KB of data of a 160 x 120 image: rejected before decoding.
  std::string big = jpeg;
  big[sof + 5] = 0x3E;
  big[sof + 6] = static_cast<char>(0x80);
  big[sof + 7] = 0x3E;
  big[sof + 8] = static_cast<char>(0x80);
  expect_load_fails(dir, "big.jpg", big, "cannot hold a 16000x16000 image");
  // 320 x 240 is plausible for that much data: stb decodes it (garbled) or fails; no crash.
  std::string doubled = jpeg;
  doubled[sof + 5] = 0;
  doubled[sof + 6] = static_cast<char>(240);
  doubled[sof + 7] = 0x01;
  doubled[sof + 8] = 0x40;
  write_file(dir.file("doubled.jpg"), doubled);
  const LoadedImage result = load_gray(dir.file("doubled.jpg"));
  if (result.ok()) {
    EXPECT_EQ(result.value().width, 320);
    EXPECT_EQ(result.value().height, 240);
  } else {
    EXPECT_THAT(result.error(), HasSubstr("doubled.jpg"));
  }
}

// Corrupted bytes must never crash; the result may be an error or a (garbled) image.
TEST(ImageIoBad, CorruptedFilesDoNotCrash) {
  const std::vector<uint8_t> jpeg = test::read_file(corridor_image("ref", 10));
  const std::vector<uint8_t> png =
      encode_png(9, 7, 3, std::vector<uint8_t>(size_t{9} * 7 * 3, 200));
  std::vector<uint8_t> bmp;
  {
    TempDir dir;
    const std::vector<uint8_t> rgb(size_t{5} * 4 * 3, 9);
    ASSERT_NE(0, stbi_write_bmp(dir.file("a.bmp").c_str(), 5, 4, 3, rgb.data()));
    bmp = test::read_file(dir.file("a.bmp"));
  }
  const std::vector<uint8_t> pgm = [] {
    const std::string s = "P2\n3 2\n# c\n255\n1 2 3\n4 5 6\n";
    return std::vector<uint8_t>(s.begin(), s.end());
  }();
  uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1103515245u + 12345u;
    return state >> 8;
  };
  const std::vector<const std::vector<uint8_t>*> originals = {&jpeg, &png, &bmp, &pgm};
  for (const std::vector<uint8_t>* original : originals) {
    for (int round = 0; round < 150; ++round) {
      std::vector<uint8_t> bytes = *original;
      const uint32_t flips = 1 + next() % 4;
      for (uint32_t k = 0; k < flips; ++k) {
        bytes[next() % bytes.size()] = static_cast<uint8_t>(next());
      }
      const LoadedImage result = decode_gray(bytes, "mutant");
      if (result.ok()) {
        EXPECT_TRUE(result.value().valid());
      } else {
        EXPECT_THAT(result.error(), HasSubstr("mutant: "));
      }
    }
  }
}

// libjpeg's own count of what it reports while decoding `jpeg` to the end with its standard
// error manager (warnings: corrupt data it decodes anyway); -1 when it gives up (an error).
// Written apart from the loader's check (jpeg_check.cpp), as the oracle.
int libjpeg_warnings(const std::vector<uint8_t>& jpeg) {
  struct Errors {
    jpeg_error_mgr manager;
    jmp_buf jump;
  };
  jpeg_decompress_struct info{};
  Errors errors{};
  std::vector<JSAMPLE> row;
  info.err = jpeg_std_error(&errors.manager);
  errors.manager.error_exit = [](j_common_ptr c) {
    longjmp(reinterpret_cast<Errors*>(c->err)->jump, 1);
  };
  errors.manager.output_message = [](j_common_ptr) {};  // quiet: only the count matters
  if (setjmp(errors.jump) != 0) {
    jpeg_destroy_decompress(&info);
    return -1;
  }
  jpeg_CreateDecompress(&info, JPEG_LIB_VERSION, sizeof info);
  jpeg_mem_src(&info, jpeg.data(), jpeg.size());
  jpeg_read_header(&info, TRUE);
  jpeg_start_decompress(&info);
  row.resize(size_t{info.output_width} * static_cast<size_t>(info.output_components));
  while (info.output_scanline < info.output_height) {
    JSAMPROW rows[1] = {row.data()};
    jpeg_read_scanlines(&info, rows, 1);
  }
  jpeg_finish_decompress(&info);
  const int warnings = static_cast<int>(errors.manager.num_warnings);
  jpeg_destroy_decompress(&info);
  return warnings;
}

// Issue 34: a JPEG libjpeg reports as corrupt is refused, never decoded to other pixels (49
// of 200 single-byte flips of a corridor image were). Every byte flip of one image in turn:
// the loader refuses exactly the files libjpeg warns about or gives up on, names libjpeg's
// reason, and what it decodes it decodes as stb_image always did.
TEST(ImageIoBad, AJpegLibjpegFindsCorruptIsRefused) {
  const std::vector<uint8_t> jpeg = test::read_file(corridor_image("ref", 10));
  ASSERT_EQ(libjpeg_warnings(jpeg), 0);
  const LoadedImage clean = decode_gray(jpeg, "clean.jpg");
  ASSERT_TRUE(clean.ok()) << clean.error();
  int corrupt = 0, refused_by_libjpeg = 0;
  for (size_t at = 2; at < jpeg.size(); at += 3) {
    std::vector<uint8_t> bytes = jpeg;
    bytes[at] ^= 0xFF;
    const int warnings = libjpeg_warnings(bytes);
    const LoadedImage result = decode_gray(bytes, "flip.jpg");
    if (warnings != 0) {
      ++corrupt;
      ASSERT_FALSE(result.ok()) << "byte " << at << ": libjpeg finds it corrupt, loaded anyway";
      EXPECT_THAT(result.error(), HasSubstr("flip.jpg: "));
      if (result.error().find("corrupt JPEG (libjpeg: ") != std::string::npos) ++refused_by_libjpeg;
    } else if (!result.ok()) {
      // Refused by the structure check before libjpeg saw it (it found nothing wrong): that
      // check's own reasons, never libjpeg's.
      EXPECT_THAT(result.error(), ::testing::Not(HasSubstr("libjpeg")));
    }
  }
  EXPECT_GT(corrupt, 100);  // the flips the oracle calls corrupt
  EXPECT_GT(refused_by_libjpeg, 0);
  // A valid file's pixels are stb_image's, as before the check.
  const LoadedImage again = load_gray(corridor_image("ref", 10));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again.value().pixels, clean.value().pixels);
}

// ---- PNG through libpng: every checksum verified, the pixels of valid files unchanged ----
// (issue 17, class 4: a PNG with bad chunk CRCs or a bad zlib Adler-32 loaded with changed
// pixels.)

namespace tp = test_png;

// A PNG written by the project's writer (save_png), as bytes.
std::vector<uint8_t> project_png(const TempDir& dir, const GrayImage& image) {
  std::string error;
  EXPECT_TRUE(save_png(dir.file("project.png"), image, &error)) << error;
  return test::read_file(dir.file("project.png"));
}

tp::Chunk find_chunk(const std::vector<uint8_t>& png, const std::string& type, size_t* index) {
  const std::vector<tp::Chunk> list = tp::chunks(png);
  for (size_t i = 0; i < list.size(); ++i) {
    if (list[i].type == type) {
      if (index != nullptr) *index = i;
      return list[i];
    }
  }
  ADD_FAILURE() << "no " << type << " chunk";
  return tp::Chunk{};
}

// The data of the zlib stream `z` inflated without its header and Adler-32 (raw deflate), so
// a change the Adler-32 would catch still inflates. False if the deflate data is invalid.
bool inflate_raw(const std::vector<uint8_t>& z, std::vector<uint8_t>* out) {
  if (z.size() < 6) return false;
  z_stream s{};
  if (inflateInit2(&s, -15) != Z_OK) return false;
  std::vector<uint8_t> in(z.begin() + 2, z.end() - 4);
  s.next_in = in.data();
  s.avail_in = static_cast<uInt>(in.size());
  out->clear();
  int ret = Z_OK;
  uint8_t buffer[4096];
  while (ret == Z_OK) {
    s.next_out = buffer;
    s.avail_out = sizeof buffer;
    ret = inflate(&s, Z_NO_FLUSH);
    out->insert(out->end(), buffer, buffer + (sizeof buffer - s.avail_out));
    if (ret == Z_BUF_ERROR && s.avail_in == 0) break;
  }
  inflateEnd(&s);
  return ret == Z_STREAM_END;
}

LoadedImage load_bytes(const TempDir& dir, const std::string& name,
                       const std::vector<uint8_t>& bytes) {
  write_file(dir.file(name), bytes);
  return load_gray(dir.file(name));
}

// Every colour type, bit depth, palette, tRNS and interlacing decodes to the pixels stb_image's
// path gave (the loader before libpng) and to the grey levels computed from the samples.
TEST(ImageIoPng, EveryKindDecodesAsStbDidAndAsItsSamples) {
  const int types[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                       PNG_COLOR_TYPE_RGB_ALPHA, PNG_COLOR_TYPE_PALETTE};
  const uint32_t sizes[][2] = {{1, 1}, {7, 5}, {33, 17}};
  int files = 0;
  uint32_t seed = 1;
  for (const int type : types) {
    const bool can_trns = type != PNG_COLOR_TYPE_GRAY_ALPHA && type != PNG_COLOR_TYPE_RGB_ALPHA;
    for (const int depth : tp::depths_of(type)) {
      for (const bool interlaced : {false, true}) {
        for (const bool trns : {false, true}) {
          if (trns && !can_trns) continue;
          for (const auto& size : sizes) {
            const tp::Spec spec =
                tp::make_spec(type, depth, interlaced, size[0], size[1], seed++, trns);
            const std::string what = "colour type " + std::to_string(type) + ", " +
                                     std::to_string(depth) + " bits, " +
                                     (interlaced ? "interlaced, " : "") + (trns ? "tRNS, " : "") +
                                     std::to_string(size[0]) + "x" + std::to_string(size[1]);
            const std::vector<uint8_t> bytes = tp::write(spec);
            ASSERT_FALSE(bytes.empty()) << what;
            const LoadedImage image = decode_gray(bytes, "kind.png");
            ASSERT_TRUE(image.ok()) << what << ": " << image.error();
            EXPECT_EQ(image.value().width, static_cast<int>(size[0])) << what;
            EXPECT_EQ(image.value().height, static_cast<int>(size[1])) << what;
            EXPECT_EQ(image.value().pixels, tp::expected_gray(spec)) << what;
            int width = 0;
            int height = 0;
            std::vector<uint8_t> stb;
            ASSERT_TRUE(tp::stb_gray(bytes, &width, &height, &stb)) << what;
            EXPECT_EQ(stb, image.value().pixels) << what;
            ++files;
          }
        }
      }
    }
  }
  // grey 5 depths x 2 x 2 tRNS, grey+alpha 2 x 2, RGB 2 x 2 x 2, RGBA 2 x 2, palette 4 x 2 x 2;
  // three sizes each.
  EXPECT_EQ(files, (20 + 4 + 8 + 4 + 16) * 3);
}

// The project's writer (save_png: stb_image_write) writes correct chunk CRCs and Adler-32: its
// files pass the checks, at several sizes.
TEST(ImageIoPng, ProjectWriterWritesValidChecksums) {
  TempDir dir;
  for (const auto& size : {std::pair<int, int>{1, 1}, {7, 5}, {300, 200}}) {
    const GrayImage image = make_image(size.first, size.second);
    const std::vector<uint8_t> bytes = project_png(dir, image);
    for (const tp::Chunk& c : tp::chunks(bytes)) {
      EXPECT_EQ(tp::be32(bytes.data() + c.crc()), tp::chunk_crc(bytes, c)) << c.type;
    }
    const tp::Chunk idat = find_chunk(bytes, "IDAT", nullptr);
    std::vector<uint8_t> raw(image.pixels.size() + static_cast<size_t>(image.height));
    uLongf raw_size = raw.size();
    EXPECT_EQ(uncompress(raw.data(), &raw_size, bytes.data() + idat.data(), idat.length), Z_OK);
    EXPECT_EQ(raw_size, raw.size());
    const LoadedImage back = decode_gray(bytes, "project.png");
    ASSERT_TRUE(back.ok()) << back.error();
    EXPECT_EQ(back.value().pixels, image.pixels);
  }
}

// Metadata chunks are skipped as stb_image skips them (even when libpng would call their
// contents invalid), but their CRC is checked, before and after the image data.
TEST(ImageIoPng, AncillaryChunksAreSkippedButTheirCrcIsChecked) {
  TempDir dir;
  const GrayImage image = make_image(6, 4);
  const std::vector<uint8_t> good = project_png(dir, image);
  size_t idat = 0;
  find_chunk(good, "IDAT", &idat);

  std::vector<uint8_t> text = good;
  tp::insert_chunk(&text, idat, "tEXt", {'k', 'e', 'y', 0, 'v', 'a', 'l'});
  tp::insert_chunk(&text, idat, "gAMA", {1, 2, 3});   // invalid length: libpng would refuse it
  tp::insert_chunk(&text, idat + 3, "prVt", {9, 9});  // unknown ancillary, after IDAT
  const LoadedImage loaded = load_bytes(dir, "meta.png", text);
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  EXPECT_EQ(loaded.value().pixels, image.pixels);

  const std::vector<tp::Chunk> list = tp::chunks(text);
  for (const size_t i : {idat, idat + 1, idat + 3}) {
    std::vector<uint8_t> bad = text;
    bad[list[i].crc()] ^= 0x01;
    const LoadedImage result = load_bytes(dir, "meta_bad.png", bad);
    EXPECT_FALSE(result.ok()) << list[i].type;
    EXPECT_EQ(result.error(),
              dir.file("meta_bad.png") + ": not a valid PNG: " + list[i].type + ": CRC error");
  }

  // An unknown critical chunk is an error, as in stb_image.
  std::vector<uint8_t> critical = good;
  tp::insert_chunk(&critical, idat, "CRIT", {1});
  const LoadedImage crit = load_bytes(dir, "crit.png", critical);
  EXPECT_FALSE(crit.ok());
  EXPECT_THAT(crit.error(), HasSubstr(dir.file("crit.png") + ": not a valid PNG: CRIT: "));
}

// One byte changed inside IHDR, IDAT or IEND of a file from the project's writer.
TEST(ImageIoPngBad, FlippedByteInIhdrIdatIendIsAnErrorNamingTheFile) {
  TempDir dir;
  const std::vector<uint8_t> good = project_png(dir, make_image(9, 7));
  const std::string path = dir.file("flipped.png");
  const std::string invalid = path + ": not a valid PNG: ";
  {
    // The interlace method (0 -> 1): the container walk accepts it, the CRC does not.
    std::vector<uint8_t> bytes = good;
    bytes[find_chunk(good, "IHDR", nullptr).data() + 12] ^= 0x01;
    const LoadedImage result = load_bytes(dir, "flipped.png", bytes);
    EXPECT_FALSE(result.ok());
    EXPECT_EQ(result.error(), invalid + "IHDR: CRC error");
  }
  {
    // A byte in the middle of the image data: the inflater or the CRC stops it.
    const tp::Chunk idat = find_chunk(good, "IDAT", nullptr);
    std::vector<uint8_t> bytes = good;
    bytes[idat.data() + idat.length / 2] ^= 0x01;
    const LoadedImage result = load_bytes(dir, "flipped.png", bytes);
    EXPECT_FALSE(result.ok());
    EXPECT_THAT(result.error(), HasSubstr(invalid + "IDAT: "));
  }
  // IEND has no data: its CRC; and the CRC of the others.
  for (const char* type : {"IHDR", "IDAT", "IEND"}) {
    std::vector<uint8_t> bytes = good;
    bytes[find_chunk(good, type, nullptr).crc() + 2] ^= 0x40;
    const LoadedImage result = load_bytes(dir, "flipped.png", bytes);
    EXPECT_FALSE(result.ok()) << type;
    EXPECT_EQ(result.error(), invalid + type + ": CRC error");
  }
}

// Any single byte changed anywhere in a valid file (signature, lengths, types, data, CRCs),
// from the project's writer and from libpng (16-bit RGBA, interlaced; palette with tRNS).
TEST(ImageIoPngBad, EveryChangedByteIsAnError) {
  TempDir dir;
  const std::vector<std::vector<uint8_t>> files = {
      project_png(dir, make_image(9, 7)),
      tp::write(tp::make_spec(PNG_COLOR_TYPE_RGB_ALPHA, 16, true, 5, 4, 7, false)),
      tp::write(tp::make_spec(PNG_COLOR_TYPE_PALETTE, 4, false, 6, 3, 8, true)),
  };
  for (const std::vector<uint8_t>& good : files) {
    ASSERT_TRUE(decode_gray(good, "good.png").ok());
    for (size_t pos = 0; pos < good.size(); ++pos) {
      for (const uint8_t change : {uint8_t{0x01}, uint8_t{0x80}, uint8_t{0xff}}) {
        std::vector<uint8_t> bytes = good;
        bytes[pos] ^= change;
        const LoadedImage result = decode_gray(bytes, "changed.png");
        EXPECT_FALSE(result.ok()) << "byte " << pos << " ^ " << int{change};
        EXPECT_THAT(result.error(), HasSubstr("changed.png: ")) << "byte " << pos;
      }
    }
  }
}

// A change inside the zlib stream with the chunk CRC recomputed: the deflate data still
// inflates to the right amount of image data, only with a changed pixel; only the Adler-32
// catches it. stb_image (the loader before libpng) returns the changed pixels.
TEST(ImageIoPngBad, ZlibChangeWithValidCrcIsCaughtByTheAdler32) {
  TempDir dir;
  const GrayImage image = make_image(16, 8);
  const std::vector<uint8_t> good = project_png(dir, image);
  size_t idat = 0;
  const tp::Chunk c = find_chunk(good, "IDAT", &idat);
  const std::vector<uint8_t> z(good.begin() + static_cast<ptrdiff_t>(c.data()),
                               good.begin() + static_cast<ptrdiff_t>(c.crc()));
  std::vector<uint8_t> raw_good;
  ASSERT_TRUE(inflate_raw(z, &raw_good));
  const size_t stride = static_cast<size_t>(image.width) + 1;
  ASSERT_EQ(raw_good.size(), stride * static_cast<size_t>(image.height));

  // The first bit flip of the deflate data that keeps it valid, the same size and every row's
  // filter type valid.
  std::vector<uint8_t> changed;
  for (size_t pos = 2; pos + 4 < z.size() && changed.empty(); ++pos) {
    for (int bit = 0; bit < 8 && changed.empty(); ++bit) {
      std::vector<uint8_t> m = z;
      m[pos] = static_cast<uint8_t>(m[pos] ^ (1u << bit));
      std::vector<uint8_t> raw;
      if (!inflate_raw(m, &raw) || raw.size() != raw_good.size() || raw == raw_good) continue;
      bool filters_valid = true;
      for (size_t row = 0; row < raw.size(); row += stride)
        filters_valid = filters_valid && raw[row] <= 4;
      if (filters_valid) changed = m;
    }
  }
  ASSERT_FALSE(changed.empty());
  std::vector<uint8_t> bytes = good;
  tp::replace_chunk_data(&bytes, idat, changed);
  ASSERT_EQ(bytes.size(), good.size());
  const tp::Chunk fixed = find_chunk(bytes, "IDAT", nullptr);
  EXPECT_EQ(tp::be32(bytes.data() + fixed.crc()), tp::chunk_crc(bytes, fixed));

  int width = 0;
  int height = 0;
  std::vector<uint8_t> stb;
  ASSERT_TRUE(tp::stb_gray(bytes, &width, &height, &stb));
  EXPECT_NE(stb, image.pixels);

  const LoadedImage result = load_bytes(dir, "adler.png", bytes);
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(result.error(),
            dir.file("adler.png") + ": not a valid PNG: IDAT: incorrect data check");

  // The Adler-32 itself changed (CRC recomputed).
  std::vector<uint8_t> trailer = z;
  trailer[z.size() - 2] ^= 0x10;
  bytes = good;
  tp::replace_chunk_data(&bytes, idat, trailer);
  const LoadedImage result2 = load_bytes(dir, "adler2.png", bytes);
  EXPECT_FALSE(result2.ok());
  EXPECT_EQ(result2.error(),
            dir.file("adler2.png") + ": not a valid PNG: IDAT: incorrect data check");
}

// Bytes after the end of the zlib stream inside the IDAT chunk (CRC valid).
TEST(ImageIoPngBad, TrailingGarbageInsideIdatIsAnError) {
  TempDir dir;
  const std::vector<uint8_t> good = project_png(dir, make_image(16, 8));
  size_t idat = 0;
  const tp::Chunk c = find_chunk(good, "IDAT", &idat);
  std::vector<uint8_t> z(good.begin() + static_cast<ptrdiff_t>(c.data()),
                         good.begin() + static_cast<ptrdiff_t>(c.crc()));
  z.insert(z.end(), {0xde, 0xad, 0xbe, 0xef});
  std::vector<uint8_t> bytes = good;
  tp::replace_chunk_data(&bytes, idat, z);
  const LoadedImage result = load_bytes(dir, "garbage.png", bytes);
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(result.error(),
            dir.file("garbage.png") + ": not a valid PNG: IDAT: Extra compressed data");
}

// IHDR fields libpng refuses, with the CRC recomputed so that libpng's check is what stops
// them.
TEST(ImageIoPngBad, BadIhdrWithValidCrcIsAnError) {
  TempDir dir;
  const std::vector<uint8_t> good = project_png(dir, make_image(5, 3));
  size_t ihdr = 0;
  const tp::Chunk c = find_chunk(good, "IHDR", &ihdr);
  const std::vector<uint8_t> fields(good.begin() + static_cast<ptrdiff_t>(c.data()),
                                    good.begin() + static_cast<ptrdiff_t>(c.crc()));
  // Bytes 8..12 of IHDR: bit depth, colour type, compression, filter and interlace methods.
  struct Case {
    uint8_t depth;
    uint8_t colour_type;
    size_t offset;  // then one more field set to 1 or 2
    uint8_t value;
    const char* detail;
  };
  const Case cases[] = {{3, 0, 12, 0, "Invalid bit depth in IHDR"},
                        {8, 5, 12, 0, "Invalid color type in IHDR"},
                        {4, 2, 12, 0, "Invalid color type/bit depth combination in IHDR"},
                        {8, 0, 10, 1, "Unknown compression method in IHDR"},
                        {8, 0, 11, 1, "Unknown filter method in IHDR"},
                        {8, 0, 12, 2, "Unknown interlace method in IHDR"}};
  for (const Case& k : cases) {
    std::vector<uint8_t> data = fields;
    data.at(8) = k.depth;
    data.at(9) = k.colour_type;
    data.at(k.offset) = k.value;
    std::vector<uint8_t> bytes = good;
    tp::replace_chunk_data(&bytes, ihdr, data);
    const LoadedImage result = load_bytes(dir, "ihdr.png", bytes);
    EXPECT_FALSE(result.ok()) << k.detail;
    EXPECT_EQ(result.error(),
              dir.file("ihdr.png") + ": not a valid PNG: Invalid IHDR data (" + k.detail + ")");
  }
}

// A palette index past the end of the palette (stb_image read whatever followed the palette;
// libpng's own check misses it when expanding the palette).
TEST(ImageIoPngBad, PaletteIndexBeyondThePaletteIsAnError) {
  tp::Spec spec = tp::make_spec(PNG_COLOR_TYPE_PALETTE, 2, false, 4, 2, 3, false);
  spec.palette.resize(4, png_color{1, 2, 3});
  spec.samples.assign(8, 1);
  spec.samples[5] = 3;
  std::vector<uint8_t> bytes = tp::write(spec);
  ASSERT_TRUE(decode_gray(bytes, "palette.png").ok());
  size_t plte = 0;
  const tp::Chunk c = find_chunk(bytes, "PLTE", &plte);
  ASSERT_EQ(c.length, 12u);
  tp::replace_chunk_data(
      &bytes, plte,
      std::vector<uint8_t>(bytes.begin() + static_cast<ptrdiff_t>(c.data()),
                           bytes.begin() + static_cast<ptrdiff_t>(c.data() + 9)));
  const LoadedImage result = decode_gray(bytes, "palette.png");
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(result.error(),
            "palette.png: not a valid PNG: a palette index is past the end of the 3-entry palette");
}

// The zlib stream cut at every length inside a well-formed IDAT chunk (CRC valid), and whole
// libpng-written files cut at every length: always an error naming the file, never a crash.
TEST(ImageIoPngBad, TruncatedAtEveryLengthIsAnError) {
  TempDir dir;
  const std::vector<uint8_t> good = project_png(dir, make_image(16, 8));
  size_t idat = 0;
  const tp::Chunk c = find_chunk(good, "IDAT", &idat);
  for (uint32_t n = 0; n < c.length; ++n) {
    std::vector<uint8_t> bytes = good;
    tp::replace_chunk_data(
        &bytes, idat,
        std::vector<uint8_t>(bytes.begin() + static_cast<ptrdiff_t>(c.data()),
                             bytes.begin() + static_cast<ptrdiff_t>(c.data() + n)));
    const LoadedImage result = decode_gray(bytes, "short_idat.png");
    EXPECT_FALSE(result.ok()) << "zlib stream cut at " << n;
    EXPECT_THAT(result.error(), HasSubstr("short_idat.png: not a valid PNG: ")) << n;
  }
  for (const tp::Spec& spec : {tp::make_spec(PNG_COLOR_TYPE_RGB_ALPHA, 16, true, 9, 6, 4, false),
                               tp::make_spec(PNG_COLOR_TYPE_PALETTE, 1, true, 17, 3, 5, true)}) {
    const std::vector<uint8_t> file = tp::write(spec);
    ASSERT_TRUE(decode_gray(file, "cut.png").ok());
    for (size_t n = 0; n < file.size(); ++n) {
      const LoadedImage result = decode_gray(
          std::vector<uint8_t>(file.begin(), file.begin() + static_cast<ptrdiff_t>(n)), "cut.png");
      EXPECT_FALSE(result.ok()) << "cut at " << n;
      EXPECT_THAT(result.error(), HasSubstr("cut.png: ")) << n;
    }
  }
}

}  // namespace
}  // namespace seqslam::tools
