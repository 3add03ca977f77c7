// The figures JSON of `seqslam slam` (slam_figures.h) through nlohmann/json: written as an
// ordered_json (the documented key order), read into a json value and checked key by key.
#include "seqslam_tools/slam_figures.h"

#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <string_view>
#include <type_traits>
#include <utility>

#include "file_util.h"

namespace seqslam::tools {

namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

// Deeper than any document of the writer (the root, events, an event: 3 levels; near_path,
// a map: 3 too); the guard
// keeps a file of 16 MiB of '[' from becoming millions of nested values.
constexpr int kMaxDepth = 32;
struct TooDeep {};

const char* class_name(uint32_t c) {
  return loop_closure_class_name(static_cast<LoopClosureClass>(c));
}

// A JSON value for a message: numbers and literals as written, other values by their kind.
std::string describe(const Json& j) {
  if (j.is_string()) return "a string";
  if (j.is_object()) return "an object";
  if (j.is_array()) return "an array";
  return j.dump();  // number, true, false, null
}

// Checks a parsed document member by member; the first problem is kept as the error.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path) {}

  bool fail(const std::string& what) {
    if (error_.empty()) error_ = path_ + ": " + what;
    return false;
  }
  const std::string& error() const { return error_; }

  // Keys are named in messages with `prefix_` before them ("decisions.", "events[2].");
  // `group_` ("has_truth", "has_map", or null) says which flag made a missing key required.
  void enter(std::string prefix, const char* group) {
    prefix_ = std::move(prefix);
    group_ = group;
  }

  const Json* member(const Json& object, const char* key) {
    const auto it = object.find(key);
    if (it == object.end()) {
      fail(group_ != nullptr
               ? std::string(group_) + " is true but key '" + name(key) + "' is missing"
               : "missing key '" + name(key) + "'");
      return nullptr;
    }
    return &*it;
  }

  template <typename T>
  bool count(const Json& object, const char* key, T* out) {
    static_assert(std::is_unsigned_v<T>);
    const Json* j = member(object, key);
    if (j == nullptr) return false;
    constexpr uint64_t kMax = std::numeric_limits<T>::max();
    if (j->is_number_unsigned()) {
      const uint64_t v = j->get<uint64_t>();
      if (v <= kMax) {
        *out = static_cast<T>(v);
        return true;
      }
    }
    return fail("'" + name(key) + "' must be a whole number from 0 to " + std::to_string(kMax) +
                ", found " + describe(*j));
  }

  bool integer(const Json& object, const char* key, int64_t lo, int64_t hi, int32_t* out) {
    const Json* j = member(object, key);
    if (j == nullptr) return false;
    if (j->is_number_integer()) {
      // Unsigned values beyond int64 cannot be in [lo, hi] (hi is an int32).
      const bool big =
          j->is_number_unsigned() &&
          j->get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
      const int64_t v = big ? std::numeric_limits<int64_t>::max() : j->get<int64_t>();
      if (v >= lo && v <= hi) {
        *out = static_cast<int32_t>(v);
        return true;
      }
    }
    return fail("'" + name(key) + "' must be a whole number from " + std::to_string(lo) + " to " +
                std::to_string(hi) + ", found " + describe(*j));
  }

  bool number(const Json& object, const char* key, double* out) {
    const Json* j = member(object, key);
    if (j == nullptr) return false;
    if (j->is_number()) {
      const double v = j->get<double>();
      if (std::isfinite(v)) {
        *out = v;
        return true;
      }
    }
    return fail("'" + name(key) + "' must be a finite number, found " + describe(*j));
  }

  bool string(const Json& object, const char* key, std::string* out) {
    const Json* j = member(object, key);
    if (j == nullptr) return false;
    if (!j->is_string()) {
      return fail("'" + name(key) + "' must be a string, found " + describe(*j));
    }
    *out = j->get<std::string>();
    return true;
  }

  bool boolean(const Json& object, const char* key, bool* out) {
    const Json* j = member(object, key);
    if (j == nullptr) return false;
    if (!j->is_boolean()) {
      return fail("'" + name(key) + "' must be true or false, found " + describe(*j));
    }
    *out = j->get<bool>();
    return true;
  }

