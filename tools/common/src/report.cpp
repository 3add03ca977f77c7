// The HTML report of an evaluation (report.h): one function per section, small helpers for
// text, PNG data URIs and SVG charts above them.
#include "seqslam_tools/report.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <functional>
#include <limits>
#include <string_view>
#include <utility>

#include "file_util.h"
#include "html_embed.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::tools {
namespace {

// ---------------------------------------------------------------------------------------
// Text

__attribute__((format(printf, 1, 2))) std::string format(const char* fmt, ...) {
  char buffer[256];
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(buffer, sizeof buffer, fmt, args);
  va_end(args);
  std::string out;
  if (n > 0 && static_cast<size_t>(n) < sizeof buffer) {
    out.assign(buffer, static_cast<size_t>(n));
  } else if (n > 0) {
    out.resize(static_cast<size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), fmt, copy);
    out.resize(static_cast<size_t>(n));
  }
  va_end(copy);
  return out;
}

// Text for HTML content and attribute values.
std::string escape(std::string_view s) {
  return detail::html_escape(s);
}

// The formats of `seqslam results` and seqslam-demo: percentages with one decimal and a space
// before "%", the AUC with three decimals, thresholds as the shortest exact decimal.
std::string percent(double fraction) {
  return format("%.1f %%", 100.0 * fraction);
}
std::string fixed3(double v) {
  return format("%.3f", v);
}
std::string millis(double ms) {
  return format("%.1f ms", ms);
}
std::string num(uint64_t v) {
  return std::to_string(v);
}

// The shortest decimal that reads back (rounded to nearest) as the unsigned fixed-point value
// raw / 2^frac_bits, as `seqslam config show` prints settings.
std::string shortest_fixed(uint64_t raw, unsigned frac_bits) {
  uint64_t scale = 1;
  for (unsigned k = 0; k <= 9; ++k, scale *= 10) {
    const uint64_t scaled = (raw * scale + (uint64_t{1} << (frac_bits - 1))) >> frac_bits;
    const uint64_t back = ((scaled << frac_bits) + scale / 2) / scale;
    if (back == raw || k == 9) {
      std::string text = std::to_string(scaled / scale);
      if (k > 0) {
        std::string frac = std::to_string(scaled % scale);
        frac.insert(0, k - frac.size(), '0');
        text += "." + frac;
      }
      return text;
    }
  }
  return std::to_string(raw);
}

double threshold_of(const EvalResult& r) {
  return to_double(r.config.localiser.sequence.threshold);
}
std::string threshold_text(const EvalResult& r) {
  return shortest_fixed(r.config.localiser.sequence.threshold.raw(), 16);
}

// SVG coordinates: one decimal, never NaN (callers pass finite values; guard anyway).
std::string c1(double v) {
  if (!std::isfinite(v)) v = 0.0;
  return format("%.1f", v);
}

std::string tick_text(double v) {
  if (std::fabs(v) < 1e-12) v = 0.0;
  return format("%g", v);
}

// ---------------------------------------------------------------------------------------
// PNG data URIs

// An 8-bit image with `channels` samples per pixel (1 grey, 3 RGB).
struct Raster {
  int width = 0;
  int height = 0;
  int channels = 1;
  std::vector<uint8_t> pixels;
};

// An <img> with the raster as a PNG data URI, displayed at its own size.
std::string img_tag(const Raster& r, const std::string& id, const std::string& alt,
                    const char* cls) {
  const std::string uri = detail::png_data_uri(r.width, r.height, r.channels, r.pixels);
  if (uri.empty()) {
    return "<p class=\"note\">" + escape(alt) + ": image could not be encoded</p>";
  }
  std::string out = "<img";
  if (!id.empty()) out += " id=\"" + escape(id) + "\"";
  out += format(" class=\"%s\" width=\"%d\" height=\"%d\" alt=\"", cls, r.width, r.height);
  out += escape(alt) + "\" src=\"" + uri + "\">";
  return out;
}

// A grey image enlarged by an integer factor, nearest neighbour.
Raster enlarge(const GrayImage& image, int factor) {
  Raster r;
  r.width = image.width * factor;
  r.height = image.height * factor;
  r.channels = 1;
  r.pixels.resize(static_cast<size_t>(r.width) * static_cast<size_t>(r.height));
  for (int y = 0; y < r.height; ++y) {
    for (int x = 0; x < r.width; ++x) {
      r.pixels[static_cast<size_t>(y) * static_cast<size_t>(r.width) + static_cast<size_t>(x)] =
          image.at(x / factor, y / factor);
    }
  }
  return r;
}

// ---------------------------------------------------------------------------------------
// Colours

struct Rgb {
  uint8_t r, g, b;
};

// Viridis (matplotlib), sampled at nine points and interpolated linearly: perceptually
// uniform, readable in grey and by most colour-blind readers. Dark = low.
constexpr Rgb kViridis[] = {{68, 1, 84},    {71, 45, 123},  {59, 82, 139},
                            {44, 114, 142}, {33, 145, 140}, {40, 174, 128},
                            {94, 201, 98},  {173, 220, 48}, {253, 231, 37}};
constexpr size_t kViridisStops = sizeof kViridis / sizeof kViridis[0];
constexpr Rgb kNanGrey = {160, 160, 160};

Rgb viridis(double t) {
  if (!(t > 0.0)) return kViridis[0];
  if (t >= 1.0) return kViridis[kViridisStops - 1];
  const double pos = t * static_cast<double>(kViridisStops - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - static_cast<double>(i);
  const auto mix = [f](uint8_t a, uint8_t b) {
    return static_cast<uint8_t>(std::lround(a + f * (b - a)));
  };
  return {mix(kViridis[i].r, kViridis[i + 1].r), mix(kViridis[i].g, kViridis[i + 1].g),
          mix(kViridis[i].b, kViridis[i + 1].b)};
}

std::string hex(Rgb c) {
  return format("#%02x%02x%02x", c.r, c.g, c.b);
}

constexpr const char* kCorrectColour = "#2ca02c";
constexpr const char* kWrongColour = "#d62728";
constexpr const char* kUnknownColour = "#ff9800";
// Run colours avoid the status colours (green, red, orange).
constexpr const char* kRunColours[] = {"#1f77b4", "#9467bd", "#17becf", "#8c564b",
                                       "#e377c2", "#7f7f7f", "#bcbd22", "#000000"};

const char* run_colour(size_t i) {
  return kRunColours[i % (sizeof kRunColours / sizeof kRunColours[0])];
}

// ---------------------------------------------------------------------------------------
// Match status

enum class Verdict { kCorrect, kWrong, kUnknown };

Verdict verdict(const EvalResult& r, const QueryResult& m) {
  if (!r.has_ground_truth) return Verdict::kUnknown;
  return m.correct ? Verdict::kCorrect : Verdict::kWrong;
}

const char* verdict_colour(Verdict v) {
  switch (v) {
    case Verdict::kCorrect:
      return kCorrectColour;
    case Verdict::kWrong:
      return kWrongColour;
    case Verdict::kUnknown:
      break;
  }
  return kUnknownColour;
}

const char* verdict_text(Verdict v) {
  switch (v) {
    case Verdict::kCorrect:
      return "correct";
    case Verdict::kWrong:
      return "wrong";
    case Verdict::kUnknown:
      break;
  }
  return "no ground truth";
}

// A match marker: filled = accepted, ring (with a white halo, visible on dark heat maps) = not.
std::string marker(double x, double y, const char* colour, bool accepted, double radius = 3.0) {
  if (accepted) {
    return "<circle cx=\"" + c1(x) + "\" cy=\"" + c1(y) + "\" r=\"" + c1(radius) + "\" fill=\"" +
           colour + "\" stroke=\"#000\" stroke-width=\"0.7\"/>";
  }
  const std::string at = "<circle cx=\"" + c1(x) + "\" cy=\"" + c1(y) + "\" r=\"" + c1(radius) +
                         "\" fill=\"none\" stroke=\"";
  return at + "#fff\" stroke-width=\"2.6\" stroke-opacity=\"0.8\"/>" + at + colour +
         "\" stroke-width=\"1.3\"/>";
}

std::string marker_legend(bool heat_map) {
  const char* bg = heat_map ? "#3b528b" : "#ffffff";
  std::string out = "<div class=\"legend\">";
  const struct {
    const char* colour;
    bool accepted;
    const char* text;
  } items[] = {{kCorrectColour, true, "accepted, correct"},
               {kWrongColour, true, "accepted, wrong"},
               {kCorrectColour, false, "not accepted, would be correct"},
               {kWrongColour, false, "not accepted, wrong"},
               {kUnknownColour, true, "accepted, no ground truth"},
               {kUnknownColour, false, "not accepted, no ground truth"}};
  for (const auto& item : items) {
    out +=
        "<span><svg width=\"14\" height=\"14\" viewBox=\"0 0 14 14\"><rect width=\"14\" "
        "height=\"14\" fill=\"";
    out += bg;
    out += "\"/>" + marker(7, 7, item.colour, item.accepted, 4.0) + "</svg> ";
    out += item.text;
    out += "</span>";
  }
  return out + "</div>";
}

// ---------------------------------------------------------------------------------------
// SVG charts

// About `target` round numbers covering [lo, hi].
std::vector<double> nice_ticks(double lo, double hi, int target = 6) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi <= lo) {
    if (std::isfinite(lo)) ticks.push_back(lo);
    return ticks;
  }
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * mag;
    if (step >= raw) break;
  }
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double v = first; v <= hi + step * 1e-9; v += step)
    ticks.push_back(v);
  return ticks;
}

