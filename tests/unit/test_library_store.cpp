// Place libraries on the SD card: teach to the card, load, localise from the card through a
// bounded cache (same matches as from RAM), and refusals that say why.
#include "seqslam/storage/library_store.h"

#include "seqslam/localiser.h"
#include "seqslam/storage/volume.h"
#include "storage_fixtures.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam::storage {
namespace {

constexpr uint32_t kPlaces = 120;
const ImageSize kSize{32, 16};
using World = test::SyntheticWorld<kPlaces * 2 + 64, 16>;

struct Card {
  test::FakeCard<400> card;
  Region meta;
  Region images;
  void reset() {
    card.reset();
    meta = Region(card.device, 0, 40);
    images = Region(card.device, 40, 360);
  }
};

struct Rig {
  PlaceInfo info[kPlaces];
  uint32_t sums[kPlaces];
  DiagonalMatcherStorage<kPlaces, 10> matcher;
  uint32_t differences[kPlaces];
  uint8_t cache[4 * 512];  // a 4-block cache: 3 images per read
  PlaceLibrary library;
  Localiser localiser;
  PlaceLibraryBuffers buffers() {
    return {Span<PlaceInfo>(info, kPlaces), Span<uint32_t>(sums, kPlaces)};
  }
};

LocaliserConfig config() {
  LocaliserConfig c;
  c.image_size = kSize;
  c.preprocess.method = Preprocessing::kHistEq;  // as written (the default before issue 33)
  c.sequence.seq_len = 10;
  c.sequence.window = 20;
  return c;
}

LibraryConfig library_config() {
  LibraryConfig c;
  c.image_size = kSize;
  c.mapping = hal::PipelineMapping::reduction(32, 16);
  return c;
}

World g_world;
uint8_t g_image[512];

void teach_to_card(Card& card, Rig& rig, StoredPlaceImages& stored, uint32_t places) {
  ASSERT_EQ(stored.create(card.meta, card.images, library_config(),
                          Span<uint8_t>(rig.cache, sizeof rig.cache)),
            Status::kOk);
  ASSERT_EQ(rig.library.configure(kSize, stored, rig.buffers()), Status::kOk);
  ASSERT_TRUE(rig.localiser
                  .configure(config(), rig.library, rig.matcher.buffers(),
                             Span<uint32_t>(rig.differences, kPlaces))
                  .ok());
  test::Rng rng(5);
  for (uint32_t p = 0; p < places; ++p) {
    g_world.render(p, 2, 0, 32, 256, 0, 3, rng, g_image);
    const Pose2 pose{Q31_32::from_ratio(p, 5), Q31_32::from_int(0), Angle{}};
    ASSERT_EQ(rig.localiser.teach(ImageView{g_image, kSize}, pose, p), Status::kOk);
  }
}

TEST(LibraryStore, LocalisingFromTheCardEqualsLocalisingFromRam) {
  static Card card;
  static Rig taught, loaded, ram;
  static PlaceLibraryStorage<kPlaces, 512> ram_storage;
  card.reset();
  g_world.generate(77, kPlaces * 2 + 64, 16);
  StoredPlaceImages teach_store;
  teach_to_card(card, taught, teach_store, kPlaces);
  EXPECT_EQ(teach_store.stored(), kPlaces);

  // Load it back.
  StoredPlaceImages stored;
  LibraryProblem problem = LibraryProblem::kNone;
  ASSERT_EQ(stored.load(card.meta, card.images, library_config(),
                        Span<uint8_t>(loaded.cache, sizeof loaded.cache), loaded.buffers(),
                        loaded.library, &problem),
            Status::kOk)
      << library_problem_text(problem);
  ASSERT_EQ(loaded.library.size(), kPlaces);
  EXPECT_FALSE(stored.recovered_tail());
  PlaceInfo info57;
  ASSERT_EQ(loaded.library.info(57, &info57), Status::kOk);
  EXPECT_EQ(info57.capture, 57u);
  EXPECT_EQ(info57.x.raw(), Q15_16::from_ratio(57, 5).raw());
  ASSERT_TRUE(loaded.localiser
                  .configure(config(), loaded.library, loaded.matcher.buffers(),
                             Span<uint32_t>(loaded.differences, kPlaces))
                  .ok());
  // The same library in RAM, taught from the same images.
  ASSERT_EQ(ram_storage.attach(ram.library, kSize), Status::kOk);
  ASSERT_TRUE(ram.localiser
                  .configure(config(), ram.library, ram.matcher.buffers(),
                             Span<uint32_t>(ram.differences, kPlaces))
                  .ok());
  test::Rng rng(5);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    g_world.render(p, 2, 0, 32, 256, 0, 3, rng, g_image);
    ASSERT_EQ(ram.localiser.teach(ImageView{g_image, kSize}, Pose2{}, p), Status::kOk);
  }
  test::Rng q(9);
  uint32_t correct = 0;
  const uint64_t before = stored.blocks_read();
  for (uint32_t p = 0; p < 60; ++p) {
    g_world.render(p + 30, 2, 1, 32, 200, 20, 5, q, g_image);
    Match a, b;
    ASSERT_EQ(loaded.localiser.localise(ImageView{g_image, kSize}, &a), Status::kOk);
    ASSERT_EQ(ram.localiser.localise(ImageView{g_image, kSize}, &b), Status::kOk);
    EXPECT_EQ(a.place, b.place);
    EXPECT_EQ(a.confidence.raw(), b.confidence.raw());
    EXPECT_EQ(a.cost, b.cost);
    const int32_t err = a.place - static_cast<int32_t>(p + 30);
    if (a.place >= 0 && err >= -1 && err <= 1) ++correct;
  }
  EXPECT_GT(correct, 45u);  // of the 51 steps with a full sequence (sanity, not the point)
  // Every step streamed the whole library through the 4-block cache.
  EXPECT_GE(stored.blocks_read() - before, 60u * (kPlaces * 512 / 512));
}

