// seqslam dream info: what a dream recording holds.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "seqslam/storage/dream.h"

namespace seqslam::cli {

namespace {

struct InfoOptions {
  std::string source;
};

void row(const char* key, const std::string& value) {
  std::printf("  %-18s %s\n", key, value.c_str());
}

std::string q16(int32_t raw) {
  return shortest_decimal(raw, 16);
}

// Microseconds as seconds with 6 decimals.
std::string seconds(uint64_t us) {
  const std::string frac = std::to_string(us % 1000000);
  return std::to_string(us / 1000000) + "." + std::string(6 - frac.size(), '0') + frac;
}

// "place 3 at (1.2, -0.5) m, 90.00 deg"
std::string true_pose(const storage::DreamTruth& t) {
  return "place " + std::to_string(t.place_index) + " at (" + shortest_decimal(t.pose.x.raw(), 32) +
         ", " + shortest_decimal(t.pose.y.raw(), 32) + ") m, " +
         angle_degrees(t.pose.heading.bam, 2) + " deg";
}

void print_header(const storage::DreamHeader& h) {
  const bool full = h.variant == storage::DreamVariant::kFull;
  row("variant", full ? "full (a sensor snapshot every bus period; places with odometry, "
                        "encoders and infrared)"
                      : "reduced (places with grey images only)");
  row("colour", h.colour == storage::ColourFormat::kYuv422 ? "YUV 4:2:2 frame with each place"
                                                           : "none (grey only)");
  row("camera", std::to_string(h.camera_width) + "x" + std::to_string(h.camera_height) +
                    " pixels, gamma " + shortest_decimal(h.camera_gamma.raw(), 8));
  const hal::PipelineMapping& m = h.mapping;
  row("image size", std::to_string(m.xmax) + "x" + std::to_string(m.ymax) + " pixels");
  row("pipeline mapping", "a11 " + q16(m.a11.raw()) + ", a12 " + q16(m.a12.raw()) + ", a21 " +
                              q16(m.a21.raw()) + ", a22 " + q16(m.a22.raw()) + ", offset (" +
                              std::to_string(m.bx) + ", " + std::to_string(m.by) + ") pixels" +
                              (m == hal::PipelineMapping::reduction(m.xmax, m.ymax)
                                   ? " (plain reduction of the camera frame)"
                                   : ""));
  const OdometryConfig& w = h.wheels;
  const std::string unused = full ? "" : " (not used by reduced recordings)";
  row("wheels", std::to_string(w.ticks_per_revolution) + " ticks/revolution, circumference left " +
                    shortest_decimal(w.circumference_left.raw(), 32) + " m, right " +
                    shortest_decimal(w.circumference_right.raw(), 32) + " m, track width " +
                    shortest_decimal(w.track_width.raw(), 32) + " m, " +
                    std::to_string(w.counter_bits) + "-bit counters, at most " +
                    std::to_string(w.max_ticks_per_update) + " ticks per update" + unused);
  row("spacing",
      shortest_decimal(h.spacing.raw(), 32) + " m (trigger spacing while recording)" + unused);
  row("snapshot period", std::to_string(h.snapshot_period_us) + " us");
  if (h.infrared_count == 0) {
    row("infrared sensors", "none");
  } else {
    row("infrared sensors", std::to_string(h.infrared_count) + ":");
    for (uint32_t i = 0; i < h.infrared_count && i < hal::kMaxInfrared; ++i) {
      const storage::InfraredMount& ir = h.infrared[i];
      std::printf("  %-18s #%u at (%d, %d) mm, pointing %s deg, range %u..%u mm\n", "", i, ir.x_mm,
                  ir.y_mm, angle_degrees(static_cast<uint32_t>(ir.angle) << 16, 2).c_str(),
                  ir.min_mm, ir.max_mm);
    }
  }
  row("head orientation", h.has_head ? "recorded" : "not recorded");
}

int run_info(const InfoOptions& o) {
  LogSource source;
  const std::string error = source.open(o.source, nullptr);
  if (!error.empty()) return fail(error);
  std::vector<uint8_t> buffer;
  storage::DreamReader reader;
  const std::string open_error = open_dream(source, reader, buffer);
  if (!open_error.empty()) return fail(open_error);
  storage::LogReader log;
  uint8_t none[1];
  const uint32_t session = log.open(source.device(), storage::kDreamKind, nullptr, 0, nullptr,
                                    Span<uint8_t>(none, 1)) == Status::kOk
                               ? log.session()
                               : 0;

  uint32_t damaged = 0;
  bool have_time = false;
  uint32_t first_us = 0;
  uint32_t last_us = 0;
  uint64_t span_us = 0;
  // Timestamps that go back (a step of 2^31 us or more modulo 2^32: the bus clock wraps
  // forward, after 71.6 minutes): not counted in the span, warned about.
  uint32_t backwards = 0;
  std::string first_backwards;
  Status end = Status::kOk;
  std::vector<std::string> problems;
  storage::DreamTruth first_truth;
  storage::DreamTruth last_truth;
  for (;;) {
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kOk && item.type == storage::DreamRecord::kTruth) {
      if (reader.truths() == 1) first_truth = item.truth;
      last_truth = item.truth;
    } else if (s == Status::kOk) {
      const uint32_t t = item.type == storage::DreamRecord::kSnapshot ? item.snapshot.timestamp_us
                                                                      : item.place.timestamp_us;
      const uint32_t step = t - last_us;  // uint32_t arithmetic: the bus clock wraps
      if (have_time && step >= 0x80000000u) {
        if (backwards++ == 0) {
          first_backwards = (item.type == storage::DreamRecord::kSnapshot
                                 ? "snapshot " + std::to_string(item.snapshot.sequence)
                                 : "place " + std::to_string(item.place.index)) +
                            ": " + std::to_string(t) + " us after " + std::to_string(last_us) +
                            " us";
        }
      } else if (have_time) {
        span_us += step;
      } else {
        first_us = t;
        have_time = true;
      }
      last_us = t;
    } else if (s == Status::kDataLoss || s == Status::kResourceExhausted) {
      ++damaged;
      problems.push_back(
          s == Status::kResourceExhausted
              ? std::string(storage::log_problem_text(storage::LogProblem::kRecordTooLarge))
          : reader.problem() == storage::DreamProblem::kLog
              ? std::string(storage::log_problem_text(reader.log_problem())) + " (at byte " +
                    std::to_string(reader.problem_offset()) + ")"
              : std::string(storage::dream_problem_text(reader.problem())));
    } else {
      end = s;
      break;
    }
  }