// A chart's plot area in pixels and the data range it shows. y grows upwards unless y_down.
struct Plot {
  double x0 = 0.0, x1 = 1.0, y0 = 0.0, y1 = 1.0;
  double left = 64.0, top = 14.0, width = 640.0, height = 300.0;
  double right = 16.0, bottom = 46.0;
  bool y_down = false;

  double px(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double py(double y) const {
    const double f = (y - y0) / (y1 - y0);
    return y_down ? top + f * height : top + height - f * height;
  }
  double total_width() const { return left + width + right; }
  double total_height() const { return top + height + bottom; }
};

std::string svg_open(const std::string& id, double width, double height, const std::string& title) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"" + escape(id) +
         "\" class=\"chart\" width=\"" + c1(width) + "\" height=\"" + c1(height) +
         "\" viewBox=\"0 0 " + c1(width) + " " + c1(height) + "\"><title>" + escape(title) +
         "</title>";
}

// Frame, ticks, grid lines and axis labels. map_x / map_y give a tick's pixel position.
std::string axes(const Plot& p, const std::vector<double>& xticks,
                 const std::function<double(double)>& map_x, const std::vector<double>& yticks,
                 const std::function<double(double)>& map_y, const std::string& xlabel,
                 const std::string& ylabel, bool grid) {
  std::string out;
  const double bottom = p.top + p.height;
  for (const double t : xticks) {
    const double x = map_x(t);
    if (grid) {
      out += "<line x1=\"" + c1(x) + "\" y1=\"" + c1(p.top) + "\" x2=\"" + c1(x) + "\" y2=\"" +
             c1(bottom) + "\" class=\"grid\"/>";
    }
    out += "<line x1=\"" + c1(x) + "\" y1=\"" + c1(bottom) + "\" x2=\"" + c1(x) + "\" y2=\"" +
           c1(bottom + 5) + "\" class=\"tick\"/>";
    out += "<text x=\"" + c1(x) + "\" y=\"" + c1(bottom + 17) + "\" class=\"tl\">" + tick_text(t) +
           "</text>";
  }
  for (const double t : yticks) {
    const double y = map_y(t);
    if (grid) {
      out += "<line x1=\"" + c1(p.left) + "\" y1=\"" + c1(y) + "\" x2=\"" + c1(p.left + p.width) +
             "\" y2=\"" + c1(y) + "\" class=\"grid\"/>";
    }
    out += "<line x1=\"" + c1(p.left - 5) + "\" y1=\"" + c1(y) + "\" x2=\"" + c1(p.left) +
           "\" y2=\"" + c1(y) + "\" class=\"tick\"/>";
    out += "<text x=\"" + c1(p.left - 8) + "\" y=\"" + c1(y + 4) + "\" class=\"tl end\">" +
           tick_text(t) + "</text>";
  }
  out += "<rect x=\"" + c1(p.left) + "\" y=\"" + c1(p.top) + "\" width=\"" + c1(p.width) +
         "\" height=\"" + c1(p.height) + "\" class=\"frame\"/>";
  out += "<text x=\"" + c1(p.left + p.width / 2) + "\" y=\"" + c1(bottom + 38) +
         "\" class=\"label\">" + escape(xlabel) + "</text>";
  const double yc = p.top + p.height / 2;
  out += "<text x=\"14\" y=\"" + c1(yc) + "\" class=\"label\" transform=\"rotate(-90 14 " + c1(yc) +
         ")\">" + escape(ylabel) + "</text>";
  return out;
}

std::string plot_axes(const Plot& p, const std::string& xlabel, const std::string& ylabel,
                      bool grid = true) {
  const double ylo = std::min(p.y0, p.y1);
  const double yhi = std::max(p.y0, p.y1);
  return axes(
      p, nice_ticks(p.x0, p.x1), [&p](double x) { return p.px(x); }, nice_ticks(ylo, yhi),
      [&p](double y) { return p.py(y); }, xlabel, ylabel, grid);
}

std::string polyline(const std::vector<std::pair<double, double>>& points, const char* colour,
                     double width, const char* extra = "") {
  if (points.empty()) return "";
  std::string out = "<polyline fill=\"none\" stroke=\"";
  out += colour;
  out += "\" stroke-width=\"" + c1(width) + "\" " + extra + " points=\"";
  for (const auto& [x, y] : points)
    out += c1(x) + "," + c1(y) + " ";
  out.back() = '"';
  return out + "/>";
}

std::string hline(const Plot& p, double y, const char* colour, const std::string& text) {
  const double py = p.py(y);
  return "<line x1=\"" + c1(p.left) + "\" y1=\"" + c1(py) + "\" x2=\"" + c1(p.left + p.width) +
         "\" y2=\"" + c1(py) + "\" stroke=\"" + colour +
         "\" stroke-width=\"1.2\" stroke-dasharray=\"5 3\"/><text x=\"" + c1(p.left + p.width - 4) +
         "\" y=\"" + c1(py - 4) + "\" class=\"tl end\">" + escape(text) + "</text>";
}

std::string vline(const Plot& p, double x, const char* colour, const std::string& text, int row) {
  const double px = p.px(x);
  // The label right of the line, or left of it in the right quarter of the chart.
  const bool left = px > p.left + 0.75 * p.width;
  return "<line x1=\"" + c1(px) + "\" y1=\"" + c1(p.top) + "\" x2=\"" + c1(px) + "\" y2=\"" +
         c1(p.top + p.height) + "\" stroke=\"" + colour +
         "\" stroke-width=\"1.2\" stroke-dasharray=\"5 3\"/><text x=\"" +
         c1(left ? px - 4 : px + 4) + "\" y=\"" + c1(p.top + p.height - 8 - 14 * row) +
         "\" class=\"tl " + (left ? "end" : "start") + "\">" + escape(text) + "</text>";
}

std::string run_legend(const std::vector<ReportRun>& runs, const std::string& suffix = "") {
  std::string out = "<div class=\"legend\">";
  for (size_t i = 0; i < runs.size(); ++i) {
    out += "<span><span class=\"swatch\" style=\"background:";
    out += run_colour(i);
    out += "\"></span> " + escape(runs[i].label) + suffix + "</span>";
  }
  return out + "</div>";
}

// ---------------------------------------------------------------------------------------
// Heat-map scaling (report.h)

struct AxisScale {
  uint32_t cells = 0;  // places on this axis
  uint32_t down = 1;   // places per pixel block
  uint32_t up = 1;     // pixels per block
  uint32_t pixels = 0;

  uint32_t blocks() const { return (cells + down - 1) / down; }
  double lo(uint32_t i) const { return static_cast<double>((i / down) * up); }
  double hi(uint32_t i) const { return static_cast<double>((i / down + 1) * up); }
  double mid(uint32_t i) const { return (lo(i) + hi(i)) / 2.0; }
  // Pixel position of a (fractional) place index, for ticks.
  double at(double i) const { return i / static_cast<double>(down) * up; }
};

