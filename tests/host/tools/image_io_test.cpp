#include "seqslam_tools/image_io.h"

#include <stb_image_write.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace seqslam::tools