TEST(LibraryStore, RefusesAnotherConfigurationAndSaysWhich) {
  static Card card;
  static Rig rig, other;
  card.reset();
  StoredPlaceImages store;
  teach_to_card(card, rig, store, 20);
  StoredPlaceImages stored;
  LibraryProblem p = LibraryProblem::kNone;
  const Span<uint8_t> cache(other.cache, sizeof other.cache);
  LibraryConfig c = library_config();
  c.image_size = ImageSize{25, 20};
  EXPECT_EQ(stored.load(card.meta, card.images, c, cache, other.buffers(), other.library, &p),
            Status::kFailedPrecondition);
  EXPECT_EQ(p, LibraryProblem::kImageSize);
  c = library_config();
  c.preprocess.method = Preprocessing::kPatchNorm;
  EXPECT_EQ(stored.load(card.meta, card.images, c, cache, other.buffers(), other.library, &p),
            Status::kFailedPrecondition);
  EXPECT_EQ(p, LibraryProblem::kPreprocessing);
  c = library_config();
  c.mapping.by = 2;
  EXPECT_EQ(stored.load(card.meta, card.images, c, cache, other.buffers(), other.library, &p),
            Status::kFailedPrecondition);
  EXPECT_EQ(p, LibraryProblem::kMapping);
  // PN parameters do not matter when PN is not used.
  c = library_config();
  c.preprocess.patch.patch_width = 8;
  EXPECT_EQ(stored.load(card.meta, card.images, c, cache, other.buffers(), other.library, &p),
            Status::kOk);
  EXPECT_TRUE(library_problem_text(LibraryProblem::kMapping)[0] != '\0');
}

TEST(LibraryStore, RefusesDamagedOrUnpairedFiles) {
  static Card card;
  static Rig rig, other;
  card.reset();
  StoredPlaceImages store;
  teach_to_card(card, rig, store, 20);
  StoredPlaceImages stored;
  LibraryProblem p = LibraryProblem::kNone;
  const Span<uint8_t> cache(other.cache, sizeof other.cache);
  // A flipped bit in image 7.
  uint8_t* image7 = card.card.bytes + 40 * 512 + 512 + 7 * 512 + 33;
  *image7 ^= 1;
  EXPECT_EQ(stored.load(card.meta, card.images, library_config(), cache, other.buffers(),
                        other.library, &p),
            Status::kDataLoss);
  EXPECT_EQ(p, LibraryProblem::kImageChecksum);
  *image7 ^= 1;
  // Too many places for the RAM metadata of this firmware.
  PlaceLibraryBuffers small = other.buffers();
  small.info = small.info.subspan(0, 10);
  small.sums = small.sums.subspan(0, 10);
  EXPECT_EQ(stored.load(card.meta, card.images, library_config(), cache, small, other.library, &p),
            Status::kResourceExhausted);
  EXPECT_EQ(p, LibraryProblem::kTooManyPlaces);
  // Metadata of a newer library (its own images elsewhere) with the images of the old one.
  StoredPlaceImages again;
  Region scratch_images(card.card.device, 400 - 20, 20);
  ASSERT_EQ(again.create(card.meta, scratch_images, library_config(), cache), Status::kOk);
  EXPECT_EQ(stored.load(card.meta, card.images, library_config(), cache, other.buffers(),
                        other.library, &p),
            Status::kDataLoss);
  EXPECT_EQ(p, LibraryProblem::kNotPaired);
}