struct MatrixScale {
  AxisScale x;  // library
  AxisScale y;  // query
};

MatrixScale matrix_scale(uint32_t library, uint32_t queries) {
  const uint32_t n = std::max(library, queries);
  uint32_t down = 1;
  uint32_t up = 1;
  if (n > 1000) {
    down = (n + 999) / 1000;
  } else {
    up = std::clamp<uint32_t>(640 / n, 1, 16);
  }
  MatrixScale s;
  s.x = {library, down, up, 0};
  s.y = {queries, down, up, 0};
  for (AxisScale* a : {&s.x, &s.y}) {
    a->pixels = a->blocks() * a->up;
    if (a->pixels < 120) {
      const uint32_t k = (120 + a->pixels - 1) / a->pixels;
      a->up *= k;
      a->pixels = a->blocks() * a->up;
    }
  }
  return s;
}

// The colour range of a matrix: its minimum to its 99th percentile (a few huge values must not
// flatten the rest), from at most ~4 million samples.
std::pair<double, double> colour_range(size_t count, const std::function<double(size_t)>& value) {
  std::vector<double> sample;
  const size_t stride = std::max<size_t>(1, count / 4'000'000);
  for (size_t i = 0; i < count; i += stride) {
    const double v = value(i);
    if (std::isfinite(v)) sample.push_back(v);
  }
  if (sample.empty()) return {0.0, 1.0};
  const double lo = *std::min_element(sample.begin(), sample.end());
  const size_t k = (sample.size() - 1) * 99 / 100;
  std::nth_element(sample.begin(), sample.begin() + static_cast<std::ptrdiff_t>(k), sample.end());
  double hi = sample[k];
  if (!(hi > lo)) hi = *std::max_element(sample.begin(), sample.end());
  if (!(hi > lo)) hi = lo + 1.0;
  return {lo, hi};
}

// value(query, library) as a double, NaN = none. Each pixel block shows the minimum of its
// block (NaN only when all of it is NaN).
Raster heat_raster(const MatrixScale& s, const std::function<double(uint32_t, uint32_t)>& value,
                   double lo, double hi) {
  Raster r;
  r.width = static_cast<int>(s.x.pixels);
  r.height = static_cast<int>(s.y.pixels);
  r.channels = 3;
  r.pixels.resize(static_cast<size_t>(s.x.pixels) * s.y.pixels * 3);
  const uint32_t bx = s.x.blocks();
  const uint32_t by = s.y.blocks();
  for (uint32_t row = 0; row < by; ++row) {
    for (uint32_t col = 0; col < bx; ++col) {
      double best = std::numeric_limits<double>::quiet_NaN();
      for (uint32_t q = row * s.y.down; q < std::min(s.y.cells, (row + 1) * s.y.down); ++q) {
        for (uint32_t j = col * s.x.down; j < std::min(s.x.cells, (col + 1) * s.x.down); ++j) {
          const double v = value(q, j);
          if (std::isfinite(v) && !(best <= v)) best = v;
        }
      }
      const Rgb c = std::isfinite(best) ? viridis((best - lo) / (hi - lo)) : kNanGrey;
      for (uint32_t dy = 0; dy < s.y.up; ++dy) {
        const size_t y = static_cast<size_t>(row) * s.y.up + dy;
        for (uint32_t dx = 0; dx < s.x.up; ++dx) {
          const size_t x = static_cast<size_t>(col) * s.x.up + dx;
          uint8_t* p = &r.pixels[(y * s.x.pixels + x) * 3];
          p[0] = c.r;
          p[1] = c.g;
          p[2] = c.b;
        }
      }
    }
  }
  return r;
}

std::string colour_bar(const std::string& id, double lo, double hi, const std::string& label,
                       bool with_nan) {
  const double w = 260;
  std::string out = svg_open(id, w + 150, 44, label);
  out += "<defs><linearGradient id=\"" + escape(id) + "-g\">";
  for (size_t i = 0; i < kViridisStops; ++i) {
    out += format("<stop offset=\"%.3f\" stop-color=\"%s\"/>",
                  static_cast<double>(i) / static_cast<double>(kViridisStops - 1),
                  hex(kViridis[i]).c_str());
  }
  out += "</linearGradient></defs>";
  out += "<rect x=\"4\" y=\"4\" width=\"" + c1(w) + "\" height=\"14\" fill=\"url(#" + escape(id) +
         "-g)\" stroke=\"#444\" stroke-width=\"0.5\"/>";
  out += "<text x=\"4\" y=\"32\" class=\"tl start\">" + escape(format("%.4g", lo)) + "</text>";
  out += "<text x=\"" + c1(w + 4) + "\" y=\"32\" class=\"tl end\">" + escape(format("%.4g", hi)) +
         " and above</text>";
  if (with_nan) {
    out += "<rect x=\"" + c1(w + 16) + "\" y=\"4\" width=\"14\" height=\"14\" fill=\"" +
           hex(kNanGrey) + "\" stroke=\"#444\" stroke-width=\"0.5\"/><text x=\"" + c1(w + 34) +
           "\" y=\"15\" class=\"tl start\">no sequence</text>";
  }
  return out + "</svg>";
}

// ---------------------------------------------------------------------------------------
// The report

struct Context {
  const std::vector<ReportRun>& runs;
  const InputSequence& library;
  const InputSequence& query;
  const ReportOptions& options;
  const EvalResult& first;  // runs[0]
  uint32_t library_size;
  uint32_t query_size;
};

std::string source_index(const InputSequence& in, int64_t position) {
  return std::to_string(static_cast<int64_t>(in.offset) + position);
}

// "library 40 (source 140)".
std::string place_text(const char* what, const InputSequence& in, int64_t position) {
  std::string out = std::string(what) + " " + std::to_string(position);
  if (in.offset != 0) out += " (source " + source_index(in, position) + ")";
  return out;
}

std::string section_open(const char* id, const char* heading) {
  return std::string("<section id=\"") + id + "\"><h2>" + heading + "</h2>";
}

