// The loop-closure gate: configuration and statuses; the confirmation run (pending until the
// confirm-th consistent, advancing match, closures after it); rejection by the position and
// the heading bound, and the position bound growing with the distance driven since the last
// fix; aliasing vs novelty by the known places near the prediction; relocalisation after a
// run of confident matches that odometry cannot explain; predictions from the fix while the
// graph is not yet optimised; the counters.
#include "seqslam/loop_closure.h"

#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kNodes = 160;

Pose2 pose_at(int64_t x_cm, int64_t y_cm, int64_t heading_deg = 0) {
  return Pose2{Q31_32::from_ratio(x_cm, 100), Q31_32::from_ratio(y_cm, 100),
               Angle::from_degrees(heading_deg)};
}

// A graph of odometry nodes only (no closures: estimates are the odometry poses). One
// static instance shared by the tests (12.8 KB: the target's RAM is 64 KB), emptied by each.
struct Graph {
  PoseGraphStorage<kNodes, kNodes> storage;
  PoseGraph graph;
  uint32_t add(const Pose2& p) {
    const Result<uint32_t> r = graph.add_node(p, graph.node_count());
    EXPECT_TRUE(r.ok());
    return r.value();
  }
};

Graph& fresh_graph() {
  static Graph g;
  EXPECT_EQ(g.graph.configure(PoseGraphConfig{}, g.storage.buffers()), Status::kOk);
  return g;
}

Match confident(int32_t place) {
  Match m;
  m.place = place;
  m.confidence = UQ16_16::from_ratio(1, 2);
  m.localised = true;
  return m;
}

Match unsure(int32_t place) {
  Match m;
  m.place = place;
  m.confidence = UQ16_16::from_ratio(95, 100);
  m.localised = false;
  return m;
}

LoopClosureDecision decide(LoopClosureGate& gate, const Graph& g, const Match& m, uint32_t node,
                           const Pose2& odometry, uint32_t known) {
  LoopClosureQuery q;
  q.match = m;
  q.node = node;
  q.matched_node = m.place;
  q.known_nodes = known;
  q.odometry = odometry;
  LoopClosureDecision d;
  EXPECT_EQ(gate.decide(g.graph, q, &d), Status::kOk);
  return d;
}

TEST(LoopClosure, ConfigurationAndStatuses) {
  LoopClosureGate gate;
  Graph& g = fresh_graph();
  g.add(pose_at(0, 0));
  LoopClosureQuery q;
  LoopClosureDecision d;
  EXPECT_EQ(gate.decide(g.graph, q, &d), Status::kFailedPrecondition);
  LoopClosureConfig bad;
  bad.confirm = 0;
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  bad = LoopClosureConfig{};
  bad.drift_rate = UQ16_16::from_ratio(3, 2);
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  bad = LoopClosureConfig{};
  bad.drift_base = Q31_32::from_int(-1);
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  bad = LoopClosureConfig{};
  bad.heading_base = Angle::from_degrees(181);
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  EXPECT_FALSE(gate.configured());
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);
  EXPECT_EQ(gate.decide(g.graph, q, nullptr), Status::kInvalidArgument);
  q.node = 1;
  EXPECT_EQ(gate.decide(g.graph, q, &d), Status::kOutOfRange);
  q.node = 0;
  q.matched_node = 1;
  EXPECT_EQ(gate.decide(g.graph, q, &d), Status::kOutOfRange);
  q.matched_node = -1;
  q.known_nodes = 2;
  EXPECT_EQ(gate.decide(g.graph, q, &d), Status::kOutOfRange);
  q.known_nodes = 0;
  ASSERT_EQ(gate.decide(g.graph, q, &d), Status::kOk);
  EXPECT_EQ(d.kind, LoopClosureClass::kNoSequence);
  EXPECT_EQ(gate.stats().decisions[0], 1u);
  EXPECT_STREQ(loop_closure_class_name(LoopClosureClass::kRejectedInconsistent),
               "rejected_inconsistent");
}

