// Power loss while recording a 200-place run (issue check): the power is cut after every
// write, in the middle of every write, and at every byte of the last two writes. Each
// time the recovery scan must bring back exactly the records completed before the cut, with
// their contents, and misread nothing after it - also when an older, longer recording of the
// same kind is left behind on the card.
#include <algorithm>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "journal_device.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream.h"

namespace seqslam::storage {
namespace {

constexpr uint32_t kPlaces = 200;
constexpr uint32_t kSnapshotsPerPlace = 5;
constexpr uint32_t kBlocks = 600;

using test::JournalDevice;

struct Item {
  DreamRecord type;
  uint32_t key;  // snapshot sequence or place index
  uint8_t fingerprint;
};

hal::SensorSnapshot snapshot(uint32_t i) {
  hal::SensorSnapshot s;
  s.sequence = i;
  s.timestamp_us = i * 10000u;
  s.flags = hal::SensorSnapshot::kHasEncoders;
  s.encoder_left = 0xFFFFFF00u + 23u * i;
  s.encoder_right = 0xFFFFFF00u + 24u * i;
  return s;
}

// Writes the recording; records, per completed record, the journal length and end offset.
std::vector<Item> record(hal::BlockDevice& device, uint32_t places, uint8_t salt,
                         std::vector<std::pair<size_t, uint64_t>>* completion,
                         const JournalDevice* journal) {
  DreamHeader h;
  h.mapping = hal::PipelineMapping::reduction(32, 16);
  DreamWriter w;
  EXPECT_EQ(w.create(device, h), Status::kOk);
  std::vector<Item> items;
  std::vector<uint8_t> gray(512);
  uint32_t seq = 0;
  for (uint32_t p = 0; p < places; ++p) {
    hal::SensorSnapshot last;
    for (uint32_t k = 0; k < kSnapshotsPerPlace; ++k) {
      last = snapshot(seq++);
      EXPECT_EQ(w.snapshot(last), Status::kOk);
      items.push_back({DreamRecord::kSnapshot, last.sequence, 0});
      if (completion != nullptr)
        completion->push_back({journal->journal.size(), w.log().end_offset()});
    }
    for (uint32_t k = 0; k < 512; ++k)
      gray[k] = static_cast<uint8_t>(p * 7 + k + salt);
    DreamPlace place;
    place.index = p;
    place.bus_sequence = last.sequence;
    place.size = ImageSize{32, 16};
    place.gray = gray.data();
    EXPECT_EQ(w.place(place), Status::kOk);
    items.push_back({DreamRecord::kPlace, p, gray[100]});
    if (completion != nullptr)
      completion->push_back({journal->journal.size(), w.log().end_offset()});
  }
  return items;
}

// Recovers the recording on `bytes`; returns how many items came back, checking each against
// `expected` in order. Any mismatch (a misread) fails the test.
uint32_t recover(std::vector<uint8_t>& bytes, const std::vector<Item>& expected) {
  hal::FakeBlockDevice card(Span<uint8_t>(bytes.data(), bytes.size()));
  std::vector<uint8_t> buffer(kDreamRecordMax);
  DreamReader r;
  if (r.open(card, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) return 0;
  DreamItem item;
  uint32_t n = 0;
  Status s;
  while ((s = r.next(&item)) == Status::kOk) {
    if (n >= expected.size()) {
      ADD_FAILURE() << "more items than were written";
      return n;
    }
    const Item& e = expected[n];
    const uint32_t key =
        item.type == DreamRecord::kSnapshot ? item.snapshot.sequence : item.place.index;
    const uint8_t fp = item.type == DreamRecord::kPlace ? item.place.gray[100] : 0;
    if (item.type != e.type || key != e.key || fp != e.fingerprint) {
      ADD_FAILURE() << "misread item " << n;
      return n;
    }
    ++n;
  }
  EXPECT_EQ(s, Status::kOutOfRange) << "recovery must end at the cut, not report damage";
  return n;
}

TEST(PowerLoss, TwoHundredPlaceRecordingLosesAtMostTheRecordBeingWritten) {
  // The card holds an older, longer recording of the same kind (session 1): its records sit
  // behind every cut point.
  std::vector<uint8_t> initial(kBlocks * hal::kBlockSize, 0xEE);
  std::vector<Item> old_items;
  {
    hal::FakeBlockDevice old(Span<uint8_t>(initial.data(), initial.size()));
    old_items = record(old, kPlaces + 40, 99, nullptr, nullptr);
  }
  // The new recording, journalled.
  JournalDevice device(initial);
  std::vector<std::pair<size_t, uint64_t>> completion;
  const std::vector<Item> items = record(device, kPlaces, 0, &completion, &device);
  const size_t writes = device.journal.size();
  // complete_at[i]: (write index, bytes into that write) at which record i's last byte landed:
  // each append ends with the record's last block, then its commit slot.
  std::vector<std::pair<size_t, uint32_t>> complete_at;
  for (const auto& c : completion) {
    complete_at.push_back(
        {c.first - 2, static_cast<uint32_t>((c.second - 1) % hal::kBlockSize + 1)});
  }

  std::vector<uint8_t> disk = initial;  // the card with writes [0, w) applied
  std::vector<uint8_t> trial;
  uint32_t tried = 0, lost = 0, misread_or_extra = 0;
  const uint32_t offsets[] = {0, 255};  // after the previous write; a torn write
  for (size_t w = 0; w < writes; ++w) {
    const JournalDevice::Write& write = device.journal[w];
    const bool final_writes = w + 2 >= writes;
    for (uint32_t cut = 0; cut < hal::kBlockSize; ++cut) {
      bool wanted = false;
      for (uint32_t o : offsets)
        wanted = wanted || o == cut;
      if (!wanted && !final_writes) continue;
      trial = disk;
      test::apply_write(trial, write, cut);
      uint32_t complete = 0;
      while (complete < complete_at.size() &&
             (complete_at[complete].first < w ||
              (complete_at[complete].first == w && complete_at[complete].second <= cut))) {
        ++complete;
      }
      ++tried;
      // A cut before the new header is complete leaves the old header in place (the first
      // bytes of both are identical) or a damaged one: then the old recording - still whole
      // on the card - or nothing is what a reader must find.
      if (std::equal(trial.begin(), trial.begin() + hal::kBlockSize, initial.begin())) {
        if (recover(trial, old_items) != old_items.size()) ++lost;
        continue;
      }
      const uint32_t recovered = recover(trial, items);
      if (recovered < complete) ++lost;
      if (recovered > complete) ++misread_or_extra;
    }
    test::apply_write(disk, write);
  }
  // And with every write done: everything is there.
  EXPECT_EQ(recover(disk, items), items.size());
  std::printf(
      "[ figure   ] power-loss cuts tried %u (over %zu writes of a %u-place, %zu-record "
      "recording), records lost %u, misread %u\n",
      tried, writes, kPlaces, items.size(), lost, misread_or_extra);
  EXPECT_EQ(lost, 0u);
  EXPECT_EQ(misread_or_extra, 0u);
  EXPECT_GT(tried, 2u * writes);
}

}  // namespace
}  // namespace seqslam::storage