// 1. Inputs, configuration, metrics, timing.
std::string section_summary(const Context& c) {
  std::string out = section_open("sec-summary", "Summary");
  out +=
      "<h3>Inputs</h3><table><tr><th></th><th>source</th><th>kind</th><th>images</th>"
      "<th>range (source indices)</th><th>image size</th><th>poses</th></tr>";
  const struct {
    const char* name;
    const InputSequence& in;
  } inputs[] = {{"library", c.library}, {"query", c.query}};
  for (const auto& [name, in] : inputs) {
    const size_t n = in.images.size();
    std::string range = "none";
    if (n > 0) {
      range = std::to_string(in.offset) + ".." + source_index(in, static_cast<int64_t>(n) - 1) +
              " of " + std::to_string(in.source_size);
    }
    std::string size = "-";
    if (n > 0) size = format("%dx%d", in.images[0].width, in.images[0].height);
    std::string poses;
    if (!in.truth.empty()) poses = "true";
    if (!in.odometry.empty()) poses += poses.empty() ? "odometry" : ", odometry";
    if (poses.empty()) poses = "none";
    out += "<tr><th>" + std::string(name) + "</th><td class=\"path\">" + escape(in.source) +
           "</td><td>" + escape(in.kind) + "</td><td>" + num(n) + "</td><td>" + range +
           "</td><td>" + size + "</td><td>" + poses + "</td></tr>";
  }
  out += "</table>";

  // Configuration, one column per run.
  std::string head = "<tr><th></th>";
  for (size_t i = 0; i < c.runs.size(); ++i) {
    head += "<th><span class=\"swatch\" style=\"background:" + std::string(run_colour(i)) +
            "\"></span> " + escape(c.runs[i].label) + "</th>";
  }
  head += "</tr>";
  const auto row = [&c](const char* name, const std::function<std::string(const EvalResult&)>& f) {
    std::string r = std::string("<tr><th>") + name + "</th>";
    for (const ReportRun& run : c.runs)
      r += "<td>" + f(*run.result) + "</td>";
    return r + "</tr>";
  };
  out += "<h3>Configuration</h3><table>" + head;
  out += row("image size", [](const EvalResult& r) {
    return format("%ux%u", static_cast<unsigned>(r.config.localiser.image_size.width),
                  static_cast<unsigned>(r.config.localiser.image_size.height));
  });
  out += row("preprocessing", [](const EvalResult& r) {
    return escape(preprocessing_name(r.config.localiser.preprocess.method));
  });
  out +=
      row("max shift (px)", [](const EvalResult& r) { return num(r.config.localiser.max_shift); });
  out += row("S (sequence length)",
             [](const EvalResult& r) { return num(r.config.localiser.sequence.seq_len); });
  out += row("W (normalisation window)", [](const EvalResult& r) {
    const uint16_t w = r.config.localiser.sequence.window;
    return w == 0 ? std::string("0 (off)") : num(w);
  });
  out += row("sigma min (grey levels)", [](const EvalResult& r) {
    return shortest_fixed(r.config.localiser.sequence.sigma_min.raw(), 8);
  });
  out += row("R (exclusion)",
             [](const EvalResult& r) { return num(r.config.localiser.sequence.exclusion); });
  out += row("threshold", [](const EvalResult& r) { return threshold_text(r); });
  out += row("matcher", [](const EvalResult& r) { return escape(matcher_name(r.config.localiser.matcher)); });
  out += "</table>";

  // Metrics.
  out += "<h3>Results</h3><table class=\"metrics\">" + head;
  const auto metric = [&c](const char* name,
                           const std::function<std::string(const EvalResult&)>& f) {
    std::string r = std::string("<tr><th>") + name + "</th>";
    for (const ReportRun& run : c.runs) {
      r += "<td>" + (run.result->has_ground_truth ? f(*run.result) : std::string("n/a")) + "</td>";
    }
    return r + "</tr>";
  };
  out += row("query images", [](const EvalResult& r) { return num(r.query_size); });
  out += row("with a match candidate", [](const EvalResult& r) {
    return num(static_cast<uint64_t>(std::count_if(
        r.matches.begin(), r.matches.end(), [](const QueryResult& m) { return m.library >= 0; })));
  });
  out += row("accepted (confidence &lt; threshold)", [](const EvalResult& r) {
    return num(static_cast<uint64_t>(
        std::count_if(r.matches.begin(), r.matches.end(),
                      [](const QueryResult& m) { return m.library >= 0 && m.accepted; })));
  });
  out += metric("queries (recall denominator)",
                [](const EvalResult& r) { return num(r.summary.queries); });
  out += metric("best match correct (top-1)",
                [](const EvalResult& r) { return percent(r.summary.top1); });
  out += metric("precision at threshold", [](const EvalResult& r) {
    return percent(r.summary.at_threshold(threshold_of(r)).precision);
  });
  out += metric("recall at threshold", [](const EvalResult& r) {
    return percent(r.summary.at_threshold(threshold_of(r)).recall);
  });
  out += metric("recall at 100 % precision",
                [](const EvalResult& r) { return percent(r.summary.recall_at_100_precision); });
  out += metric("area under the PR curve",
                [](const EvalResult& r) { return fixed3(r.summary.auc_pr); });
  out += metric("precision at recall 0.5",
                [](const EvalResult& r) { return percent(r.summary.precision_at_recall(0.5)); });
  out += metric("precision at recall 0.85",
                [](const EvalResult& r) { return percent(r.summary.precision_at_recall(0.85)); });
  out += metric("max recall (everything accepted)",
                [](const EvalResult& r) { return percent(r.summary.max_recall); });
  out += "</table>";

  // The headline sentences, as `seqslam results --ground-truth` prints them.
  for (const ReportRun& run : c.runs) {
    const EvalResult& r = *run.result;
    out += "<p class=\"headline\"><b>" + escape(run.label) + ":</b> ";
    if (!r.has_ground_truth) {
      out += "no ground truth: no precision or recall.</p>";
      continue;
    }
    const PrPoint at = r.summary.at_threshold(threshold_of(r));
    const std::string t = threshold_text(r);
    out += escape(format(
        "best match correct (top-1, no threshold): %s; at threshold %s: %zu "
        "accepted, precision %s, recall %s; recall at 100 %% precision: %s; "
        "area under the PR curve: %s",
        percent(r.summary.top1).c_str(), t.c_str(), at.accepted, percent(at.precision).c_str(),
        percent(at.recall).c_str(), percent(r.summary.recall_at_100_precision).c_str(),
        fixed3(r.summary.auc_pr).c_str()));
    out += "</p>";
  }

  // Timing.
  out += "<h3>Timing</h3><table>" + head;
  out += row("load", [](const EvalResult& r) { return millis(r.timing.load_ms); });
  out += row("preprocess", [](const EvalResult& r) { return millis(r.timing.preprocess_ms); });
  out += row("differences", [](const EvalResult& r) {
    return millis(r.timing.differences_ms) +
           (r.timing.matrix_from_cache ? std::string(" (from the cache)") : std::string());
  });
  out += row("match", [](const EvalResult& r) { return millis(r.timing.match_ms); });
  out += row("total", [](const EvalResult& r) { return millis(r.timing.total_ms); });
  out += "</table></section>";
  return out;
}

// Runs of consecutive indices in a sorted list: [first, last] pairs.
std::vector<std::pair<uint32_t, uint32_t>> index_runs(const std::vector<uint32_t>& sorted) {
  std::vector<std::pair<uint32_t, uint32_t>> runs;
  for (const uint32_t v : sorted) {
    if (!runs.empty() && v == runs.back().second + 1) {
      runs.back().second = v;
    } else if (runs.empty() || v > runs.back().second) {
      runs.emplace_back(v, v);
    }
  }
  return runs;
}

// The correct library places of a query (positions, < library_size), from options.truth.
std::vector<uint32_t> correct_places(const Context& c, uint32_t q) {
  std::vector<uint32_t> out;
  if (c.options.truth == nullptr || q >= c.options.truth->matches.size()) return out;
  for (const uint32_t j : c.options.truth->matches[q]) {
    if (j < c.library_size) out.push_back(j);
  }
  return out;
}

// One heat map with its overlay: an <img> under an absolutely placed SVG of the same geometry.
std::string heat_map(const Context& c, const std::string& id, const std::string& title,
                     const std::function<double(uint32_t, uint32_t)>& value,
                     const std::string& bar_label, bool with_nan) {
  const MatrixScale s = matrix_scale(c.library_size, c.query_size);
  const size_t count = static_cast<size_t>(c.library_size) * c.query_size;
  const auto [lo, hi] = colour_range(count, [&](size_t i) {
    return value(static_cast<uint32_t>(i / c.library_size),
                 static_cast<uint32_t>(i % c.library_size));
  });
  const Raster raster = heat_raster(s, value, lo, hi);

  Plot p;
  p.left = 64;
  p.top = 10;
  p.width = s.x.pixels;
  p.height = s.y.pixels;
  p.right = 20;
  p.bottom = 48;
  std::string out = "<figure><div class=\"heat\" style=\"width:" + c1(p.total_width()) +
                    "px;height:" + c1(p.total_height()) + "px\">";
  out += "<div class=\"heat-img\" style=\"left:" + c1(p.left) + "px;top:" + c1(p.top) + "px\">" +
         img_tag(raster, "img-" + id, title, "matrix") + "</div>";
  out += svg_open("svg-" + id, p.total_width(), p.total_height(), title);
  const auto xt = nice_ticks(0, c.library_size - 1.0);
  const auto yt = nice_ticks(0, c.query_size - 1.0);
  out += axes(
      p, xt, [&](double j) { return p.left + s.x.at(j) + s.x.up / 2.0; }, yt,
      [&](double q) { return p.top + s.y.at(q) + s.y.up / 2.0; },
      "library place (position in the input)", "query (position in the input)", false);
  // The correct places (full ground truth): translucent white bands, one row per pixel block.
  if (c.options.truth != nullptr) {
    out += "<g fill=\"#ffffff\" fill-opacity=\"0.35\">";
    for (uint32_t q = 0; q < c.query_size; q += s.y.down) {
      for (const auto& [a, b] : index_runs(correct_places(c, q))) {
        out += "<rect x=\"" + c1(p.left + s.x.lo(a)) + "\" y=\"" + c1(p.top + s.y.lo(q)) +
               "\" width=\"" + c1(s.x.hi(b) - s.x.lo(a)) + "\" height=\"" +
               c1(s.y.hi(q) - s.y.lo(q)) + "\"/>";
      }
    }
    out += "</g>";
  }
  for (const QueryResult& m : c.first.matches) {
    if (m.library < 0 || static_cast<uint32_t>(m.library) >= c.library_size ||
        m.query >= c.query_size) {
      continue;
    }
    out += marker(p.left + s.x.mid(static_cast<uint32_t>(m.library)), p.top + s.y.mid(m.query),
                  verdict_colour(verdict(c.first, m)), m.accepted);
  }
  out += "</svg></div><figcaption>" + escape(title);
  if (s.x.down > 1) {
    out += format(" (each pixel the minimum of %u x %u places)", s.x.down, s.y.down);
  }
  out += "</figcaption>" + colour_bar("bar-" + id, lo, hi, bar_label, with_nan) + "</figure>";
  return out;
}