  // The member `key`, which must be an object (kind "object") or an array ("array").
  const Json* container(const Json& object, const char* key, bool array) {
    const Json* j = member(object, key);
    if (j == nullptr) return nullptr;
    if (array ? !j->is_array() : !j->is_object()) {
      fail("'" + name(key) + "' must be " + (array ? "an array" : "an object") + ", found " +
           describe(*j));
      return nullptr;
    }
    return j;
  }

 private:
  std::string name(const char* key) const { return prefix_ + key; }

  std::string path_;
  std::string error_;
  std::string prefix_;
  const char* group_ = nullptr;
};

bool read_truth(Reader& r, const Json& doc, SlamTruthFigures* t) {
  r.enter("", "has_truth");
  if (!r.number(doc, "rmse_dead_reckoning_m", &t->rmse_dead_reckoning_m) ||
      !r.number(doc, "rmse_corrected_m", &t->rmse_corrected_m) ||
      !r.number(doc, "rmse_online_m", &t->rmse_online_m) ||
      !r.number(doc, "max_error_dead_reckoning_m", &t->max_error_dead_reckoning_m) ||
      !r.number(doc, "max_error_corrected_m", &t->max_error_corrected_m) ||
      !r.count(doc, "false_closures", &t->false_closures) ||
      !r.number(doc, "largest_closure_true_distance_m", &t->largest_closure_true_distance_m) ||
      !r.number(doc, "closure_heading_error_rms_deg", &t->closure_heading_error_rms_deg) ||
      !r.number(doc, "closure_same_heading_error_rms_deg",
                &t->closure_same_heading_error_rms_deg) ||
      !r.number(doc, "closure_along_error_rms_m", &t->closure_along_error_rms_m) ||
      !r.number(doc, "closure_gate_along_error_rms_m", &t->closure_gate_along_error_rms_m)) {
    return false;
  }
  const Json* events = r.container(doc, "events", true);
  if (events == nullptr) return false;
  for (size_t i = 0; i < events->size(); ++i) {
    const Json& e = (*events)[i];
    const std::string name = "events[" + std::to_string(i) + "]";
    if (!e.is_object()) return r.fail("'" + name + "' must be an object, found " + describe(e));
    r.enter(name + ".", nullptr);
    SlamEvent ev;
    if (!r.count(e, "place", &ev.place) || !r.string(e, "kind", &ev.kind) ||
        !r.integer(e, "relocalised_after", -1, std::numeric_limits<int32_t>::max(),
                   &ev.relocalised_after)) {
      return false;
    }
    t->events.push_back(std::move(ev));
  }
  return true;
}

// The counts of one map's comparison near the path (the rates beside them are not read).
bool read_near_path_map(Reader& r, const Json& near, const char* key, NearPathComparison* c) {
  r.enter("near_path.", nullptr);
  const Json* j = r.container(near, key, false);
  if (j == nullptr) return false;
  r.enter(std::string("near_path.") + key + ".", nullptr);
  if (!r.count(*j, "cells", &c->cells) || !r.count(*j, "truth_occupied", &c->truth_occupied) ||
      !r.count(*j, "grid_occupied", &c->grid_occupied) ||
      !r.count(*j, "grid_free", &c->grid_free) ||
      !r.count(*j, "occupied_occupied", &c->occupied_occupied) ||
      !r.count(*j, "grid_occupied_near_truth", &c->grid_occupied_near_truth) ||
      !r.count(*j, "truth_occupied_near_grid", &c->truth_occupied_near_grid)) {
    return false;
  }
  if (!c->consistent()) {
    return r.fail(std::string("'near_path.") + key +
                  "' counts that no comparison gives (a part larger than its whole)");
  }
  return true;
}

bool read_near_path(Reader& r, const Json& doc, SlamNearPathFigures* n) {
  const Json* near = r.container(doc, "near_path", false);
  if (near == nullptr) return false;
  r.enter("near_path.", nullptr);
  if (!r.number(*near, "band_m", &n->band_m)) return false;
  if (n->band_m <= 0) return r.fail("'near_path.band_m' must be more than 0");
  return read_near_path_map(r, *near, "corrected", &n->corrected) &&
         read_near_path_map(r, *near, "dead_reckoning", &n->dead_reckoning);
}

