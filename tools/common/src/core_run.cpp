#include "seqslam_tools/core_run.h"

#include <memory>
#include <string>

#include "seqslam/seqslam.h"

namespace seqslam::tools {

Outcome<std::vector<CoreMatch>> run_core(const std::vector<GrayImage>& library,
                                         const std::vector<GrayImage>& queries,
                                         const LocaliserConfig& c) {
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) {
    return Error{std::string("invalid configuration: ") + config_issue_text(check.issue)};
  }
  if (library.size() > kCoreRunMaxPlaces) {
    return Error{"the library has " + std::to_string(library.size()) + " images; at most " +
                 std::to_string(kCoreRunMaxPlaces) + " are supported"};
  }
  if (c.sequence.seq_len > kCoreRunMaxSeq) return Error{"sequence length above 100"};
  // The same static-capacity storage the firmware uses, here on the heap of the PC.
  auto lib_storage = std::make_unique<PlaceLibraryStorage<kCoreRunMaxPlaces, kMaxPixels>>();
  auto matcher_storage =
      std::make_unique<DiagonalMatcherStorage<kCoreRunMaxPlaces, kCoreRunMaxSeq>>();
  std::vector<uint32_t> differences(kCoreRunMaxPlaces);
  PlaceLibrary places;
  DiagonalMatcherBuffers mb = matcher_storage->buffers();
  mb.ring = mb.ring.subspan(0, static_cast<size_t>(kCoreRunMaxPlaces) * c.sequence.seq_len);
  if (lib_storage->attach(places, c.image_size) != Status::kOk) {
    return Error{"the image size does not fit the library storage"};
  }
  Localiser localiser;
  const ConfigCheck cfg =
      localiser.configure(c, places, mb, Span<uint32_t>(differences.data(), differences.size()));
  if (!cfg.ok())
    return Error{std::string("configuration refused: ") + config_issue_text(cfg.issue)};
  const auto wrong_size = [&](const GrayImage& img) {
    return img.width != c.image_size.width || img.height != c.image_size.height;
  };
  uint32_t index = 0;
  for (const GrayImage& img : library) {
    if (wrong_size(img))
      return Error{"library image " + std::to_string(index) + " has another size"};
    const Status s = localiser.teach(ImageView{img.pixels.data(), c.image_size}, Pose2{}, index);
    if (s != Status::kOk) {
      return Error{"teaching library image " + std::to_string(index) +
                   " failed: " + status_name(s)};
    }
    ++index;
  }
  std::vector<CoreMatch> out;
  out.reserve(queries.size());
  for (const GrayImage& img : queries) {
    if (wrong_size(img))
      return Error{"query image " + std::to_string(out.size()) + " has another size"};
    Match m;
    const Status s = localiser.localise(ImageView{img.pixels.data(), c.image_size}, &m);
    if (s != Status::kOk) {
      return Error{"localising query image " + std::to_string(out.size()) +
                   " failed: " + status_name(s)};
    }
    CoreMatch cm;
    cm.place = m.place;
    cm.confidence = m.confidence.raw() / 65536.0;
    cm.localised = m.localised;
    out.push_back(cm);
  }
  return out;
}

}  // namespace seqslam::tools