// 2. The difference and sequence-cost matrices of runs[0].
std::string section_matrices(const Context& c) {
  std::string out = section_open("sec-matrices", "Difference and sequence-cost matrices");
  out += "<p>Run <b>" + escape(c.runs[0].label) +
         "</b>. Library places across, queries down; dark = similar (low difference or cost). "
         "A correct localisation shows as a dark diagonal; the markers are the matcher's "
         "choices";
  out += c.options.truth != nullptr ? ", the light bands the correct places." : ".";
  out += "</p>" + marker_legend(true);
  const EvalResult& r = c.first;
  const uint32_t L = c.library_size;
  out += heat_map(
      c, "differences", "Difference matrix (raw SAD of the preprocessed images)",
      [&r, L](uint32_t q, uint32_t j) {
        return static_cast<double>(r.differences[static_cast<size_t>(q) * L + j]);
      },
      "SAD", false);
  out += heat_map(
      c, "costs", "Sequence-cost matrix (the matcher's cost / S)",
      [&r, L](uint32_t q, uint32_t j) {
        return static_cast<double>(r.sequence_costs[static_cast<size_t>(q) * L + j]);
      },
      "cost / S", true);
  return out + "</section>";
}

// 3. PR curves and precision / recall against the threshold.
std::string section_pr(const Context& c) {
  std::string out = section_open("sec-pr", "Precision and recall");
  bool any = false;
  for (const ReportRun& run : c.runs)
    any = any || run.result->has_ground_truth;
  if (!any) {
    return out + "<p class=\"note\">No ground truth: no precision or recall to show.</p></section>";
  }
  out += run_legend(c.runs);

  // PR curves.
  Plot p;
  p.width = 420;
  p.height = 320;
  std::string svg = svg_open("svg-pr", p.total_width(), p.total_height(), "PR curves");
  svg += plot_axes(p, "recall", "precision");
  for (size_t i = 0; i < c.runs.size(); ++i) {
    const EvalResult& r = *c.runs[i].result;
    if (!r.has_ground_truth || r.summary.curve.empty()) continue;
    std::vector<std::pair<double, double>> pts;
    pts.emplace_back(p.px(0.0), p.py(r.summary.curve.front().precision));
    for (const PrPoint& pt : r.summary.curve)
      pts.emplace_back(p.px(pt.recall), p.py(pt.precision));
    svg += polyline(pts, run_colour(i), 2.0);
    const PrPoint at = r.summary.at_threshold(threshold_of(r));
    if (at.accepted > 0) {
      svg += "<rect x=\"" + c1(p.px(at.recall) - 4) + "\" y=\"" + c1(p.py(at.precision) - 4) +
             "\" width=\"8\" height=\"8\" fill=\"" + run_colour(i) +
             "\" stroke=\"#000\" stroke-width=\"0.8\"><title>" + escape(c.runs[i].label) +
             " at threshold " + threshold_text(r) + "</title></rect>";
    }
  }
  svg += "</svg>";
  out += "<div class=\"row\"><figure>" + svg +
         "<figcaption>PR curves (squares: the configured thresholds)</figcaption></figure>";

  // Against the threshold.
  double xmax = 1.0;
  for (const ReportRun& run : c.runs) {
    for (const PrPoint& pt : run.result->summary.curve) {
      if (std::isfinite(pt.confidence_threshold)) xmax = std::max(xmax, pt.confidence_threshold);
    }
    xmax = std::max(xmax, threshold_of(*run.result));
  }
  Plot t;
  t.width = 420;
  t.height = 320;
  t.x1 = xmax;
  svg = svg_open("svg-threshold", t.total_width(), t.total_height(),
                 "precision and recall against the threshold");
  svg += plot_axes(t, "confidence threshold (accept confidence <= it)", "precision, recall");
  std::vector<std::string> marked;
  for (size_t i = 0; i < c.runs.size(); ++i) {
    const EvalResult& r = *c.runs[i].result;
    if (!r.has_ground_truth) continue;
    std::vector<std::pair<double, double>> prec;
    std::vector<std::pair<double, double>> rec;
    rec.emplace_back(t.px(0.0), t.py(0.0));
    double last_p = 0.0;
    double last_r = 0.0;
    for (const PrPoint& pt : r.summary.curve) {
      const double x = std::isfinite(pt.confidence_threshold) ? pt.confidence_threshold : xmax;
      if (!prec.empty()) prec.emplace_back(t.px(x), t.py(last_p));
      prec.emplace_back(t.px(x), t.py(pt.precision));
      rec.emplace_back(t.px(x), t.py(last_r));
      rec.emplace_back(t.px(x), t.py(pt.recall));
      last_p = pt.precision;
      last_r = pt.recall;
    }
    if (!prec.empty()) prec.emplace_back(t.px(xmax), t.py(last_p));
    rec.emplace_back(t.px(xmax), t.py(last_r));
    svg += polyline(prec, run_colour(i), 2.0);
    svg += polyline(rec, run_colour(i), 2.0, "stroke-dasharray=\"6 3\"");
    const std::string text = "threshold " + threshold_text(r);
    if (std::find(marked.begin(), marked.end(), text) == marked.end()) {
      svg += vline(t, threshold_of(r), "#444", text, static_cast<int>(marked.size()));
      marked.push_back(text);
    }
  }
  svg += "</svg>";
  out += "<figure>" + svg +
         "<figcaption>Precision (solid) and recall (dashed) when accepting every match up to "
         "a confidence threshold</figcaption></figure></div>";
  return out + "</section>";
}

struct Stretch {
  uint32_t first = 0;
  uint32_t last = 0;
  uint32_t wrong = 0;   // accepted, wrong
  uint32_t missed = 0;  // not accepted although a correct place exists
};

// Stretches of consecutive failing queries: an accepted wrong match, or no accepted match
// where a correct place exists. Longest first.
std::vector<Stretch> failure_stretches(const EvalResult& r) {
  std::vector<Stretch> out;
  bool open = false;
  for (const QueryResult& m : r.matches) {
    const bool wrong = m.library >= 0 && m.accepted && !m.correct;
    const bool missed = m.has_truth && !(m.library >= 0 && m.accepted);
    if (!wrong && !missed) {
      open = false;
      continue;
    }
    if (!open || m.query != out.back().last + 1) {
      out.push_back(Stretch{m.query, m.query, 0, 0});
      open = true;
    }
    out.back().last = m.query;
    out.back().wrong += wrong ? 1 : 0;
    out.back().missed += missed ? 1 : 0;
  }
  std::stable_sort(out.begin(), out.end(), [](const Stretch& a, const Stretch& b) {
    return a.last - a.first > b.last - b.first;
  });
  return out;
}

