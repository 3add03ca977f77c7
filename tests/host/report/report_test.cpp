// The HTML report (seqslam_tools/report.h) on synthetic evaluations: structure, images, charts,
// escaping, number formats, edge cases and errors. tests/host/report/browser_test.sh checks
// the same pages in a browser.
#include <gtest/gtest.h>
#include <stb_image.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "seqslam_tools/report.h"
#include "synthetic.h"

namespace seqslam::tools::test {
namespace {

std::string render(const Synthetic& s, ReportOptions options) {
  const Outcome<std::string> html = render_report(s.runs(), s.library, s.query, options);
  EXPECT_TRUE(html.ok()) << html.error();
  return html.value();
}
std::string render(const Synthetic& s) {
  return render(s, s.options());
}

std::vector<uint8_t> base64_decode(const std::string& text) {
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (const char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue;  // '=' padding
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>((acc >> bits) & 0xff));
    }
  }
  return out;
}

struct DecodedImage {
  std::string id;
  int declared_width = 0;
  int declared_height = 0;
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<uint8_t> rgb;  // 3 channels
  bool decoded = false;
};

// The value of attribute `name` in the tag text `tag` ("" when absent). No std::regex: it
// recurses per character and overflows the stack on long data URIs.
std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const size_t begin = tag.find(key);
  if (begin == std::string::npos) return "";
  const size_t value = begin + key.size();
  return tag.substr(value, tag.find('"', value) - value);
}

// Every <img> of the page, its data URI decoded with stb_image.
std::vector<DecodedImage> images(const std::string& html) {
  std::vector<DecodedImage> out;
  const std::string prefix = "data:image/png;base64,";
  for (size_t pos = html.find("<img "); pos != std::string::npos;
       pos = html.find("<img ", pos + 1)) {
    const std::string tag = html.substr(pos, html.find('>', pos) - pos);
    DecodedImage d;
    d.id = attribute(tag, "id");
    const std::string w = attribute(tag, "width");
    const std::string h = attribute(tag, "height");
    d.declared_width = w.empty() ? -1 : std::stoi(w);
    d.declared_height = h.empty() ? -1 : std::stoi(h);
    const std::string src = attribute(tag, "src");
    if (src.rfind(prefix, 0) == 0) {
      const std::vector<uint8_t> png = base64_decode(src.substr(prefix.size()));
      stbi_uc* pixels = stbi_load_from_memory(png.data(), static_cast<int>(png.size()), &d.width,
                                              &d.height, &d.channels, 3);
      if (pixels != nullptr) {
        d.decoded = true;
        d.rgb.assign(pixels,
                     pixels + static_cast<size_t>(d.width) * static_cast<size_t>(d.height) * 3);
        stbi_image_free(pixels);
      }
    }
    out.push_back(std::move(d));
  }
  return out;
}

const DecodedImage* find_image(const std::vector<DecodedImage>& all, const std::string& id) {
  for (const DecodedImage& d : all) {
    if (d.id == id) return &d;
  }
  return nullptr;
}

std::array<int, 3> pixel(const DecodedImage& d, int x, int y) {
  const size_t i =
      (static_cast<size_t>(y) * static_cast<size_t>(d.width) + static_cast<size_t>(x)) * 3;
  return {d.rgb[i], d.rgb[i + 1], d.rgb[i + 2]};
}

// Each <svg>...</svg> of the page: tags balanced and properly nested, attributes quoted in
// pairs, no NaN or infinity in an attribute. Returns "" or what is wrong.
std::string check_svgs(const std::string& html, size_t* count) {
  *count = 0;
  size_t pos = 0;
  while ((pos = html.find("<svg", pos)) != std::string::npos) {
    const size_t end = html.find("</svg>", pos);
    if (end == std::string::npos) return "unterminated <svg> at " + std::to_string(pos);
    const std::string svg = html.substr(pos, end + 6 - pos);
    std::vector<std::string> stack;
    size_t i = 0;
    while ((i = svg.find('<', i)) != std::string::npos) {
      const size_t close = svg.find('>', i);
      if (close == std::string::npos) return "unclosed tag in svg at " + std::to_string(pos);
      const std::string tag = svg.substr(i + 1, close - i - 1);
      if (std::count(tag.begin(), tag.end(), '"') % 2 != 0) return "odd quotes in <" + tag + ">";
      std::string lower = tag;
      for (char& ch : lower)
        ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos) {
        return "non-finite number in <" + tag + ">";
      }
      if (tag.empty()) return "empty tag";
      if (tag[0] == '/') {
        const std::string name = tag.substr(1);
        if (stack.empty() || stack.back() != name) {
          return "</" + name + "> closes <" + (stack.empty() ? "" : stack.back()) + ">";
        }
        stack.pop_back();
      } else if (tag.back() != '/') {
        stack.push_back(tag.substr(0, tag.find_first_of(" \t\n")));
      }
      i = close + 1;
    }
    if (!stack.empty()) return "unclosed <" + stack.back() + "> in svg at " + std::to_string(pos);
    ++*count;
    pos = end;
  }
  return "";
}