// Lap 1: nodes 0..59 along x every 20 cm. Lap 2 starts again at x = 0 (odometry returned to
// its start), offset 30 cm to the side; each lap-2 place matches the lap-1 place at its x.
TEST(LoopClosure, ConfirmationThenClosures) {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 60; ++k)
    g.add(pose_at(20 * k, 0));
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);  // confirm 3
  for (uint32_t k = 0; k < 60; ++k) {
    (void)decide(gate, g, unsure(-1), k, pose_at(20 * k, 0), 0);
  }
  for (int64_t k = 0; k < 10; ++k) {
    const Pose2 odo = pose_at(20 * k, 30);
    const uint32_t node = g.add(odo);
    const LoopClosureDecision d =
        decide(gate, g, confident(static_cast<int32_t>(k)), node, odo, 50);
    if (k < 2) {
      EXPECT_EQ(d.kind, LoopClosureClass::kPending);
      EXPECT_EQ(d.streak, k + 1);
    } else {
      EXPECT_EQ(d.kind, LoopClosureClass::kClosure);
    }
    if (k <= 2) {
      // Dead reckoning until the first closure: the 30 cm offset between the laps.
      EXPECT_LE(d.distance.raw(), Q31_32::from_ratio(31, 100).raw());
      EXPECT_GE(d.distance.raw(), Q31_32::from_ratio(29, 100).raw());
    } else {
      // Then predicted from the fix (the matched place plus the odometry since): the offset
      // is gone, whatever the optimiser has done with the graph.
      EXPECT_LE(d.distance.raw(), Q31_32::from_ratio(1, 1000).raw());
    }
  }
  EXPECT_EQ(gate.stats().decisions[static_cast<uint32_t>(LoopClosureClass::kPending)], 2u);
  EXPECT_EQ(gate.stats().decisions[static_cast<uint32_t>(LoopClosureClass::kClosure)], 8u);
  EXPECT_TRUE(gate.has_fix());
  EXPECT_EQ(gate.fix_node(), 9u);
  EXPECT_EQ(gate.travelled().raw(), 0);
}

TEST(LoopClosure, TheCurrentImageMustNotRankTheMatchedPlaceAmongTheLeastLikeIt) {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 60; ++k)
    g.add(pose_at(20 * k, 0));
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);  // max_image_rank 0.9
  for (uint32_t k = 0; k < 60; ++k)
    (void)decide(gate, g, unsure(-1), k, pose_at(20 * k, 0), 0);
  // 50 known places: 44 closer (88 %) is accepted, 46 (92 %) is not.
  for (int64_t k = 0; k < 6; ++k) {
    const Pose2 odo = pose_at(20 * k, 30);
    LoopClosureQuery q;
    q.match = confident(static_cast<int32_t>(k));
    q.node = g.add(odo);
    q.matched_node = q.match.place;
    q.known_nodes = 50;
    q.odometry = odo;
    q.closer_places = k == 4 ? 46u : 44u;
    LoopClosureDecision d;
    ASSERT_EQ(gate.decide(g.graph, q, &d), Status::kOk);
    if (k == 4) {
      EXPECT_EQ(d.kind, LoopClosureClass::kRejectedInconsistent);
      EXPECT_EQ(d.reject, LoopClosureReject::kImage);
    } else {
      EXPECT_EQ(d.kind, k < 2 || k == 5 ? LoopClosureClass::kPending : LoopClosureClass::kClosure);
    }
  }
  EXPECT_EQ(gate.stats().rejected_image, 1u);

  // count_closer over a difference row.
  const uint32_t row[6] = {50, 10, 30, 30, 70, 20};
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 6, 2), 2u);  // 10 and 20
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 6, 1), 0u);
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 6, 4), 5u);
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 4, 4), 0u);  // place not known
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 4, 0), 3u);  // among the first 4
  EXPECT_EQ(count_closer(Span<const uint32_t>(row, 6), 7, 1), 0u);  // row too short
}