// 4. Matches and confidence over time, one pair of charts per run.
std::string section_time(const Context& c) {
  std::string out = section_open("sec-time", "Matches over time");
  out += "<p>The library place found for each query and its confidence (smaller = surer).";
  if (c.options.truth != nullptr) out += " Light green: the correct places.";
  out += "</p>" + marker_legend(false);
  const double Q = c.query_size;
  const double L = c.library_size;
  for (size_t i = 0; i < c.runs.size(); ++i) {
    const EvalResult& r = *c.runs[i].result;
    const std::string label = escape(c.runs[i].label);
    out += "<h3><span class=\"swatch\" style=\"background:" + std::string(run_colour(i)) +
           "\"></span> " + label + "</h3>";
    Plot p;
    p.width = 760;
    p.height = 280;
    p.x0 = -0.5;
    p.x1 = Q - 0.5;
    p.y0 = -0.5;
    p.y1 = L - 0.5;
    std::string svg = svg_open(format("svg-time-%zu", i), p.total_width(), p.total_height(),
                               c.runs[i].label + ": matches over time");
    svg += plot_axes(p, "query (position in the input)", "library place found");
    if (c.options.truth != nullptr) {
      svg += "<g fill=\"" + std::string(kCorrectColour) + "\" fill-opacity=\"0.25\">";
      const double qw = std::max(1.0, p.width / Q);
      const double lh = std::max(1.0, p.height / L);
      for (uint32_t q = 0; q < c.query_size; ++q) {
        for (const auto& [a, b] : index_runs(correct_places(c, q))) {
          const double top = p.py(b + 0.5);
          svg += "<rect x=\"" + c1(p.px(q - 0.5)) + "\" y=\"" + c1(top) + "\" width=\"" + c1(qw) +
                 "\" height=\"" + c1(std::max(lh, p.py(a - 0.5) - top)) + "\"/>";
        }
      }
      svg += "</g>";
    }
    const double radius = Q > 400 ? 2.0 : 3.0;
    for (const QueryResult& m : r.matches) {
      if (m.library < 0 || m.library >= static_cast<int64_t>(L) || m.query >= c.query_size) {
        continue;
      }
      svg +=
          marker(p.px(m.query), p.py(m.library), verdict_colour(verdict(r, m)), m.accepted, radius);
    }
    svg += "</svg>";

    // Confidence over time.
    double ymax = 1.0;
    for (const QueryResult& m : r.matches) {
      if (m.library >= 0 && std::isfinite(m.confidence)) ymax = std::max(ymax, m.confidence);
    }
    ymax = std::min(ymax, 4.0);
    Plot k = p;
    k.height = 150;
    k.y0 = 0.0;
    k.y1 = ymax;
    std::string conf = svg_open(format("svg-confidence-%zu", i), k.total_width(), k.total_height(),
                                c.runs[i].label + ": confidence over time");
    conf += plot_axes(k, "query (position in the input)", "confidence");
    conf += hline(k, threshold_of(r), "#444", "threshold " + threshold_text(r));
    for (const QueryResult& m : r.matches) {
      if (m.library < 0 || m.query >= c.query_size) continue;
      const double v = std::isfinite(m.confidence) ? std::min(m.confidence, ymax) : ymax;
      conf += marker(k.px(m.query), k.py(v), verdict_colour(verdict(r, m)), m.accepted, radius);
    }
    conf += "</svg>";
    out += "<figure>" + svg + conf + "</figure>";

    const std::vector<Stretch> stretches =
        r.has_ground_truth ? failure_stretches(r) : std::vector<Stretch>{};
    if (!stretches.empty()) {
      out +=
          "<table class=\"stretches\"><tr><th>longest failures (queries)</th><th>length</th>"
          "<th>accepted wrong</th><th>not accepted, correct place exists</th></tr>";
      for (size_t s = 0; s < std::min<size_t>(5, stretches.size()); ++s) {
        const Stretch& st = stretches[s];
        out += "<tr><td>" + num(st.first) + ".." + num(st.last) + "</td><td>" +
               num(st.last - st.first + 1) + "</td><td>" + num(st.wrong) + "</td><td>" +
               num(st.missed) + "</td></tr>";
      }
      out += "</table>";
    }
  }
  return out + "</section>";
}

// 5. Trajectories: true and odometry poses of both inputs, equal axes, metres.
std::string section_trajectories(const Context& c) {
  std::string out = section_open("sec-trajectories", "Trajectories");
  const struct Track {
    const std::vector<PoseD>* poses;
    const char* colour;
    const char* text;
    bool dashed;
  } tracks[] = {{&c.library.truth, kRunColours[0], "library, true", false},
                {&c.library.odometry, kRunColours[0], "library, odometry", true},
                {&c.query.truth, kRunColours[1], "query, true", false},
                {&c.query.odometry, kRunColours[1], "query, odometry", true}};
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  for (const Track& t : tracks) {
    for (const PoseD& pose : *t.poses) {
      if (!std::isfinite(pose.x) || !std::isfinite(pose.y)) continue;
      x0 = std::min(x0, pose.x);
      x1 = std::max(x1, pose.x);
      y0 = std::min(y0, pose.y);
      y1 = std::max(y1, pose.y);
    }
  }
  if (!(x0 <= x1)) {
    return out +
           "<p class=\"note\">The inputs hold no poses (image directories, index files or "
           "recordings without odometry and ground truth).</p></section>";
  }
  // Equal scaling: the larger extent fills its side, at least 1 m each way, 4 % margin.
  const double cx = (x0 + x1) / 2;
  const double cy = (y0 + y1) / 2;
  const double pixels_per_metre =
      std::min(760.0 / std::max(x1 - x0, 1.0) / 1.08, 480.0 / std::max(y1 - y0, 1.0) / 1.08);
  Plot p;
  p.width = std::max(x1 - x0, 1.0) * 1.08 * pixels_per_metre;
  p.height = std::max(y1 - y0, 1.0) * 1.08 * pixels_per_metre;
  p.x0 = cx - p.width / pixels_per_metre / 2;
  p.x1 = cx + p.width / pixels_per_metre / 2;
  p.y0 = cy - p.height / pixels_per_metre / 2;
  p.y1 = cy + p.height / pixels_per_metre / 2;
  std::string svg = svg_open("svg-trajectories", p.total_width(), p.total_height(), "trajectories");
  svg += plot_axes(p, "x (m)", "y (m)");
  std::string legend = "<div class=\"legend\">";
  for (const Track& t : tracks) {
    if (t.poses->empty()) continue;
    std::vector<std::pair<double, double>> pts;
    for (const PoseD& pose : *t.poses) {
      if (std::isfinite(pose.x) && std::isfinite(pose.y)) {
        pts.emplace_back(p.px(pose.x), p.py(pose.y));
      }
    }
    svg +=
        polyline(pts, t.colour, t.dashed ? 1.2 : 1.8, t.dashed ? "stroke-dasharray=\"5 3\"" : "");
    if (!pts.empty()) {
      svg += "<rect x=\"" + c1(pts.front().first - 3) + "\" y=\"" + c1(pts.front().second - 3) +
             "\" width=\"6\" height=\"6\" fill=\"" + t.colour + "\"><title>" + t.text +
             ": start</title></rect>";
    }
    legend += std::string("<span><span class=\"swatch") + (t.dashed ? " dashed" : "") +
              "\" style=\"border-color:" + t.colour +
              ";background:" + (t.dashed ? "transparent" : t.colour) + "\"></span> " + t.text +
              "</span>";
  }
  legend += "<span>squares: start</span></div>";
  // runs[0]'s matches at the query's true position; accepted wrong ones joined to the place.
  const std::vector<PoseD>& qt = c.query.truth;
  const std::vector<PoseD>& lt = c.library.truth;
  if (!qt.empty()) {
    std::string lines;
    std::string dots;
    for (const QueryResult& m : c.first.matches) {
      if (m.library < 0 || m.query >= qt.size()) continue;
      const PoseD& a = qt[m.query];
      dots += marker(p.px(a.x), p.py(a.y), verdict_colour(verdict(c.first, m)), m.accepted, 2.2);
      if (m.accepted && c.first.has_ground_truth && !m.correct &&
          static_cast<size_t>(m.library) < lt.size()) {
        const PoseD& b = lt[static_cast<size_t>(m.library)];
        lines += "<line x1=\"" + c1(p.px(a.x)) + "\" y1=\"" + c1(p.py(a.y)) + "\" x2=\"" +
                 c1(p.px(b.x)) + "\" y2=\"" + c1(p.py(b.y)) + "\"/>";
      }
    }
    svg += "<g stroke=\"" + std::string(kWrongColour) + "\" stroke-width=\"0.8\">" + lines +
           "</g>" + dots;
    legend += marker_legend(false);
  }
  svg += "</svg>";
  out += "<p>Poses in metres, equal scale on both axes. Markers: run <b>" +
         escape(c.runs[0].label) +
         "</b>'s match for each query at the query's true position; red lines join an accepted "
         "wrong match to the true position of the place it chose.</p>";
  return out + legend + "<figure>" + svg + "</figure></section>";
}

