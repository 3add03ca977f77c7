// seqslam convert images-to-dream|dream-to-images: between image sequences on the PC and
// dream recordings.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "seqslam/storage/dream.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/dataset.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/output_file.h"

namespace seqslam::cli {

namespace {

namespace fs = std::filesystem;

// --- images-to-dream --------------------------------------------------------------------

struct ToDreamOptions {
  std::string input;
  std::string out;
  std::string size;
  std::string variant = "reduced";
  uint32_t interval_us = hal::kSnapshotPeriodUs;
};

// Bytes of one reduced place record: record overhead, the fixed fields, the grey image.
constexpr uint64_t kReducedPlaceFixed = 16;

int run_to_dream(const ToDreamOptions& o) {
  if (o.variant != "reduced") {
    return usage_error("--variant " + o.variant +
                       ": a full recording needs sensor snapshots and odometry, which images do "
                       "not have; only 'reduced' recordings can be made from images");
  }
  uint16_t width = 0;
  uint16_t height = 0;
  const std::string size_error = parse_image_size(o.size, &width, &height);
  if (!size_error.empty()) return usage_error("--size: " + size_error);

  tools::InputFiles inputs;  // INPUT and the images it lists: OUT must be none of them
  inputs.add_sequence(o.input);
  if (const std::string clash = inputs.clash(o.out); !clash.empty()) return usage_error(clash);
  const tools::LoadedSequence loaded = tools::load_sequence(o.input, width, height);
  if (!loaded) return fail(loaded.error());
  const std::vector<tools::GrayImage>& images = loaded.value().images;
  const uint64_t pixels = static_cast<uint64_t>(width) * height;
  const uint64_t bytes = storage::kFirstRecordOffset +
                         images.size() * (storage::kRecordOverhead + kReducedPlaceFixed + pixels);
  const uint64_t blocks = blocks_for(bytes);
  if (blocks > UINT32_MAX) return fail(o.input + ": too many images for one dream file");

  // Written to a temporary file renamed over OUT at the end (a device in place): a failure
  // leaves no partial recording and OUT as it was.
  tools::OutputPath out;
  if (const std::string error = out.open(o.out); !error.empty()) return fail(error);
  hal::FileBlockDevice device;
  auto give_up = [&](const std::string& message) {
    const std::string shown = out.shown(message);  // OUT, not the temporary's name
    device.close();
    out.discard();
    return fail(shown);
  };
  if (device.create(out.write_path(), static_cast<uint32_t>(blocks)) != Status::kOk) {
    return give_up(device.error());
  }
  storage::DreamHeader header;
  header.variant = storage::DreamVariant::kReduced;
  header.colour = storage::ColourFormat::kNone;
  header.mapping = hal::PipelineMapping::reduction(width, height);
  header.has_head = false;
  storage::DreamWriter writer;
  storage::DreamProblem problem = storage::DreamProblem::kNone;
  if (writer.create(device, header, &problem) != Status::kOk) {
    return give_up(o.out + ": cannot start the recording: " +
                   (problem == storage::DreamProblem::kLog
                        ? std::string(storage::log_problem_text(writer.log_problem()))
                        : std::string(storage::dream_problem_text(problem))));
  }
  for (size_t i = 0; i < images.size(); ++i) {
    storage::DreamPlace place;
    place.index = static_cast<uint32_t>(i);
    place.timestamp_us = static_cast<uint32_t>(uint64_t{i} * o.interval_us);
    place.size = ImageSize{width, height};
    place.gray = images[i].pixels.data();
    if (writer.place(place, &problem) != Status::kOk) {
      const std::string why = problem == storage::DreamProblem::kLog
                                  ? std::string(storage::log_problem_text(writer.log_problem()))
                                  : std::string(storage::dream_problem_text(problem));
      return give_up(o.out + ": cannot write place " + std::to_string(i) + " (" +
                     loaded.value().paths[i] + "): " + why +
                     (device.error().empty() ? "" : " (" + device.error() + ")"));
    }
  }
  if (device.sync() != Status::kOk) return give_up(device.error());
  device.close();
  if (const std::string error = out.commit(); !error.empty()) return fail(error);
  std::printf("%s: %zu places of %ux%u pixels (reduced recording), %llu bytes\n", o.out.c_str(),
              images.size(), width, height,
              static_cast<unsigned long long>(blocks) * hal::kBlockSize);
  return kExitOk;
}

// --- dream-to-images --------------------------------------------------------------------

struct ToImagesOptions {
  std::string input;
  std::string outdir;
  std::string format = "png";
  std::string index;
};

std::string place_file_name(uint32_t index, const std::string& format) {
  char name[32];
  std::snprintf(name, sizeof name, "place_%06u.%s", index, format.c_str());
  return name;
}

// Refuses outputs of dream-to-images that are its input: the index file, and the images'
// names (OUTDIR/place_*.FORMAT) when OUTDIR exists. Returns "" or the message.
std::string to_images_clash(const ToImagesOptions& o) {
  tools::InputFiles inputs;
  inputs.add(log_source_file(o.input));
  if (!o.index.empty()) {
    const std::string clash = inputs.clash(o.index);
    if (!clash.empty()) return clash;
  }
  std::error_code ec;
  for (fs::directory_iterator it(o.outdir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("place_", 0) != 0 || it->path().extension() != "." + o.format) continue;
    const std::string clash = inputs.clash(it->path().string());
    if (!clash.empty()) return clash;
  }
  return {};
}

int run_to_images(const ToImagesOptions& o) {
  if (const std::string clash = to_images_clash(o); !clash.empty()) return usage_error(clash);
  LogSource source;
  const std::string error = source.open(o.input, nullptr);
  if (!error.empty()) return fail(error);
  std::vector<uint8_t> buffer;
  storage::DreamReader reader;
  const std::string open_error = open_dream(source, reader, buffer);
  if (!open_error.empty()) return fail(open_error);
  std::error_code ec;
  fs::create_directories(o.outdir, ec);
  if (ec || !fs::is_directory(o.outdir, ec)) {
    return fail(o.outdir + ": cannot create the directory" + (ec ? ": " + ec.message() : ""));
  }

  std::vector<std::string> written;
  uint32_t damaged = 0;
  Status end = Status::kOk;
  for (;;) {
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kOk) {
      if (item.type != storage::DreamRecord::kPlace &&
          item.type != storage::DreamRecord::kReducedPlace) {
        continue;  // snapshots and ground-truth poses
      }
      const storage::DreamPlace& p = item.place;
      tools::GrayImage image;
      image.width = p.size.width;
      image.height = p.size.height;
      image.pixels.assign(p.gray, p.gray + p.size.pixels());
      const std::string path = (fs::path(o.outdir) / place_file_name(p.index, o.format)).string();
      std::string save_error;
      const bool saved = o.format == "pgm" ? tools::save_pgm(path, image, &save_error)
                                           : tools::save_png(path, image, &save_error);
      if (!saved) return fail(save_error);
      written.push_back(path);
    } else if (s == Status::kDataLoss) {
      ++damaged;
      warn(source.name() + ": record skipped: " +
           (reader.problem() == storage::DreamProblem::kLog
                ? std::string(storage::log_problem_text(reader.log_problem())) + " (at byte " +
                      std::to_string(reader.problem_offset()) + ")"
                : std::string(storage::dream_problem_text(reader.problem()))));
    } else if (s == Status::kResourceExhausted) {
      ++damaged;
      warn(source.name() +
           ": record skipped: " + storage::log_problem_text(storage::LogProblem::kRecordTooLarge));
    } else {
      end = s;
      break;
    }
  }
  if (end != Status::kOutOfRange) {
    return fail(source.name() + ": read failed after " + std::to_string(written.size()) +
                " places (" + status_name(end) + ")");
  }