size_t occurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t i = text.find(what); i != std::string::npos; i = text.find(what, i + 1))
    ++n;
  return n;
}

// The text of the section with this id.
std::string section(const std::string& html, const std::string& id) {
  const size_t begin = html.find("<section id=\"" + id + "\"");
  if (begin == std::string::npos) return "";
  return html.substr(begin, html.find("</section>", begin) - begin);
}

// The <svg> with this id.
std::string svg(const std::string& html, const std::string& id) {
  const size_t begin = html.find("<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"" + id + "\"");
  if (begin == std::string::npos) return "";
  return html.substr(begin, html.find("</svg>", begin) - begin);
}

const char* const kSections[] = {"sec-summary", "sec-pr",           "sec-matrices",
                                 "sec-time",    "sec-trajectories", "sec-pairs"};

TEST(Report, HasEverySectionAndIsSelfContained) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  for (const char* id : kSections)
    EXPECT_FALSE(section(html, id).empty()) << id;
  EXPECT_NE(html.find("<pre id=\"selftest\" hidden></pre>"), std::string::npos);
  EXPECT_NE(html.find("location.hash !== '#selftest'"), std::string::npos);
  // Nothing fetched from elsewhere: no external scripts, styles, images or links.
  for (const char* bad :
       {"src=\"http", "href=\"http", "url(http", "<link", "src=\"//", "@import"}) {
    EXPECT_EQ(html.find(bad), std::string::npos) << bad;
  }
  EXPECT_EQ(occurrences(html, "<script"), 1u);
}

TEST(Report, EveryImageDecodesToItsDeclaredSize) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  const std::vector<DecodedImage> all = images(html);
  ASSERT_GE(all.size(), 5u);
  for (const DecodedImage& d : all) {
    ASSERT_TRUE(d.decoded) << d.id;
    EXPECT_EQ(d.width, d.declared_width) << d.id;
    EXPECT_EQ(d.height, d.declared_height) << d.id;
  }
  // 60 x 50 places: enlarged 10 times (floor(640 / 60)).
  const DecodedImage* diff = find_image(all, "img-differences");
  const DecodedImage* costs = find_image(all, "img-costs");
  ASSERT_NE(diff, nullptr);
  ASSERT_NE(costs, nullptr);
  EXPECT_EQ(diff->width, 600);
  EXPECT_EQ(diff->height, 500);
  EXPECT_EQ(costs->width, 600);
  EXPECT_EQ(costs->height, 500);
  // Image pairs: 32x16 enlarged 8 times.
  size_t pairs = 0;
  for (const DecodedImage& d : all) {
    if (d.id.rfind("pair-", 0) != 0) continue;
    ++pairs;
    EXPECT_EQ(d.width, 256) << d.id;
    EXPECT_EQ(d.height, 128) << d.id;
    EXPECT_EQ(d.channels, 1) << d.id;  // grey PNG
  }
  EXPECT_GE(pairs, 6u);
}