struct Pick {
  uint32_t query = 0;
  std::string why;  // why it was chosen
};

// Automatic choice of image pairs from runs[0] (report.h).
std::vector<Pick> choose_pairs(const Context& c) {
  const EvalResult& r = c.first;
  std::vector<const QueryResult*> order;
  for (const QueryResult& m : r.matches) {
    if (m.library >= 0 && m.query < c.query_size) order.push_back(&m);
  }
  const auto key = [](const QueryResult* m) {
    return std::isnan(m->confidence) ? std::numeric_limits<double>::infinity() : m->confidence;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&key](const QueryResult* a, const QueryResult* b) { return key(a) < key(b); });
  std::vector<Pick> picks;
  const auto add = [&picks](const QueryResult* m, const char* why) {
    for (Pick& p : picks) {
      if (p.query == m->query) {
        p.why += std::string("; ") + why;
        return;
      }
    }
    picks.push_back(Pick{m->query, why});
  };
  if (order.empty()) return picks;
  add(order.front(), "the most confident match");
  add(order.back(), "the least confident match");
  std::vector<const QueryResult*> spread;  // correct (without ground truth: accepted) ones
  std::vector<const QueryResult*> wrong;   // accepted wrong ones, most confident first
  std::vector<const QueryResult*> rejected;
  for (const QueryResult* m : order) {
    if (!m->accepted) {
      rejected.push_back(m);
    } else if (!r.has_ground_truth || m->correct) {
      spread.push_back(m);
    } else {
      wrong.push_back(m);
    }
  }
  std::sort(spread.begin(), spread.end(),
            [](const QueryResult* a, const QueryResult* b) { return a->query < b->query; });
  const char* spread_why =
      r.has_ground_truth ? "correct, spread over the run" : "accepted, spread over the run";
  for (size_t k = 1; k <= 3 && !spread.empty(); ++k) {
    add(spread[(spread.size() - 1) * k / 4], spread_why);
  }
  for (size_t k = 0; k < std::min<size_t>(3, wrong.size()); ++k) {
    add(wrong[k], "accepted but wrong, among the most confident");
  }
  for (size_t k = 0; k < std::min<size_t>(2, rejected.size()); ++k) {
    add(rejected[k], "not accepted, among the most confident");
  }
  std::sort(picks.begin(), picks.end(),
            [](const Pick& a, const Pick& b) { return a.query < b.query; });
  return picks;
}

std::string pair_image(const GrayImage& image, const std::string& id, const std::string& alt) {
  if (!image.valid()) return "<p class=\"note\">" + escape(alt) + ": no image</p>";
  const int factor = std::clamp(256 / image.width, 1, 16);
  return img_tag(enlarge(image, factor), id, alt, "photo");
}

// 6. Image pairs at chosen matches.
std::string section_pairs(const Context& c) {
  std::string out = section_open("sec-pairs", "Image pairs");
  std::vector<Pick> chosen;
  for (const uint32_t q : c.options.pair_queries)
    chosen.push_back(Pick{q, "requested"});
  const bool automatic = chosen.empty();
  if (automatic) chosen = choose_pairs(c);
  std::vector<uint32_t> skipped;
  out += "<p>Run <b>" + escape(c.runs[0].label) + "</b>, raw images at the evaluation size, " +
         (automatic ? "chosen automatically (the most and the least confident match, correct "
                      "ones spread over the run, the most confident wrong ones, the most "
                      "confident not accepted)"
                    : "the requested queries") +
         ".</p>";
  if (chosen.empty()) out += "<p class=\"note\">No matches to show.</p>";
  for (const Pick& pick : chosen) {
    const uint32_t q = pick.query;
    if (q >= c.query_size || q >= c.query.images.size()) {
      skipped.push_back(q);
      continue;
    }
    const QueryResult* m = nullptr;
    for (const QueryResult& x : c.first.matches) {
      if (x.query == q) m = &x;
    }
    out += "<div class=\"pair\">";
    const std::string qtext = place_text("query", c.query, q);
    out += "<figure>" + pair_image(c.query.images[q], format("pair-%u-query", q), qtext) +
           "<figcaption>" + escape(qtext) + "<br><i>" + escape(pick.why) +
           "</i></figcaption></figure>";
    const bool has_match = m != nullptr && m->library >= 0 &&
                           static_cast<uint32_t>(m->library) < c.library_size &&
                           static_cast<size_t>(m->library) < c.library.images.size();
    if (has_match) {
      const uint32_t j = static_cast<uint32_t>(m->library);
      const Verdict v = verdict(c.first, *m);
      const std::string ltext = "match: " + place_text("library", c.library, j);
      std::string caption = escape(ltext) + "<br>confidence " + fixed3(m->confidence) + ", " +
                            (m->accepted ? "accepted" : "not accepted") +
                            ", <b style=\"color:" + verdict_colour(v) + "\">" + verdict_text(v) +
                            "</b>";
      if (v == Verdict::kWrong && !m->has_truth) caption += " (no correct place exists)";
      out += "<figure>" + pair_image(c.library.images[j], format("pair-%u-match", q), ltext) +
             "<figcaption>" + caption + "</figcaption></figure>";
      if (v != Verdict::kCorrect) {
        const std::vector<uint32_t> good = correct_places(c, q);
        if (!good.empty()) {
          uint32_t best = good[good.size() / 2];
          for (const uint32_t g : good) {
            const auto d = [j](uint32_t x) { return x > j ? x - j : j - x; };
            if (d(g) < d(best)) best = g;
          }
          const std::string ctext = "correct: " + place_text("library", c.library, best);
          if (best < c.library.images.size()) {
            out += "<figure>" +
                   pair_image(c.library.images[best], format("pair-%u-correct", q), ctext) +
                   "<figcaption>" + escape(ctext) + format("<br>%zu correct places", good.size()) +
                   "</figcaption></figure>";
          }
        } else if (v == Verdict::kWrong && m->has_truth) {
          out +=
              "<p class=\"note\">correct place: pass the ground truth to the report to see "
              "it</p>";
        }
      }
    } else {
      out += "<p class=\"note\">no match candidate (no full sequence yet)</p>";
    }
    // The other runs' answers for this query.
    if (c.runs.size() > 1) {
      out += "<ul class=\"others\">";
      for (size_t i = 1; i < c.runs.size(); ++i) {
        const EvalResult& r = *c.runs[i].result;
        const QueryResult* o = nullptr;
        for (const QueryResult& x : r.matches) {
          if (x.query == q) o = &x;
        }
        out += "<li>" + escape(c.runs[i].label) + ": ";
        if (o == nullptr || o->library < 0) {
          out += "no match candidate</li>";
          continue;
        }
        const Verdict v = verdict(r, *o);
        out += escape(place_text("library", c.library, o->library)) + ", confidence " +
               fixed3(o->confidence) + ", " + (o->accepted ? "accepted" : "not accepted") +
               ", <b style=\"color:" + verdict_colour(v) + "\">" + verdict_text(v) + "</b></li>";
      }
      out += "</ul>";
    }
    out += "</div>";
  }
  if (!skipped.empty()) {
    out += "<p class=\"note\">Skipped (beyond the query input):";
    for (const uint32_t q : skipped)
      out += " " + num(q);
    out += "</p>";
  }
  return out + "</section>";
}