bool read_map(Reader& r, const Json& doc, SlamMapFigures* m) {
  r.enter("", "has_map");
  if (!r.number(doc, "map_accuracy_corrected", &m->map_accuracy_corrected) ||
      !r.count(doc, "map_cells_corrected", &m->map_cells_corrected) ||
      !r.number(doc, "map_accuracy_dead_reckoning", &m->map_accuracy_dead_reckoning) ||
      !r.count(doc, "map_cells_dead_reckoning", &m->map_cells_dead_reckoning)) {
    return false;
  }
  // Optional: documents without true poses, or written before it existed, lack it.
  if (!doc.contains("near_path")) return true;
  m->near_path.emplace();
  return read_near_path(r, doc, &*m->near_path);
}

bool read_calibration(Reader& r, const Json& doc, SlamCalibrationFigures* c) {
  const Json* j = r.container(doc, "calibration", false);
  if (j == nullptr) return false;
  r.enter("calibration.", nullptr);
  bool has_truth = false;
  if (!r.boolean(*j, "accepted", &c->accepted) || !r.number(*j, "difference", &c->difference) ||
      !r.number(*j, "track", &c->track) ||
      !r.number(*j, "sigma_difference", &c->sigma_difference) ||
      !r.number(*j, "sigma_track", &c->sigma_track) ||
      !r.count(*j, "closures_used", &c->closures_used) ||
      !r.count(*j, "closures_skipped", &c->closures_skipped) ||
      !r.number(*j, "residual_before_m", &c->residual_before_m) ||
      !r.number(*j, "residual_after_m", &c->residual_after_m) ||
      !r.string(*j, "corrected_wheels", &c->corrected_wheels) ||
      !r.boolean(*j, "has_truth", &has_truth)) {
    return false;
  }
  if (has_truth) {
    double d = 0, t = 0, m = 0;
    if (!r.number(*j, "true_difference", &d) || !r.number(*j, "true_track", &t) ||
        !r.number(*j, "true_mean", &m)) {
      return false;
    }
    c->true_difference = d;
    c->true_track = t;
    c->true_mean = m;
  }
  r.enter("", nullptr);
  return true;
}

OrderedJson near_path_json(const NearPathComparison& c) {
  OrderedJson j = OrderedJson::object();
  j["cells"] = c.cells;
  j["truth_occupied"] = c.truth_occupied;
  j["grid_occupied"] = c.grid_occupied;
  j["grid_free"] = c.grid_free;
  j["occupied_occupied"] = c.occupied_occupied;
  j["grid_occupied_near_truth"] = c.grid_occupied_near_truth;
  j["truth_occupied_near_grid"] = c.truth_occupied_near_grid;
  j["occupied_precision"] = c.precision();
  j["occupied_recall"] = c.recall();
  j["balanced_accuracy"] = c.balanced_accuracy();
  j["occupied_precision_within_1_cell"] = c.precision_within_cell();
  j["occupied_recall_within_1_cell"] = c.recall_within_cell();
  return j;
}