TEST(LoopClosure, TheRobotAndTheMatchedPlacesMustTurnAlike) {
  // Known places along a straight line; the robot drives beside them, then turns off to the
  // left (5 degrees a place) while its matches keep running straight on, as where a route
  // leaves the one it was matched to.
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 60; ++k)
    g.add(pose_at(20 * k, 0));
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);  // turn_tolerance 20 degrees
  for (uint32_t k = 0; k < 60; ++k)
    (void)decide(gate, g, unsure(-1), k, pose_at(20 * k, 0), 0);
  int first_rejected = -1;
  for (int64_t k = 0; k < 12; ++k) {
    const int64_t heading = k < 4 ? 0 : 5 * (k - 3);
    const Pose2 odo = pose_at(20 * k, 30, heading);
    const uint32_t node = g.add(odo);
    const LoopClosureDecision d =
        decide(gate, g, confident(static_cast<int32_t>(k)), node, odo, 50);
    if (d.kind == LoopClosureClass::kRejectedInconsistent && first_rejected < 0) {
      first_rejected = static_cast<int>(k);
      EXPECT_EQ(d.reject, LoopClosureReject::kHeading);
    }
  }
  // The run began at k = 0; the robot has turned 25 degrees at k = 8 (20 at k = 7: still
  // within the tolerance), and the gate's own heading bound (30 degrees) alone would still
  // accept it.
  EXPECT_EQ(first_rejected, 8);
}

TEST(LoopClosure, MatchesThatDoNotAdvanceAreNotConfirmed) {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 60; ++k)
    g.add(pose_at(20 * k, 0));
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);
  // Alternating matched places 3 and 1 (a step back each time): never a run of 3.
  const int32_t places[] = {3, 1, 3, 1, 3, 1};
  for (int64_t k = 0; k < 6; ++k) {
    const Pose2 odo = pose_at(20 * k, 0);
    const uint32_t node = g.add(odo);
    const LoopClosureDecision d = decide(gate, g, confident(places[k]), node, odo, 50);
    EXPECT_EQ(d.kind, LoopClosureClass::kPending);
  }
  EXPECT_EQ(gate.stats().decisions[static_cast<uint32_t>(LoopClosureClass::kClosure)], 0u);
}

TEST(LoopClosure, PositionBoundGrowsWithDistanceDriven) {
  Graph& g = fresh_graph();
  // 300 m of straight driving in 20 cm steps is too many nodes; 1 m steps make the same
  // distance for the bound (steps are measured, not counted).
  for (int64_t k = 0; k < 150; ++k)
    g.add(pose_at(100 * k, 0));
  LoopClosureConfig c;
  c.confirm = 1;
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(c), Status::kOk);
  // Node 5 (x = 5 m), seen from x = 8 m after 8 m: bound 1 + 0.4 = 1.4 m < 3 m: rejected.
  for (uint32_t k = 0; k <= 8; ++k)
    (void)decide(gate, g, unsure(-1), k, pose_at(100 * k, 0), 0);
  LoopClosureQuery q;
  q.match = confident(5);
  q.node = 8;
  q.matched_node = 5;
  q.known_nodes = 1;
  q.odometry = pose_at(800, 0);
  LoopClosureDecision d;
  ASSERT_EQ(gate.decide(g.graph, q, &d), Status::kOk);  // no step: same odometry again
  EXPECT_EQ(d.kind, LoopClosureClass::kRejectedInconsistent);
  EXPECT_EQ(d.reject, LoopClosureReject::kPosition);
  EXPECT_EQ(d.bound.raw(),
            (Q31_32::from_int(1) + mul_sat<Q31_32>(c.drift_rate, Q31_32::from_int(8))).raw());
  EXPECT_EQ(d.travelled.raw(), Q31_32::from_int(8).raw());
  // After 50 m the bound is 3.5 m: node 47 seen from x = 50 m is 3 m off: accepted.
  for (uint32_t k = 9; k <= 50; ++k)
    (void)decide(gate, g, unsure(-1), k, pose_at(100 * k, 0), 0);
  q.match = confident(47);
  q.node = 50;
  q.matched_node = 47;
  q.odometry = pose_at(5000, 0);
  ASSERT_EQ(gate.decide(g.graph, q, &d), Status::kOk);
  EXPECT_EQ(d.kind, LoopClosureClass::kClosure);
  EXPECT_EQ(gate.stats().rejected_position, 1u);
}

TEST(LoopClosure, HeadingBound) {
  Graph& g = fresh_graph();
  g.add(pose_at(0, 0, 90));  // node 0: same spot, heading north
  g.add(pose_at(0, 0, 0));   // node 1: the robot, heading east
  LoopClosureConfig c;
  c.confirm = 1;
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(c), Status::kOk);
  const LoopClosureDecision d = decide(gate, g, confident(0), 1, pose_at(0, 0, 0), 1);
  EXPECT_EQ(d.kind, LoopClosureClass::kRejectedInconsistent);
  EXPECT_EQ(d.reject, LoopClosureReject::kHeading);
  EXPECT_EQ(d.heading_error, signed_diff(Angle::from_degrees(90), Angle{}));
  EXPECT_EQ(gate.stats().rejected_heading, 1u);
}