TEST(Report, HeatMapsAreOrientedAndColoured) {
  const Synthetic s = make_synthetic({});
  const std::vector<DecodedImage> all = images(render(s));
  const DecodedImage& diff = *find_image(all, "img-differences");
  const DecodedImage& costs = *find_image(all, "img-costs");
  // Query 20 (row 20, 10 px per place) is most similar to library 25: the darkest viridis
  // colour (the matrix's minimum); library 55 is far: bright (viridis' green rises).
  const int y = 20 * 10 + 5;
  EXPECT_EQ(pixel(diff, 25 * 10 + 5, y), (std::array<int, 3>{68, 1, 84}));
  EXPECT_GT(pixel(diff, 55 * 10 + 5, y)[1], 200);
  EXPECT_GT(pixel(diff, 24 * 10 + 5, y)[1], 1);
  // Sequence costs: none (NaN, grey) before query S-1 = 9, then as the differences.
  EXPECT_EQ(pixel(costs, 305, 8 * 10 + 5), (std::array<int, 3>{160, 160, 160}));
  EXPECT_EQ(pixel(costs, 25 * 10 + 5, y), (std::array<int, 3>{68, 1, 84}));
}

TEST(Report, ChartsAreWellFormed) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  size_t count = 0;
  EXPECT_EQ(check_svgs(html, &count), "");
  EXPECT_EQ(occurrences(html, "<svg"), occurrences(html, "</svg>"));
  for (const char* id :
       {"svg-differences", "svg-costs", "svg-pr", "svg-threshold", "svg-time-0", "svg-confidence-0",
        "svg-time-1", "svg-confidence-1", "svg-trajectories"}) {
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  }
  EXPECT_GE(count, 9u);
  // The matches are drawn: one marker per candidate on each heat map, accepted filled.
  const std::string matrices = svg(html, "svg-differences") + svg(html, "svg-costs");
  size_t candidates = 0;
  for (const QueryResult& m : s.first.matches)
    candidates += m.library >= 0 ? 1 : 0;
  EXPECT_GE(occurrences(matrices, "<circle"), 2 * candidates);
  EXPECT_NE(matrices.find("fill=\"#d62728\""), std::string::npos);  // accepted wrong
  EXPECT_NE(matrices.find("fill=\"#2ca02c\""), std::string::npos);  // accepted correct
  // The ground truth bands.
  EXPECT_NE(matrices.find("fill-opacity=\"0.35\""), std::string::npos);
  // PR: one curve per run, the thresholds marked.
  const std::string pr = section(html, "sec-pr");
  EXPECT_GE(occurrences(pr, "<polyline"), 2u + 4u);
  EXPECT_NE(pr.find("threshold 0.85"), std::string::npos);
  EXPECT_NE(pr.find("threshold 0.9"), std::string::npos);
  // Trajectories: four tracks and the wrong matches joined.
  const std::string traj = section(html, "sec-trajectories");
  EXPECT_EQ(occurrences(traj, "<polyline"), 4u);
  EXPECT_NE(traj.find("<g stroke=\"#d62728\" stroke-width=\"0.8\"><line"), std::string::npos);
}

TEST(Report, EscapesText) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  EXPECT_EQ(html.find("<he&pn>"), std::string::npos);
  EXPECT_NE(html.find("&lt;he&amp;pn&gt;"), std::string::npos);
  EXPECT_EQ(html.find("<library>"), std::string::npos);
  EXPECT_NE(html.find("sim/noon &amp; lamps/&lt;library&gt;.dream"), std::string::npos);
  EXPECT_NE(html.find("<title>synthetic &quot;report&quot; &lt;test&gt;</title>"),
            std::string::npos);
}

TEST(Report, NumbersAsTheOtherTools) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  const PrSummary& sum = s.first.summary;
  const PrPoint at = sum.at_threshold(0.85);
  char line[256];
  std::snprintf(line, sizeof line,
                "best match correct (top-1, no threshold): %.1f %%; at threshold 0.85: %zu "
                "accepted, precision %.1f %%, recall %.1f %%; recall at 100 %% precision: %.1f "
                "%%; area under the PR curve: %.3f",
                100.0 * sum.top1, at.accepted, 100.0 * at.precision, 100.0 * at.recall,
                100.0 * sum.recall_at_100_precision, sum.auc_pr);
  EXPECT_NE(html.find(line), std::string::npos) << line;
  const std::string summary = section(html, "sec-summary");
  EXPECT_NE(summary.find("<td>10</td>"), std::string::npos);                // S
  EXPECT_NE(summary.find("<td>0.85</td><td>0.9</td>"), std::string::npos);  // thresholds
  EXPECT_NE(summary.find("<td>none</td><td>he-pn</td>"), std::string::npos);
  EXPECT_NE(summary.find("<td>7.5 ms</td>"), std::string::npos);
  EXPECT_NE(summary.find("(from the cache)"), std::string::npos);
  EXPECT_NE(summary.find("100..149 of 250"), std::string::npos);  // the query's source range
  EXPECT_NE(summary.find("32x16"), std::string::npos);
}

