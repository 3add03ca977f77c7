// Helper of browser_test.sh:
//   report_sample html OUT.html full|minimal   writes a synthetic report: `full` has two runs,
//       the ground truth and poses; `minimal` has no ground truth, no poses, and a second run
//       without any match candidate;
//   report_sample png-check FILE.png            exits 1 unless FILE is a PNG that is not blank
//       (at least 16 colours, at least 5 % of the pixels not white).
#include <stb_image.h>

#include <cstdio>
#include <cstring>
#include <set>
#include <string>

#include "seqslam_tools/report.h"
#include "synthetic.h"

namespace {

int write_html(const std::string& path, const std::string& variant) {
  using namespace seqslam::tools;
  test::SyntheticOptions so;
  if (variant == "minimal") {
    so.ground_truth = false;
    so.poses = false;
    so.second_run_empty = true;
  } else if (variant != "full") {
    std::fprintf(stderr, "report_sample: unknown variant %s\n", variant.c_str());
    return 2;
  }
  const test::Synthetic s = test::make_synthetic(so);
  const Outcome<std::string> html = render_report(s.runs(), s.library, s.query, s.options());
  if (!html) {
    std::fprintf(stderr, "report_sample: %s\n", html.error().c_str());
    return 1;
  }
  std::string error;
  if (!write_report(path, html.value(), &error)) {
    std::fprintf(stderr, "report_sample: %s\n", error.c_str());
    return 1;
  }
  std::printf("%s: %zu bytes (%s)\n", path.c_str(), html.value().size(), variant.c_str());
  return 0;
}

int check_png(const std::string& path) {
  int w = 0;
  int h = 0;
  int n = 0;
  stbi_uc* pixels = stbi_load(path.c_str(), &w, &h, &n, 3);
  if (pixels == nullptr) {
    std::fprintf(stderr, "report_sample: %s: not a readable PNG\n", path.c_str());
    return 1;
  }
  std::set<uint32_t> colours;
  size_t not_white = 0;
  const size_t count = static_cast<size_t>(w) * static_cast<size_t>(h);
  for (size_t i = 0; i < count; ++i) {
    const stbi_uc* p = pixels + 3 * i;
    colours.insert((uint32_t{p[0]} << 16) | (uint32_t{p[1]} << 8) | p[2]);
    if (p[0] < 250 || p[1] < 250 || p[2] < 250) ++not_white;
  }
  stbi_image_free(pixels);
  const double fraction =
      count == 0 ? 0.0 : static_cast<double>(not_white) / static_cast<double>(count);
  std::printf("%s: %dx%d, %zu colours, %.1f %% not white\n", path.c_str(), w, h, colours.size(),
              100.0 * fraction);
  if (colours.size() < 16 || fraction < 0.05) {
    std::fprintf(stderr, "report_sample: %s: the screenshot looks blank\n", path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "html") == 0) return write_html(argv[2], argv[3]);
  if (argc == 3 && std::strcmp(argv[1], "png-check") == 0) return check_png(argv[2]);
  std::fprintf(stderr, "usage: report_sample html OUT.html full|minimal | png-check FILE.png\n");
  return 2;
}