bool read_figures(Reader& r, const Json& doc, SlamFigures* f) {
  constexpr int64_t kIntMin = std::numeric_limits<int32_t>::min();
  constexpr int64_t kIntMax = std::numeric_limits<int32_t>::max();
  r.enter("", nullptr);
  if (!r.count(doc, "places", &f->places) || !r.count(doc, "runs", &f->runs)) return false;
  const Json* decisions = r.container(doc, "decisions", false);
  if (decisions == nullptr) return false;
  r.enter("decisions.", nullptr);
  for (uint32_t c = 0; c < kLoopClosureClasses; ++c) {
    if (!r.count(*decisions, class_name(c), &f->decisions[c])) return false;
  }
  r.enter("", nullptr);
  bool has_truth = false, has_map = false;
  if (!r.count(doc, "rejected_position", &f->rejected_position) ||
      !r.count(doc, "rejected_heading", &f->rejected_heading) ||
      !r.count(doc, "rejected_image", &f->rejected_image) ||
      !r.count(doc, "closures", &f->closures) ||
      !r.count(doc, "optimiser_work", &f->optimiser_work) || !r.count(doc, "slices", &f->slices) ||
      !r.count(doc, "final_slices", &f->final_slices) ||
      !r.count(doc, "max_solve_places", &f->max_solve_places) ||
      !r.string(doc, "wheels", &f->wheels) ||
      !r.string(doc, "closure_heading", &f->closure_heading) ||
      !r.number(doc, "hfov_deg", &f->hfov_deg) ||
      !r.integer(doc, "align_length", kIntMin, kIntMax, &f->align_length) ||
      !r.integer(doc, "align_range", kIntMin, kIntMax, &f->align_range) ||
      !r.integer(doc, "align_shift", kIntMin, kIntMax, &f->align_shift) ||
      !r.count(doc, "closures_realigned", &f->closures_realigned) ||
      !r.boolean(doc, "has_truth", &has_truth) || !r.boolean(doc, "has_map", &has_map) ||
      !r.count(doc, "unreliable_places", &f->unreliable_places) ||
      !r.count(doc, "relocalisations", &f->relocalisations)) {
    return false;
  }
  // Optional: documents written before these counters existed lack them.
  f->align_failures = 0;
  f->heading_failures = 0;
  if ((doc.contains("align_failures") && !r.count(doc, "align_failures", &f->align_failures)) ||
      (doc.contains("heading_failures") &&
       !r.count(doc, "heading_failures", &f->heading_failures))) {
    return false;
  }
  f->closure_lateral = 1.0;
  if (doc.contains("closure_lateral")) {
    if (!r.number(doc, "closure_lateral", &f->closure_lateral)) return false;
    if (f->closure_lateral < 0.0 || f->closure_lateral > 1.0) {
      char found[32];
      std::snprintf(found, sizeof found, "%g", f->closure_lateral);
      return r.fail(std::string("'closure_lateral' must be a number from 0 to 1, found ") + found);
    }
  }
  if (doc.contains("calibration")) {
    f->calibration.emplace();
    if (!read_calibration(r, doc, &*f->calibration)) return false;
  }
  if (has_truth) {
    f->truth.emplace();
    if (!read_truth(r, doc, &*f->truth)) return false;
  }
  if (has_map) {
    f->map.emplace();
    if (!read_map(r, doc, &*f->map)) return false;
  }
  return true;
}

}  // namespace

bool operator==(const SlamEvent& a, const SlamEvent& b) {
  return a.place == b.place && a.kind == b.kind && a.relocalised_after == b.relocalised_after;
}

bool operator==(const SlamTruthFigures& a, const SlamTruthFigures& b) {
  return a.rmse_dead_reckoning_m == b.rmse_dead_reckoning_m &&
         a.rmse_corrected_m == b.rmse_corrected_m && a.rmse_online_m == b.rmse_online_m &&
         a.max_error_dead_reckoning_m == b.max_error_dead_reckoning_m &&
         a.max_error_corrected_m == b.max_error_corrected_m &&
         a.false_closures == b.false_closures &&
         a.largest_closure_true_distance_m == b.largest_closure_true_distance_m &&
         a.closure_heading_error_rms_deg == b.closure_heading_error_rms_deg &&
         a.closure_same_heading_error_rms_deg == b.closure_same_heading_error_rms_deg &&
         a.closure_along_error_rms_m == b.closure_along_error_rms_m &&
         a.closure_gate_along_error_rms_m == b.closure_gate_along_error_rms_m &&
         a.events == b.events;
}

bool operator==(const SlamNearPathFigures& a, const SlamNearPathFigures& b) {
  return a.band_m == b.band_m && a.corrected == b.corrected && a.dead_reckoning == b.dead_reckoning;
}

bool operator==(const SlamMapFigures& a, const SlamMapFigures& b) {
  return a.map_accuracy_corrected == b.map_accuracy_corrected &&
         a.map_cells_corrected == b.map_cells_corrected &&
         a.map_accuracy_dead_reckoning == b.map_accuracy_dead_reckoning &&
         a.map_cells_dead_reckoning == b.map_cells_dead_reckoning && a.near_path == b.near_path;
}