  std::printf("%s: dream recording, session %u\n", source.name().c_str(), session);
  print_header(reader.header());
  row("snapshots", std::to_string(reader.snapshots()));
  row("places", std::to_string(reader.places()));
  row("ground truth", reader.truths() == 0
                          ? std::string("none")
                          : std::to_string(reader.truths()) + " places with a true pose (first " +
                                true_pose(first_truth) + "; last " + true_pose(last_truth) + ")");
  row("missed snapshots",
      std::to_string(reader.missed_snapshots()) + " (gaps in the bus sequence)");
  row("damaged records", std::to_string(damaged));
  row("records lost", std::to_string(reader.lost_records()));
  const storage::LogProblem how = reader.log_problem();
  std::string ending;
  if (end != Status::kOutOfRange) {
    ending = std::string("read error (") + status_name(end) + ")";
  } else if (how == storage::LogProblem::kEndClean) {
    ending = "ends cleanly";
  } else if (how == storage::LogProblem::kEndTruncated) {
    ending = "cut short or damaged at byte " + std::to_string(reader.problem_offset()) +
             " (records the log committed are missing)";
  } else if (how == storage::LogProblem::kEndDamagedTail) {
    ending = "damaged tail at byte " + std::to_string(reader.problem_offset()) +
             " (the last record is incomplete: power cut while writing, or a truncated file)";
  } else {
    ending = storage::log_problem_text(how);
  }
  row("log end", ending);
  row("time span",
      have_time ? seconds(span_us) + " s (first timestamp " + std::to_string(first_us) +
                      " us, last " + std::to_string(last_us) + " us" +
                      (backwards > 0 ? "; " + std::to_string(backwards) + " step" +
                                           (backwards == 1 ? "" : "s") + " back in time not counted"
                                     : std::string()) +
                      ")"
                : std::string("none (no readable records)"));

  if (end != Status::kOutOfRange) return fail(source.name() + ": read failed");
  int code = kExitOk;
  for (const std::string& p : problems)
    warn(source.name() + ": record skipped: " + p);
  if (how == storage::LogProblem::kEndDamagedTail) {
    warn(source.name() + ": " + storage::log_problem_text(how));
  }
  if (backwards > 0) {
    warn(source.name() + ": the timestamps run backwards " + std::to_string(backwards) + " time" +
         (backwards == 1 ? "" : "s") + " (first at " + first_backwards +
         "); the time span counts only the steps forward");
  }
  if (const uint32_t slot = storage::damaged_commit_slot(source.device(), storage::kDreamKind);
      slot != 0) {
    warn(source.name() + ": " + storage::log_problem_text(storage::LogProblem::kCommitSlotDamaged) +
         " (slot " + std::to_string(slot) + ")");
    code = kExitFailure;
  }
  if (damaged > 0) code = kExitFailure;
  if (warn_if_truncated(source)) code = kExitFailure;
  return code;
}

}  // namespace

void add_dream_commands(CLI::App& app, Command* chosen) {
  CLI::App* dream = app.add_subcommand("dream", "Dream recordings (robot runs for replay)");
  dream->require_subcommand(1);
  auto o = std::make_shared<InfoOptions>();
  CLI::App* info = dream->add_subcommand(
      "info",
      "Print a recording's header (variant, camera, image size, wheel constants, "
      "sensors) and what it holds: snapshots, places, ground-truth poses, missed "
      "snapshots, damaged records, how the log ends, time span");
  info->add_option("FILE", o->source, "Dream file, or IMAGE:NAME for a volume file of a disk image")
      ->required();
  info->callback([chosen, o] { *chosen = [o] { return run_info(*o); }; });
}

}  // namespace seqslam::cli