TEST(LibraryStore, PowerCutWhileTeachingKeepsTheCompletePlaces) {
  static Card card;
  static Rig rig, other;
  card.reset();
  hal::BlockFaults faults;
  faults.power_cut_after_byte = 6000;  // header blocks + a few places
  card.card.device.set_faults(faults);
  StoredPlaceImages store;
  ASSERT_EQ(store.create(card.meta, card.images, library_config(),
                         Span<uint8_t>(rig.cache, sizeof rig.cache)),
            Status::kOk);
  ASSERT_EQ(rig.library.configure(kSize, store, rig.buffers()), Status::kOk);
  uint32_t added = 0;
  for (uint32_t p = 0; p < 20; ++p) {
    for (uint32_t k = 0; k < 512; ++k)
      g_image[k] = test::place_pixel(p, k);
    if (rig.library.add(ImageView{g_image, kSize}, Pose2{}, p) != Status::kOk) break;
    ++added;
  }
  EXPECT_LT(added, 20u);
  card.card.device.restore_power();
  card.card.device.set_faults(hal::BlockFaults{});
  StoredPlaceImages stored;
  LibraryProblem p = LibraryProblem::kNone;
  ASSERT_EQ(stored.load(card.meta, card.images, library_config(),
                        Span<uint8_t>(other.cache, sizeof other.cache), other.buffers(),
                        other.library, &p),
            Status::kOk)
      << library_problem_text(p);
  // Every place whose add() returned kOk is there; the one being added may or may not be.
  EXPECT_GE(other.library.size(), added);
  EXPECT_LE(other.library.size(), added + 1);
  for (uint32_t i = 0; i < other.library.size(); ++i) {
    ImageView v;
    ASSERT_EQ(other.library.image(i, &v), Status::kOk);
    EXPECT_EQ(v.pixels[100], test::place_pixel(i, 100));
  }
}

// Teaching over two runs (an explore run continued from the card): a library taught 70
// places, then loaded for teaching with the rest, equals byte for byte on the card the
// library taught 120 places at once; also when a power cut interrupted the first run while
// it added place 71 (cut at every 61st byte of that place's writes: the image, the record,
// the commit): the second run continues after the complete places, overwriting the rest.
uint32_t add_places(PlaceLibrary& library, uint32_t from, uint32_t to) {
  for (uint32_t p = from; p < to; ++p) {
    for (uint32_t k = 0; k < 512; ++k)
      g_image[k] = test::place_pixel(p, k);
    const Pose2 pose{Q31_32::from_ratio(p, 5), Q31_32::from_int(0), Angle{}};
    if (library.add(ImageView{g_image, kSize}, pose, p) != Status::kOk) return p;
  }
  return to;
}