TEST(LoopClosure, AliasingNearKnownPlacesNoveltyElsewhere) {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 20; ++k)
    g.add(pose_at(20 * k, 0));   // known: x 0..3.8 m
  g.add(pose_at(100, 50));       // node 20: 0.5 m beside node 5
  g.add(pose_at(100, 1000));     // node 21: 10 m away from everything
  g.add(pose_at(100, 50, 180));  // node 22: beside node 5 but facing the other way
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);
  EXPECT_EQ(decide(gate, g, unsure(3), 20, pose_at(100, 50), 20).kind, LoopClosureClass::kAliasing);
  EXPECT_EQ(decide(gate, g, unsure(3), 21, pose_at(100, 1000), 20).kind,
            LoopClosureClass::kNovelty);
  EXPECT_EQ(decide(gate, g, unsure(3), 22, pose_at(100, 50, 180), 20).kind,
            LoopClosureClass::kNovelty);
  // Without known places, everything is new.
  LoopClosureGate fresh;
  ASSERT_EQ(fresh.configure(LoopClosureConfig{}), Status::kOk);
  EXPECT_EQ(decide(fresh, g, unsure(3), 20, pose_at(100, 50), 0).kind, LoopClosureClass::kNovelty);
}

// Kidnapped: odometry says x = 0.2 k, the robot is really on the known places 100 + k at
// x = 20 m + 0.2 k. Without relocalisation every match is rejected; with it, the third in a
// row relocalises and the next consistent match closes.
TEST(LoopClosure, Relocalisation) {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 150; ++k)
    g.add(pose_at(20 * k, 0));  // known places along x 0..29.8 m
  for (int relocalise = 0; relocalise <= 3; relocalise += 3) {
    LoopClosureConfig c;
    c.relocalise = static_cast<uint16_t>(relocalise);
    c.relocalise_turn = Angle{};  // a straight line: no turn asked for (see the next test)
    LoopClosureGate gate;
    ASSERT_EQ(gate.configure(c), Status::kOk);
    uint32_t closures = 0;
    for (int64_t k = 0; k < 8; ++k) {
      const Pose2 odo = pose_at(20 * k, 0);
      const LoopClosureDecision d = decide(gate, g, confident(static_cast<int32_t>(100 + k)),
                                           static_cast<uint32_t>(k), odo, 150);
      if (relocalise == 0 || k < 2) {
        EXPECT_EQ(d.kind, LoopClosureClass::kRejectedInconsistent);
      } else if (k == 2) {
        EXPECT_EQ(d.kind, LoopClosureClass::kRelocalised);
        EXPECT_EQ(gate.fix_node(), 102u);
      } else {
        EXPECT_EQ(d.kind, LoopClosureClass::kClosure);
        // Predicted from the fix: node 102's estimate plus the odometry since.
        EXPECT_LE(d.distance.raw(), Q31_32::from_ratio(1, 1000).raw());
        ++closures;
      }
    }
    EXPECT_EQ(closures, relocalise == 0 ? 0u : 5u);
  }
}

// Known places along an L: 100 along +x, then 60 along +y after a left turn.
Graph& l_graph() {
  Graph& g = fresh_graph();
  for (int64_t k = 0; k < 100; ++k)
    g.add(pose_at(20 * k, 0, 0));
  for (int64_t k = 1; k <= 60; ++k)
    g.add(pose_at(1980, 20 * k, 90));
  return g;
}

// The robot's odometry where it drives the matched places 80 + k (k = 0..) of the L, but 50 m
// away in its own frame (a kidnap): along x, then left up y at the same step as the L turns.
// `turn_sign` -1 makes it turn right instead; `straight` keeps it going along x.
Pose2 kidnapped_odometry(int64_t k, int turn_sign, bool straight) {
  if (straight || k < 20) return pose_at(5000 + 20 * k, 0, 0);
  return pose_at(5000 + 20 * 19, turn_sign * 20 * (k - 19), turn_sign * 90);
}