bool operator==(const SlamFigures& a, const SlamFigures& b) {
  return a.places == b.places && a.runs == b.runs && a.decisions == b.decisions &&
         a.rejected_position == b.rejected_position && a.rejected_heading == b.rejected_heading &&
         a.rejected_image == b.rejected_image && a.closures == b.closures &&
         a.optimiser_work == b.optimiser_work && a.slices == b.slices &&
         a.final_slices == b.final_slices && a.max_solve_places == b.max_solve_places &&
         a.wheels == b.wheels && a.closure_heading == b.closure_heading &&
         a.hfov_deg == b.hfov_deg && a.align_length == b.align_length &&
         a.align_range == b.align_range && a.align_shift == b.align_shift &&
         a.closures_realigned == b.closures_realigned && a.truth == b.truth && a.map == b.map &&
         a.unreliable_places == b.unreliable_places && a.relocalisations == b.relocalisations &&
         a.align_failures == b.align_failures && a.heading_failures == b.heading_failures &&
         a.closure_lateral == b.closure_lateral && a.calibration == b.calibration;
}

bool operator==(const SlamCalibrationFigures& a, const SlamCalibrationFigures& b) {
  return a.accepted == b.accepted && a.difference == b.difference && a.track == b.track &&
         a.sigma_difference == b.sigma_difference && a.sigma_track == b.sigma_track &&
         a.closures_used == b.closures_used && a.closures_skipped == b.closures_skipped &&
         a.residual_before_m == b.residual_before_m && a.residual_after_m == b.residual_after_m &&
         a.corrected_wheels == b.corrected_wheels && a.true_difference == b.true_difference &&
         a.true_track == b.true_track && a.true_mean == b.true_mean;
}

bool operator!=(const SlamFigures& a, const SlamFigures& b) {
  return !(a == b);
}

