#include "codec.h"

#include "seqslam/storage/settings_codec.h"

namespace seqslam::storage::codec {

void put_mapping(ByteWriter& w, const hal::PipelineMapping& m) {
  w.i32(m.a11.raw());
  w.i32(m.a12.raw());
  w.i32(m.a21.raw());
  w.i32(m.a22.raw());
  w.i16(m.bx);
  w.i16(m.by);
  w.u16(m.xmax);
  w.u16(m.ymax);
}

hal::PipelineMapping get_mapping(ByteReader& r) {
  hal::PipelineMapping m;
  m.a11 = Q15_16::from_raw(r.i32());
  m.a12 = Q15_16::from_raw(r.i32());
  m.a21 = Q15_16::from_raw(r.i32());
  m.a22 = Q15_16::from_raw(r.i32());
  m.bx = r.i16();
  m.by = r.i16();
  m.xmax = r.u16();
  m.ymax = r.u16();
  return m;
}

void put_preprocess(ByteWriter& w, const PreprocessConfig& p) {
  w.u8(static_cast<uint8_t>(p.method));
  w.u8(p.patch.patch_width);
  w.u8(p.patch.patch_height);
  w.u8(0);
  w.u16(p.patch.epsilon.raw());
  w.u16(p.patch.gain.raw());
}

PreprocessConfig get_preprocess(ByteReader& r) {
  PreprocessConfig p;
  p.method = static_cast<Preprocessing>(r.u8());
  p.patch.patch_width = r.u8();
  p.patch.patch_height = r.u8();
  r.skip(1);
  p.patch.epsilon = UQ8_8::from_raw(r.u16());
  p.patch.gain = UQ8_8::from_raw(r.u16());
  return p;
}

void put_odometry(ByteWriter& w, const OdometryConfig& c) {
  w.u32(c.ticks_per_revolution);
  w.i64(c.circumference_left.raw());
  w.i64(c.circumference_right.raw());
  w.i64(c.track_width.raw());
  w.u8(c.counter_bits);
  w.zeros(3);
  w.u32(c.max_ticks_per_update);
}

OdometryConfig get_odometry(ByteReader& r) {
  OdometryConfig c;
  c.ticks_per_revolution = r.u32();
  c.circumference_left = Q31_32::from_raw(r.i64());
  c.circumference_right = Q31_32::from_raw(r.i64());
  c.track_width = Q31_32::from_raw(r.i64());
  c.counter_bits = r.u8();
  r.skip(3);
  c.max_ticks_per_update = r.u32();
  return c;
}

void put_pose(ByteWriter& w, const Pose2& p) {
  w.i64(p.x.raw());
  w.i64(p.y.raw());
  w.u32(p.heading.bam);
}

Pose2 get_pose(ByteReader& r) {
  Pose2 p;
  p.x = Q31_32::from_raw(r.i64());
  p.y = Q31_32::from_raw(r.i64());
  p.heading = Angle{r.u32()};
  return p;
}

}  // namespace seqslam::storage::codec

namespace seqslam::storage::settings_detail {

void put(ByteWriter& w, const hal::PipelineMapping& m) {
  codec::put_mapping(w, m);
}
void put(ByteWriter& w, const PreprocessConfig& p) {
  codec::put_preprocess(w, p);
}
void put(ByteWriter& w, const OdometryConfig& o) {
  codec::put_odometry(w, o);
}
void get(ByteReader& r, hal::PipelineMapping* m) {
  *m = codec::get_mapping(r);
}
void get(ByteReader& r, PreprocessConfig* p) {
  *p = codec::get_preprocess(r);
}
void get(ByteReader& r, OdometryConfig* o) {
  *o = codec::get_odometry(r);
}

}  // namespace seqslam::storage::settings_detail