  if (!o.index.empty()) {
    const fs::path index_dir = fs::absolute(fs::path(o.index)).parent_path();
    std::string text;
    for (const std::string& path : written) {
      const fs::path relative = fs::absolute(fs::path(path))
                                    .lexically_normal()
                                    .lexically_relative(index_dir.lexically_normal());
      text += relative.generic_string() + "\n";
    }
    const std::string write_error = tools::write_output(o.index, text);
    if (!write_error.empty()) return fail(write_error);
  }

  const storage::DreamHeader& h = reader.header();
  std::printf(
      "%s: %zu places of %ux%u pixels written as %s, %u snapshots not written, %u "
      "damaged records skipped\n",
      o.outdir.c_str(), written.size(), h.mapping.xmax, h.mapping.ymax, o.format.c_str(),
      reader.snapshots(), damaged);
  int code = kExitOk;
  if (reader.log_problem() == storage::LogProblem::kEndDamagedTail) {
    warn(source.name() + ": " + storage::log_problem_text(reader.log_problem()));
  }
  if (damaged > 0) {
    warn(source.name() + ": " + std::to_string(damaged) + " damaged record(s) skipped");
    code = kExitFailure;
  }
  if (warn_if_truncated(source)) code = kExitFailure;
  return code;
}

}  // namespace