const char kStyle[] = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#222;background:#fff}
main{max-width:1280px;margin:0 auto;padding:12px 20px 40px}
h1{font-size:1.5em;margin:.4em 0}h2{border-bottom:2px solid #ddd;padding-bottom:4px;margin-top:1.6em}
h3{margin:1em 0 .4em;font-size:1.05em}
table{border-collapse:collapse;margin:.3em 0 .8em;font-size:.9em}
th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#f3f3f3;font-weight:600}td.path{font-family:monospace;word-break:break-all}
.metrics td{text-align:right;font-variant-numeric:tabular-nums}
.headline{font-size:.92em;margin:.3em 0}
.note{color:#666;font-style:italic}
figure{margin:.6em 0 1em;display:inline-block;vertical-align:top}
figcaption{font-size:.85em;color:#444;margin-top:2px}
.row{display:flex;flex-wrap:wrap;gap:16px}
.heat{position:relative}.heat-img{position:absolute;line-height:0}
.heat svg{position:absolute;left:0;top:0}
img.matrix,img.photo{image-rendering:pixelated;display:block}
svg.chart{display:block;font-size:11px}
svg .grid{stroke:#e6e6e6;stroke-width:1}svg .tick{stroke:#444;stroke-width:1}
svg .frame{fill:none;stroke:#444;stroke-width:1}
svg .tl{text-anchor:middle;fill:#333}svg .tl.end{text-anchor:end}svg .tl.start{text-anchor:start}
svg .label{text-anchor:middle;fill:#222;font-size:12px}
.legend{font-size:.85em;margin:.3em 0;display:flex;flex-wrap:wrap;gap:4px 16px;align-items:center}
.legend svg{vertical-align:middle}
.swatch{display:inline-block;width:14px;height:10px;border:2px solid transparent;vertical-align:middle}
.swatch.dashed{border-style:dashed;background:transparent}
.pair{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start;border-top:1px solid #eee;padding-top:8px}
.pair figure{margin:0;max-width:272px}.others{font-size:.85em;margin:0;padding-left:18px;flex:1 1 240px}
#selftest{background:#f6f6f6;border:1px solid #ccc;padding:8px}
)";

// The in-browser self-check, run only for the fragment #selftest (report.h).
const char kSelfTest[] = R"(
(function () {
  if (location.hash !== '#selftest') return;
  function check() {
    var lines = [], failures = [], present = 0;
    var sections = ['sec-summary', 'sec-matrices', 'sec-pr', 'sec-time', 'sec-trajectories',
                    'sec-pairs'];
    sections.forEach(function (id) {
      var e = document.getElementById(id);
      if (!e) { failures.push('missing section ' + id); return; }
      var box = e.getBoundingClientRect();
      if (box.width <= 0 || box.height <= 0 || e.textContent.trim().length === 0)
        failures.push('empty section ' + id);
      else present++;
    });
    lines.push('sections: ' + sections.length + ' expected, ' + present + ' present');
    var images = Array.prototype.slice.call(document.images), decoded = 0, uniform = [];
    images.forEach(function (im) {
      var name = im.id || im.alt;
      if (!(im.complete && im.naturalWidth > 0 && im.naturalHeight > 0)) {
        failures.push('image not decoded: ' + name); return;
      }
      if (im.naturalWidth !== im.width || im.naturalHeight !== im.height)
        failures.push('image ' + name + ' is ' + im.naturalWidth + 'x' + im.naturalHeight +
                      ', declared ' + im.width + 'x' + im.height);
      var box = im.getBoundingClientRect();
      if (box.width <= 0 || box.height <= 0) failures.push('image not shown: ' + name);
      decoded++;
      var canvas = document.createElement('canvas');
      canvas.width = im.naturalWidth; canvas.height = im.naturalHeight;
      var g = canvas.getContext('2d');
      g.drawImage(im, 0, 0);
      var d = g.getImageData(0, 0, canvas.width, canvas.height).data, same = true;
      for (var i = 4; i < d.length && same; i += 4)
        same = d[i] === d[0] && d[i + 1] === d[1] && d[i + 2] === d[2];
      if (same) uniform.push(name);
    });
    lines.push('images: ' + images.length + ', decoded ' + decoded);
    lines.push('uniform images: ' + uniform.length + (uniform.length ? ' (' + uniform.join(', ') + ')' : ''));
    var svgs = Array.prototype.slice.call(document.querySelectorAll('svg.chart')), drawn = 0;
    svgs.forEach(function (s) {
      var shapes = s.querySelectorAll('path,line,polyline,polygon,rect,circle');
      var box = s.getBBox(), shown = s.getBoundingClientRect();
      if (shapes.length > 0 && box.width > 0 && box.height > 0 && shown.width > 0 &&
          shown.height > 0) drawn++;
      else failures.push('chart not drawn: ' + s.id);
    });
    lines.push('charts: ' + svgs.length + ', drawn ' + drawn);
    var text = document.body.innerText.length;
    lines.push('text: ' + text + ' characters');
    if (text < 200) failures.push('page nearly empty');
    failures.forEach(function (f) { lines.push('failure: ' + f); });
    lines.push('selftest: ' + (failures.length ? 'FAIL' : 'PASS'));
    var out = document.getElementById('selftest');
    out.textContent = lines.join('\n');
    out.hidden = false;
  }
  window.addEventListener('load', check);
})();
)";

}  // namespace

Outcome<std::string> render_report(const std::vector<ReportRun>& runs, const InputSequence& library,
                                   const InputSequence& query, const ReportOptions& options) {
  if (runs.empty()) return Error{"report: no evaluation to show"};
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].result == nullptr) {
      return Error{"report: run " + std::to_string(i) + " (" + runs[i].label + ") has no result"};
    }
  }
  const EvalResult& first = *runs[0].result;
  const uint32_t L = first.library_size;
  const uint32_t Q = first.query_size;
  if (L == 0 || Q == 0) return Error{"report: the evaluation has no library or no queries"};
  for (const ReportRun& run : runs) {
    const EvalResult& r = *run.result;
    if (r.library_size != L || r.query_size != Q) {
      return Error{"report: run " + run.label + " is " + std::to_string(r.query_size) + " x " +
                   std::to_string(r.library_size) + ", run " + runs[0].label + " " +
                   std::to_string(Q) + " x " + std::to_string(L) +
                   " (queries x library): runs to overlay need the same inputs"};
    }
    if (r.matches.size() != Q) {
      return Error{"report: run " + run.label + " has " + std::to_string(r.matches.size()) +
                   " results for " + std::to_string(Q) + " queries"};
    }
  }
  const size_t cells = static_cast<size_t>(L) * Q;
  if (first.differences.size() != cells || first.sequence_costs.size() != cells) {
    return Error{"report: run " + runs[0].label +
                 " holds no difference and sequence-cost matrices (evaluate with keep_matrices)"};
  }
  if (library.images.size() != L || query.images.size() != Q) {
    return Error{"report: the inputs hold " + std::to_string(query.images.size()) + " query and " +
                 std::to_string(library.images.size()) + " library images, the evaluation " +
                 std::to_string(Q) + " and " + std::to_string(L)};
  }

  const Context c{runs, library, query, options, first, L, Q};
  const std::string title = options.title.empty() ? "SeqSLAM evaluation" : options.title;
  std::string html;
  html.reserve(1 << 20);
  html +=
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>" +
      escape(title) + "</title><style>" + kStyle + "</style></head>\n<body><main>\n<h1>" +
      escape(title) + "</h1>\n<p class=\"note\">" + num(Q) + " queries against " + num(L) +
      " library places; runs: ";
  for (size_t i = 0; i < runs.size(); ++i)
    html += (i > 0 ? ", " : "") + escape(runs[i].label);
  html +=
      ". Sections: <a href=\"#sec-summary\">summary</a>, <a href=\"#sec-matrices\">"
      "matrices</a>, <a href=\"#sec-pr\">precision and recall</a>, <a href=\"#sec-time\">"
      "matches over time</a>, <a href=\"#sec-trajectories\">trajectories</a>, "
      "<a href=\"#sec-pairs\">image pairs</a>.</p>\n";
  html += section_summary(c) + "\n";
  html += section_matrices(c) + "\n";
  html += section_pr(c) + "\n";
  html += section_time(c) + "\n";
  html += section_trajectories(c) + "\n";
  html += section_pairs(c) + "\n";
  html += "<pre id=\"selftest\" hidden></pre>\n</main>\n<script>";
  html += kSelfTest;
  html += "</script>\n</body></html>\n";
  return html;
}

bool write_report(const std::string& path, const std::string& html, std::string* error) {
  return detail::write_file_bytes(path, html.data(), html.size(), error);
}

}  // namespace seqslam::tools