TEST(LoopClosure, RelocalisationNeedsATurnBothAgreeOn) {
  struct Case {
    const char* what;
    int turn_sign;
    bool straight;
    bool confident_turn;  // false: the matches around the corner are unconfident
    bool relocalises;
  };
  const Case cases[] = {
      {"straight: a corridor aliasing itself looks the same", 1, true, true, false},
      {"odometry turns right where the places turn left", -1, false, true, false},
      {"both turn left", 1, false, true, true},
      {"both turn left, unconfident round the corner", 1, false, false, true},
  };
  for (const Case& t : cases) {
    Graph& g = l_graph();
    LoopClosureConfig c;
    c.relocalise = 5;  // relocalise_turn: the default 45 degrees
    LoopClosureGate gate;
    ASSERT_EQ(gate.configure(c), Status::kOk);
    int relocalised_at = -1;
    for (int64_t k = 0; k < 40 && relocalised_at < 0; ++k) {
      // The matched places follow the robot along the L (places 80..119), or, driving
      // straight, along the first leg (60..99).
      const int32_t place = static_cast<int32_t>((t.straight ? 60 : 80) + k);
      const bool near_corner = k >= 17 && k <= 23;
      const Match m = !t.confident_turn && near_corner ? unsure(place) : confident(place);
      const LoopClosureDecision d = decide(gate, g, m, static_cast<uint32_t>(k),
                                           kidnapped_odometry(k, t.turn_sign, t.straight), 160);
      if (d.kind == LoopClosureClass::kRelocalised) relocalised_at = static_cast<int>(k);
    }
    if (t.relocalises) {
      // Once both have turned (k 20: the turn is one step) with 5 confident matches in the
      // trail; with the corner unconfident, at the first confident match after it (k 24).
      EXPECT_GE(relocalised_at, t.confident_turn ? 20 : 24) << t.what;
      EXPECT_LE(relocalised_at, 30) << t.what;
    } else {
      EXPECT_EQ(relocalised_at, -1) << t.what;
    }
  }
}

TEST(LoopClosure, ShiftToHeadingMatchesDoubleReference) {
  // -shift * hfov / width in binary angle units, against double arithmetic: rounded to
  // nearest, so within 1 unit (2^-32 turn) after the truncated low product.
  const int32_t shifts[] = {
      0,          1,           -1,       65536, -65536, 3 * 65536 + 12345, -(5 * 65536 + 999),
      16 * 65536, -16 * 65536, 123456789};
  const uint32_t fovs[] = {1, 0x15555555u /* 30 deg */, 0x2AAAAAAAu /* 60 deg */, 0x7FFFFFFFu,
                           0xFFFFFFFFu};
  const uint32_t widths[] = {1, 12, 25, 32, 64, 640};
  for (const int32_t sh : shifts)
    for (const uint32_t fov : fovs)
      for (const uint32_t w : widths) {
        const double want =
            -static_cast<double>(sh) / static_cast<double>(Q15_16::from_int(1).raw()) * fov / w;
        const Angle got = shift_to_heading(Q15_16::from_raw(sh), Angle{fov}, w);
        if (want >= 2147483648.0 || want < -2147483648.0) continue;  // saturates (below)
        EXPECT_NEAR(static_cast<double>(static_cast<int32_t>(got.bam)), want, 1.0);
      }
  // 60 degrees over 32 columns: one column is 1.875 degrees; content further right means
  // the camera turned left (positive heading) -- so a shift of +2 columns is -3.75 degrees.
  const Angle h = shift_to_heading(Q15_16::from_int(2), Angle::from_degrees(60), 32);
  EXPECT_NEAR(static_cast<int32_t>(h.bam) / static_cast<double>(uint64_t{1} << 32) * 360.0, -3.75,
              1e-6);
  EXPECT_EQ(shift_to_heading(Q15_16::from_int(3), Angle::from_degrees(60), 0).bam, 0u);
  // Saturation at +-half a turn instead of wrapping to the other side.
  const Angle big = shift_to_heading(Q15_16::from_int(-30000), Angle{0xFFFFFFFFu}, 1);
  EXPECT_EQ(big.bam, 0x7FFFFFFFu);
}

}  // namespace
}  // namespace seqslam
