// Writes the seed corpus of fuzz_image_loader: valid PNGs of every colour type (libpng's
// writer: bit depths, palette, tRNS, interlacing) and one from the project's writer (save_png),
// a JPEG (grey and colour) and a BMP from stb_image_write, plain and binary PGM/PPM, and
// generator inputs ('G' + parameters, see fuzz_image_loader.cpp).
#include <stb_image_write.h>
#include <stdio.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "png_samples.h"
#include "seqslam_tools/image_io.h"

namespace {

namespace tp = seqslam::test_png;

void save(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

void append(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

std::vector<uint8_t> samples(size_t count, uint32_t seed) {
  std::vector<uint8_t> out(count);
  for (size_t i = 0; i < count; ++i) {
    seed = seed * 1103515245u + 12345u;
    out[i] = static_cast<uint8_t>(seed >> 16);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: make_image_seeds CORPUS_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);

  const int types[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                       PNG_COLOR_TYPE_RGB_ALPHA, PNG_COLOR_TYPE_PALETTE};
  uint32_t seed = 1;
  for (const int type : types) {
    for (const int depth : tp::depths_of(type)) {
      const bool interlaced = (seed % 2) == 0;
      const bool trns = (seed % 3) == 0;
      const std::vector<uint8_t> png =
          tp::write(tp::make_spec(type, depth, interlaced, 5 + seed % 7, 3 + seed % 5, seed, trns));
      if (png.empty()) return 1;
      save(dir + "/png_" + std::to_string(type) + "_" + std::to_string(depth), png);
      ++seed;
    }
  }

  seqslam::tools::GrayImage image;
  image.width = 12;
  image.height = 9;
  image.pixels = samples(size_t{12} * 9, 7);
  std::string error;
  if (!seqslam::tools::save_png(dir + "/project.png", image, &error)) {
    fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }

  std::vector<uint8_t> out;
  const std::vector<uint8_t> grey = samples(size_t{16} * 8, 3);
  const std::vector<uint8_t> rgb = samples(size_t{16} * 8 * 3, 5);
  if (stbi_write_jpg_to_func(append, &out, 16, 8, 1, grey.data(), 90) == 0) return 1;
  save(dir + "/grey.jpg", out);
  out.clear();
  if (stbi_write_jpg_to_func(append, &out, 16, 8, 3, rgb.data(), 75) == 0) return 1;
  save(dir + "/rgb.jpg", out);
  out.clear();
  if (stbi_write_bmp_to_func(append, &out, 7, 3, 3, rgb.data()) == 0) return 1;
  save(dir + "/rgb.bmp", out);

  const std::string pnm[] = {"P2\n# plain\n3 2\n255\n0 128 255\n1 2 3\n",
                             "P3\n2 1\n65535\n65535 0 0 0 0 65535\n",
                             std::string("P5\n2 2\n255\n") + '\x00' + '\x7f' + '\x80' + '\xff',
                             std::string("P6\n1 1\n255\n") + '\x0a' + '\xc8' + '\x1e'};
  for (size_t i = 0; i < 4; ++i)
    save(dir + "/pnm_" + std::to_string(i), std::vector<uint8_t>(pnm[i].begin(), pnm[i].end()));

  // Generator inputs: 'G', colour type, depth, flags, width, height, two seed bytes, the change
  // (two position bytes, burst, four XOR values), then sample values.
  for (uint8_t k = 0; k < 5; ++k) {
    std::vector<uint8_t> g = {'G',
                              k,
                              static_cast<uint8_t>(k * 3),
                              static_cast<uint8_t>(k),
                              static_cast<uint8_t>(4 + k),
                              static_cast<uint8_t>(3 + 2 * k),
                              static_cast<uint8_t>(k * 17),
                              1,
                              static_cast<uint8_t>(40 + 9 * k),
                              0,
                              static_cast<uint8_t>(k),
                              0x01,
                              0x80,
                              0x10,
                              0xff};
    const std::vector<uint8_t> values = samples(24, k);
    g.insert(g.end(), values.begin(), values.end());
    save(dir + "/gen_" + std::to_string(k), g);
  }
  return 0;
}