TEST(Report, PairsChosenAutomatically) {
  const Synthetic s = make_synthetic({});
  const std::string pairs = section(render(s), "sec-pairs");
  // A wrong match (every 7th query from 14) with its correct place shown next to it.
  EXPECT_NE(pairs.find("id=\"pair-14-correct\""), std::string::npos);
  EXPECT_NE(pairs.find("confidence 0.550, accepted, <b style=\"color:#d62728\">wrong</b>"),
            std::string::npos);
  EXPECT_NE(pairs.find(">correct</b>"), std::string::npos);
  EXPECT_NE(pairs.find("not accepted"), std::string::npos);
  EXPECT_NE(pairs.find("query 14 (source 114)"), std::string::npos);
  EXPECT_NE(pairs.find("&lt;he&amp;pn&gt;: library"), std::string::npos);  // the other run
}

TEST(Report, PairsAsRequested) {
  const Synthetic s = make_synthetic({});
  ReportOptions o = s.options();
  o.pair_queries = {3, 20, 999};
  const std::string pairs = section(render(s, o), "sec-pairs");
  EXPECT_NE(pairs.find("id=\"pair-3-query\""), std::string::npos);
  EXPECT_NE(pairs.find("no match candidate (no full sequence yet)"), std::string::npos);
  EXPECT_NE(pairs.find("id=\"pair-20-match\""), std::string::npos);
  EXPECT_EQ(pairs.find("id=\"pair-21-"), std::string::npos);
  EXPECT_NE(pairs.find("Skipped (beyond the query input): 999"), std::string::npos);
}

TEST(Report, WithoutGroundTruth) {
  SyntheticOptions so;
  so.ground_truth = false;
  const Synthetic s = make_synthetic(so);
  const std::string html = render(s);
  size_t count = 0;
  EXPECT_EQ(check_svgs(html, &count), "");
  EXPECT_NE(section(html, "sec-pr").find("No ground truth"), std::string::npos);
  EXPECT_NE(section(html, "sec-summary").find("<td>n/a</td>"), std::string::npos);
  EXPECT_NE(html.find("no ground truth: no precision or recall."), std::string::npos);
  // Every match drawn as "no ground truth" (orange), none as correct or wrong.
  const std::string matrices = svg(html, "svg-differences");
  EXPECT_NE(matrices.find("fill=\"#ff9800\""), std::string::npos);
  EXPECT_EQ(matrices.find("fill=\"#d62728\""), std::string::npos);
  EXPECT_EQ(matrices.find("fill-opacity=\"0.35\""), std::string::npos);
  for (const DecodedImage& d : images(html))
    EXPECT_TRUE(d.decoded) << d.id;
  EXPECT_NE(section(html, "sec-pairs").find("id=\"pair-"), std::string::npos);
}

TEST(Report, WithoutPoses) {
  SyntheticOptions so;
  so.poses = false;
  const Synthetic s = make_synthetic(so);
  const std::string html = render(s);
  const std::string traj = section(html, "sec-trajectories");
  EXPECT_NE(traj.find("hold no poses"), std::string::npos);
  EXPECT_EQ(traj.find("<svg"), std::string::npos);
  size_t count = 0;
  EXPECT_EQ(check_svgs(html, &count), "");
}

TEST(Report, RunWithoutMatches) {
  SyntheticOptions so;
  so.second_run_empty = true;
  const Synthetic s = make_synthetic(so);
  EXPECT_TRUE(s.second.summary.curve.empty());
  const std::string html = render(s);
  size_t count = 0;
  EXPECT_EQ(check_svgs(html, &count), "");
  EXPECT_NE(section(html, "sec-pairs").find("&lt;he&amp;pn&gt;: no match candidate"),
            std::string::npos);
  EXPECT_NE(html.find("id=\"svg-time-1\""), std::string::npos);
  // The empty run's precision and recall are 0, not NaN.
  EXPECT_NE(section(html, "sec-summary").find("<td>0.0 %</td>"), std::string::npos);
  // Its only chart marks are the axes: no match markers in its time chart.
  const std::string chart = svg(html, "svg-time-1");
  EXPECT_NE(chart.find("<rect"), std::string::npos);
  EXPECT_EQ(chart.find("<circle"), std::string::npos);
}