void add_convert_commands(CLI::App& app, Command* chosen) {
  CLI::App* convert =
      app.add_subcommand("convert", "Convert between image sequences and dream recordings");
  convert->require_subcommand(1);

  auto a = std::make_shared<ToDreamOptions>();
  CLI::App* to_dream = convert->add_subcommand(
      "images-to-dream",
      "Reduce every image of a sequence to WxH (the FPGA's area averaging) and write them as "
      "the places of a new reduced dream recording, sized to fit exactly");
  to_dream
      ->add_option("INPUT", a->input,
                   "A directory of images (.png .pgm .ppm .jpg .jpeg .bmp, sorted by name) or an "
                   "index file listing image paths, one per line")
      ->required();
  to_dream->add_option("OUT", a->out, "Dream file to write (overwritten)")->required();
  to_dream
      ->add_option("--size", a->size,
                   "Image size in pixels after reduction, W * H <= 512 (the FPGA pixel buffer); "
                   "the header's mapping is the plain reduction of the camera frame to it")
      ->type_name("WxH")
      ->required()
      ->check(CLI::Validator(
          [](std::string& s) {
            uint16_t w = 0;
            uint16_t h = 0;
            return parse_image_size(s, &w, &h);
          },
          ""));
  to_dream
      ->add_option("--variant", a->variant,
                   "Recording variant: reduced (places only). 'full' needs sensor snapshots "
                   "and odometry and is refused for images")
      ->capture_default_str()
      ->check(CLI::IsMember({"reduced", "full"}));
  to_dream
      ->add_option("--interval-us", a->interval_us,
                   "Timestamp step between consecutive places in microseconds (images carry "
                   "no time; the default is one sensor-bus period). Timestamps are the bus's "
                   "32-bit microsecond clock and wrap as it does; intervals stay exact. Below "
                   "2^31 (35.8 minutes): a longer step reads as a step back in time")
      ->type_name("US")
      ->check(tools::whole<uint32_t>(0, 2147483647))
      ->capture_default_str();
  to_dream->callback([chosen, a] { *chosen = [a] { return run_to_dream(*a); }; });

  auto b = std::make_shared<ToImagesOptions>();
  CLI::App* to_images = convert->add_subcommand(
      "dream-to-images",
      "Write every place's grey image of a dream recording as OUTDIR/place_NNNNNN.png "
      "(the place index, zero-padded to 6 digits)");
  to_images
      ->add_option("IN", b->input, "Dream file, or IMAGE:NAME for a volume file of a disk image")
      ->required();
  to_images->add_option("OUTDIR", b->outdir, "Output directory (created if missing)")->required();
  to_images->add_option("--format", b->format, "Image file format")
      ->capture_default_str()
      ->check(CLI::IsMember({"png", "pgm"}));
  to_images
      ->add_option("--index", b->index,
                   "Also write an index file listing the images in order, one path per "
                   "line, relative to the index file's directory (usable as INPUT of "
                   "images-to-dream)")
      ->type_name("FILE");
  to_images->callback([chosen, b] { *chosen = [b] { return run_to_images(*b); }; });
}

}  // namespace seqslam::cli