TEST(LibraryStore, TeachingContinuesAStoredLibrary) {
  static Card whole, parts;
  static Rig rig, first, second;
  whole.reset();
  StoredPlaceImages one;
  ASSERT_EQ(one.create(whole.meta, whole.images, library_config(),
                       Span<uint8_t>(rig.cache, sizeof rig.cache)),
            Status::kOk);
  ASSERT_EQ(rig.library.configure(kSize, one, rig.buffers()), Status::kOk);
  ASSERT_EQ(add_places(rig.library, 0, kPlaces), kPlaces);

  uint64_t before = 0, after = 0;  // bytes written before and after place 71
  for (uint64_t cut = 0;; cut += 61) {
    parts.reset();
    StoredPlaceImages b;
    ASSERT_EQ(b.create(parts.meta, parts.images, library_config(),
                       Span<uint8_t>(first.cache, sizeof first.cache)),
              Status::kOk);
    ASSERT_EQ(first.library.configure(kSize, b, first.buffers()), Status::kOk);
    ASSERT_EQ(add_places(first.library, 0, 70), 70u);
    before = parts.card.device.bytes_written();
    if (after > 0 && before + cut >= after) break;  // every cut inside place 71 tried
    hal::BlockFaults faults;
    faults.power_cut_after_byte = after > 0 ? before + cut : ~uint64_t{0};
    parts.card.device.set_faults(faults);
    (void)add_places(first.library, 70, 71);
    if (after == 0) after = parts.card.device.bytes_written();
    parts.card.device.restore_power();
    parts.card.device.set_faults(hal::BlockFaults{});

    StoredPlaceImages c;
    LibraryProblem lp = LibraryProblem::kNone;
    ASSERT_EQ(c.load_for_teaching(parts.meta, parts.images, library_config(),
                                  Span<uint8_t>(second.cache, sizeof second.cache),
                                  second.buffers(), second.library, &lp),
              Status::kOk)
        << library_problem_text(lp) << " cut " << static_cast<uint32_t>(cut);
    const uint32_t stored = second.library.size();
    EXPECT_TRUE(stored == 70 || stored == 71) << stored;
    ASSERT_EQ(add_places(second.library, stored, kPlaces), kPlaces);
    bool same = true;
    for (uint32_t i = 0; i < sizeof whole.card.bytes && same; ++i)
      same = whole.card.bytes[i] == parts.card.bytes[i];
    EXPECT_TRUE(same) << "cut after " << static_cast<uint32_t>(cut) << " bytes of place 71";
  }
  // Not a library that lost places: a damaged image is refused, not continued.
  parts.card.bytes[40 * 512 + 3 * 512 + 100] ^= 0x10;
  StoredPlaceImages d;
  LibraryProblem lp = LibraryProblem::kNone;
  EXPECT_EQ(d.load_for_teaching(parts.meta, parts.images, library_config(),
                                Span<uint8_t>(second.cache, sizeof second.cache), second.buffers(),
                                second.library, &lp),
            Status::kDataLoss);
  EXPECT_EQ(lp, LibraryProblem::kImageChecksum);
}

// Every block of the metadata log zeroed, and the log cut at every block: loading refuses
// with kDataLoss every time a block held a place's record or the cut removed one (never a
// smaller library that looks complete); a zeroed commit slot loses nothing.
TEST(LibraryStore, EveryCutAndEveryZeroedMetadataBlockIsRefused) {
  static Card card;
  static Rig rig, other;
  card.reset();
  StoredPlaceImages store;
  teach_to_card(card, rig, store, 20);
  uint64_t end = 0;
  {
    static uint8_t buffer[256];
    LogReader log;
    ASSERT_EQ(log.open(card.meta, kLibraryKind, nullptr, 0, nullptr,
                       Span<uint8_t>(buffer, sizeof buffer)),
              Status::kOk);
    RecordView v;
    while (log.next(&v) == Status::kOk) {
    }
    end = log.end_offset();
  }
  const uint32_t blocks = static_cast<uint32_t>((end + 511) / 512);
  const Span<uint8_t> cache(other.cache, sizeof other.cache);
  static uint8_t saved[512];
  for (uint32_t b = 1; b < blocks; ++b) {
    StoredPlaceImages stored;
    Region cut(card.card.device, 0, b);
    EXPECT_EQ(
        stored.load(cut, card.images, library_config(), cache, other.buffers(), other.library),
        Status::kDataLoss)
        << "cut at block " << b;
    uint8_t* block = card.card.bytes + b * 512;
    for (uint32_t k = 0; k < 512; ++k) {
      saved[k] = block[k];
      block[k] = 0;
    }
    const Status loaded = stored.load(card.meta, card.images, library_config(), cache,
                                      other.buffers(), other.library);
    if (b >= kFirstRecordOffset / 512) {
      EXPECT_EQ(loaded, Status::kDataLoss) << "zeroed block " << b;
    } else {
      EXPECT_EQ(loaded, Status::kOk) << "zeroed commit slot " << b;
      EXPECT_EQ(other.library.size(), 20u);
    }
    for (uint32_t k = 0; k < 512; ++k)
      block[k] = saved[k];
  }
}

}  // namespace
}  // namespace seqslam::storage