TEST(Report, SingleQuery) {
  SyntheticOptions so;
  so.queries = 1;
  const Synthetic s = make_synthetic(so);
  const std::string html = render(s);
  size_t count = 0;
  EXPECT_EQ(check_svgs(html, &count), "");
  const std::vector<DecodedImage> all = images(html);
  for (const DecodedImage& d : all)
    EXPECT_TRUE(d.decoded) << d.id;
  // 60 x 1 places: 10 px per place, the single row stretched to 120 px.
  const DecodedImage* diff = find_image(all, "img-differences");
  ASSERT_NE(diff, nullptr);
  EXPECT_EQ(diff->width, 600);
  EXPECT_EQ(diff->height, 120);
  EXPECT_NE(section(html, "sec-pairs").find("No matches to show."), std::string::npos);
}

TEST(Report, LargeMatrixIsReduced) {
  SyntheticOptions so;
  so.library = 2100;
  so.queries = 30;
  so.second_run = false;
  const Synthetic s = make_synthetic(so);
  const std::string html = render(s);
  const std::vector<DecodedImage> all = images(html);
  // 2100 places: 3 per pixel (700 px); 30 queries: 10 pixels, stretched 12 times.
  const DecodedImage* diff = find_image(all, "img-differences");
  ASSERT_NE(diff, nullptr);
  EXPECT_EQ(diff->width, 700);
  EXPECT_EQ(diff->height, 120);
  EXPECT_NE(html.find("each pixel the minimum of 3 x 3 places"), std::string::npos);
  // The matching diagonal survives the reduction: query 15 (block row 5, 12 px each) is
  // closest to library 20 (block 6).
  EXPECT_EQ(pixel(*diff, 6, 5 * 12 + 6), (std::array<int, 3>{68, 1, 84}));
}

TEST(Report, Errors) {
  const Synthetic s = make_synthetic({});
  const ReportOptions o = s.options();
  Outcome<std::string> r = render_report({}, s.library, s.query, o);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error().find("no evaluation"), std::string::npos);

  r = render_report({{"x", nullptr}}, s.library, s.query, o);
  EXPECT_NE(r.error().find("run 0 (x) has no result"), std::string::npos);

  // runs[0] without matrices.
  r = render_report({{"<he&pn>", &s.second}, {"none", &s.first}}, s.library, s.query, o);
  EXPECT_NE(r.error().find("keep_matrices"), std::string::npos) << r.error();

  EvalResult other = s.second;
  other.query_size = 49;
  r = render_report({{"none", &s.first}, {"cut", &other}}, s.library, s.query, o);
  EXPECT_NE(r.error().find("need the same inputs"), std::string::npos) << r.error();

  other = s.second;
  other.matches.pop_back();
  r = render_report({{"none", &s.first}, {"short", &other}}, s.library, s.query, o);
  EXPECT_NE(r.error().find("has 49 results for 50 queries"), std::string::npos) << r.error();

  InputSequence fewer = s.library;
  fewer.images.pop_back();
  r = render_report(s.runs(), fewer, s.query, o);
  EXPECT_NE(r.error().find("59 library images"), std::string::npos) << r.error();
}

TEST(Report, WritesTheFile) {
  const Synthetic s = make_synthetic({});
  const std::string html = render(s);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("seqslam_report_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "report.html").string();
  std::string error;
  ASSERT_TRUE(write_report(path, html, &error)) << error;
  std::string back;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[65536];
    size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0)
      back.append(buffer, n);
    std::fclose(f);
  }
  EXPECT_EQ(back, html);
  EXPECT_FALSE(write_report(dir.string(), html, &error));  // a directory
  EXPECT_NE(error.find(dir.string()), std::string::npos) << error;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace seqslam::tools::test
