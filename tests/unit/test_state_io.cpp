// Saved run states (state_io.h): every field type goes out and comes back bit for bit in a
// fixed little-endian layout, and a state that is cut short, carries another section's tag,
// an enum or bool out of range, or meets a full sink is refused with a status.
#include "seqslam/state_io.h"

#include "ram_state.h"
#include "test.h"

namespace seqslam {
namespace {

enum class Colour : uint8_t { kRed = 0, kGreen = 1, kBlue = 2 };

struct Fields {
  uint8_t u8 = 0;
  uint16_t u16 = 0;
  uint32_t u32 = 0;
  uint64_t u64 = 0;
  int8_t i8 = 0;
  int16_t i16 = 0;
  int32_t i32 = 0;
  int64_t i64 = 0;
  bool flag = false;
  Q31_32 q{};
  UQ16_16 uq{};
  Angle angle{};
  Int128 wide{};
  Colour colour = Colour::kRed;
  uint32_t list[3] = {};

  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("TEST"));
    io.field(u8);
    io.field(u16);
    io.field(u32);
    io.field(u64);
    io.field(i8);
    io.field(i16);
    io.field(i32);
    io.field(i64);
    io.field(flag);
    io.field(q);
    io.field(uq);
    io.field(angle);
    io.field(wide);
    io.enumeration(colour, Colour::kBlue);
    io.array(Span<uint32_t>(list));
  }
};

Fields sample() {
  Fields f;
  f.u8 = 0xAB;
  f.u16 = 0xBEEF;
  f.u32 = 0x01020304u;
  f.u64 = 0x8877665544332211ull;
  f.i8 = -5;
  f.i16 = -30000;
  f.i32 = -2000000000;
  f.i64 = -(int64_t{1} << 62) - 7;
  f.flag = true;
  f.q = Q31_32::from_ratio(-7, 3);
  f.uq = UQ16_16::from_ratio(3, 4);
  f.angle = Angle{0xC0000001u};
  f.wide = Int128::from_parts(0xFFFFFFFFFFFFFFFEull, 0x0123456789ABCDEFull);
  f.colour = Colour::kBlue;
  f.list[0] = 1;
  f.list[1] = 0xFFFFFFFFu;
  f.list[2] = 42;
  return f;
}

// Bytes of the sample: tag 4, integers 1+2+4+8 + 1+2+4+8, bool 1, Q31.32 8, UQ16.16 4, angle
// 4, Int128 16, enum 1, list 12.
constexpr uint32_t kSampleBytes = 4 + 15 + 15 + 1 + 8 + 4 + 4 + 16 + 1 + 12;

TEST(StateIo, EveryFieldComesBackBitForBit) {
  static test::RamState<256> ram;
  Fields a = sample();
  StateOut out(ram);
  a.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  EXPECT_EQ(ram.size(), kSampleBytes);
  EXPECT_EQ(out.bytes(), kSampleBytes);
  Fields b;
  StateIn in(ram);
  b.state(in);
  ASSERT_EQ(in.status(), Status::kOk);
  EXPECT_EQ(b.u8, a.u8);
  EXPECT_EQ(b.u16, a.u16);
  EXPECT_EQ(b.u32, a.u32);
  EXPECT_EQ(b.u64, a.u64);
  EXPECT_EQ(b.i8, a.i8);
  EXPECT_EQ(b.i16, a.i16);
  EXPECT_EQ(b.i32, a.i32);
  EXPECT_EQ(b.i64, a.i64);
  EXPECT_EQ(b.flag, a.flag);
  EXPECT_EQ(b.q.raw(), a.q.raw());
  EXPECT_EQ(b.uq.raw(), a.uq.raw());
  EXPECT_EQ(b.angle.bam, a.angle.bam);
  EXPECT_EQ(b.wide.high64(), a.wide.high64());
  EXPECT_EQ(b.wide.low64(), a.wide.low64());
  EXPECT_EQ(static_cast<uint32_t>(b.colour), 2u);
  EXPECT_EQ(b.list[1], 0xFFFFFFFFu);
  EXPECT_EQ(b.list[2], 42u);
}

TEST(StateIo, TheLayoutIsLittleEndianWithoutPadding) {
  static test::RamState<256> ram;
  Fields a = sample();
  StateOut out(ram);
  a.state(out);
  EXPECT_EQ(ram.bytes[0], 'T');  // the tag, as written
  EXPECT_EQ(ram.bytes[3], 'T');
  EXPECT_EQ(ram.bytes[4], 0xAB);  // u8
  EXPECT_EQ(ram.bytes[5], 0xEF);  // u16, low byte first
  EXPECT_EQ(ram.bytes[6], 0xBE);
  EXPECT_EQ(ram.bytes[7], 0x04);  // u32
  EXPECT_EQ(ram.bytes[10], 0x01);
  EXPECT_EQ(ram.bytes[11], 0x11);  // u64
  EXPECT_EQ(ram.bytes[18], 0x88);
  EXPECT_EQ(ram.bytes[19], 0xFB);  // i8 -5, two's complement
}

TEST(StateIo, ADamagedOrShortStateIsRefused) {
  static test::RamState<256> ram;
  Fields a = sample();
  StateOut out(ram);
  a.state(out);
  const uint32_t full = ram.size();
  for (uint32_t cut = 0; cut < full; ++cut) {  // every length short of the whole
    ram.truncate(cut);
    Fields b;
    StateIn in(ram);
    b.state(in);
    EXPECT_EQ(in.status(), Status::kDataLoss) << "cut at " << cut;
  }
  ram.truncate(0);
  StateOut again(ram);
  a.state(again);
  struct Damage {
    uint32_t at;
    uint8_t value;
  };
  // Another section's tag; a bool of 2; an enum beyond its last value.
  for (const Damage d : {Damage{0, 'X'}, Damage{34, 2}, Damage{full - 13, 3}}) {
    const uint8_t kept = ram.bytes[d.at];
    ram.bytes[d.at] = d.value;
    ram.rewind();
    Fields b;
    StateIn in(ram);
    b.state(in);
    EXPECT_EQ(in.status(), Status::kDataLoss) << "byte " << d.at;
    ram.bytes[d.at] = kept;
  }
  ram.rewind();
  Fields b;
  StateIn in(ram);
  b.state(in);
  EXPECT_EQ(in.status(), Status::kOk);
}

TEST(StateIo, AFullSinkStopsTheSave) {
  static test::RamState<20> small;
  Fields a = sample();
  StateOut out(small);
  a.state(out);
  EXPECT_EQ(out.status(), Status::kResourceExhausted);
  EXPECT_LE(small.size(), 20u);
}

}  // namespace
}  // namespace seqslam