std::string slam_figures_json(const SlamFigures& f) {
  OrderedJson doc = OrderedJson::object();
  doc["places"] = f.places;
  doc["runs"] = f.runs;
  OrderedJson decisions = OrderedJson::object();
  for (uint32_t c = 0; c < kLoopClosureClasses; ++c)
    decisions[class_name(c)] = f.decisions[c];
  doc["decisions"] = std::move(decisions);
  doc["rejected_position"] = f.rejected_position;
  doc["rejected_heading"] = f.rejected_heading;
  doc["rejected_image"] = f.rejected_image;
  doc["closures"] = f.closures;
  doc["optimiser_work"] = f.optimiser_work;
  doc["slices"] = f.slices;
  doc["final_slices"] = f.final_slices;
  doc["max_solve_places"] = f.max_solve_places;
  doc["wheels"] = f.wheels;
  doc["closure_heading"] = f.closure_heading;
  doc["hfov_deg"] = f.hfov_deg;
  doc["align_length"] = f.align_length;
  doc["align_range"] = f.align_range;
  doc["align_shift"] = f.align_shift;
  doc["closures_realigned"] = f.closures_realigned;
  doc["has_truth"] = f.truth.has_value();
  if (f.truth) {
    const SlamTruthFigures& t = *f.truth;
    doc["rmse_dead_reckoning_m"] = t.rmse_dead_reckoning_m;
    doc["rmse_corrected_m"] = t.rmse_corrected_m;
    doc["rmse_online_m"] = t.rmse_online_m;
    doc["max_error_dead_reckoning_m"] = t.max_error_dead_reckoning_m;
    doc["max_error_corrected_m"] = t.max_error_corrected_m;
    doc["false_closures"] = t.false_closures;
    doc["largest_closure_true_distance_m"] = t.largest_closure_true_distance_m;
    doc["closure_heading_error_rms_deg"] = t.closure_heading_error_rms_deg;
    doc["closure_same_heading_error_rms_deg"] = t.closure_same_heading_error_rms_deg;
    doc["closure_along_error_rms_m"] = t.closure_along_error_rms_m;
    doc["closure_gate_along_error_rms_m"] = t.closure_gate_along_error_rms_m;
    OrderedJson events = OrderedJson::array();
    for (const SlamEvent& e : t.events) {
      OrderedJson event = OrderedJson::object();
      event["place"] = e.place;
      event["kind"] = e.kind;
      event["relocalised_after"] = e.relocalised_after;
      events.push_back(std::move(event));
    }
    doc["events"] = std::move(events);
  }
  doc["has_map"] = f.map.has_value();
  if (f.map) {
    const SlamMapFigures& m = *f.map;
    doc["map_accuracy_corrected"] = m.map_accuracy_corrected;
    doc["map_cells_corrected"] = m.map_cells_corrected;
    doc["map_accuracy_dead_reckoning"] = m.map_accuracy_dead_reckoning;
    doc["map_cells_dead_reckoning"] = m.map_cells_dead_reckoning;
    if (m.near_path) {
      OrderedJson near = OrderedJson::object();
      near["band_m"] = m.near_path->band_m;
      near["corrected"] = near_path_json(m.near_path->corrected);
      near["dead_reckoning"] = near_path_json(m.near_path->dead_reckoning);
      doc["near_path"] = std::move(near);
    }
  }
  doc["unreliable_places"] = f.unreliable_places;
  doc["relocalisations"] = f.relocalisations;
  doc["align_failures"] = f.align_failures;
  doc["heading_failures"] = f.heading_failures;
  doc["closure_lateral"] = f.closure_lateral;
  if (f.calibration) {
    const SlamCalibrationFigures& c = *f.calibration;
    OrderedJson cal = OrderedJson::object();
    cal["accepted"] = c.accepted;
    cal["difference"] = c.difference;
    cal["track"] = c.track;
    cal["sigma_difference"] = c.sigma_difference;
    cal["sigma_track"] = c.sigma_track;
    cal["closures_used"] = c.closures_used;
    cal["closures_skipped"] = c.closures_skipped;
    cal["residual_before_m"] = c.residual_before_m;
    cal["residual_after_m"] = c.residual_after_m;
    cal["corrected_wheels"] = c.corrected_wheels;
    const bool truth = c.true_difference && c.true_track && c.true_mean;
    cal["has_truth"] = truth;
    if (truth) {
      cal["true_difference"] = *c.true_difference;
      cal["true_track"] = *c.true_track;
      cal["true_mean"] = *c.true_mean;
    }
    doc["calibration"] = std::move(cal);
  }
  // error_handler_t::replace: a string that is not UTF-8 (wheels comes from the command
  // line) is written with U+FFFD instead of throwing.
  return doc.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

Outcome<SlamFigures> parse_slam_figures(const std::string& text, const std::string& path) {
  try {
    if (text.size() > kMaxSlamFiguresBytes) {
      return Error{path + ": " + std::to_string(text.size()) + " bytes, more than the " +
                   std::to_string(kMaxSlamFiguresBytes) + " a figures JSON may have"};
    }
    const Json::parser_callback_t guard = [](int depth, Json::parse_event_t event, Json&) {
      if ((event == Json::parse_event_t::object_start ||
           event == Json::parse_event_t::array_start) &&
          depth >= kMaxDepth) {
        throw TooDeep{};
      }
      return true;
    };
    Json doc;
    try {
      doc = Json::parse(text, guard, /*allow_exceptions=*/true, /*ignore_comments=*/false);
    } catch (const Json::exception& e) {
      // "[json.exception.parse_error.101] parse error at line 3, column 1: ..." (or
      // "[json.exception.out_of_range.406] number overflow parsing '1e999'") without the
      // bracketed id.
      std::string_view what = e.what();
      const size_t id_end = what.find("] ");
      if (what.substr(0, 1) == "[" && id_end != std::string_view::npos)
        what.remove_prefix(id_end + 2);
      return Error{path + ": not JSON: " + detail::printable(what, 400)};
    } catch (const TooDeep&) {
      return Error{path + ": not a figures JSON: nested deeper than " + std::to_string(kMaxDepth) +
                   " levels"};
    }
    if (!doc.is_object()) {
      return Error{path + ": not a figures JSON: the document must be an object, found " +
                   describe(doc)};
    }
    Reader reader(path);
    SlamFigures figures;
    if (!read_figures(reader, doc, &figures)) return Error{reader.error()};
    return figures;
  } catch (const std::exception& e) {  // memory, or a bug: never out of the function
    return Error{path + ": " + e.what()};
  } catch (...) {
    return Error{path + ": unexpected error reading the figures JSON"};
  }
}

}  // namespace seqslam::tools
