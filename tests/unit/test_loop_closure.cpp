// The loop-closure gate: configuration and statuses; the confirmation run (pending until the
// confirm-th consistent, advancing match, closures after it); rejection by the position and
// the heading bound, and the position bound growing with the distance driven since the last
// fix; aliasing vs novelty by the known places near the prediction; relocalisation after a
// run of confident matches that odometry cannot explain; its verification, which rejects a
// corner that aliases another and accepts a true relocalisation, and continues exactly from a
// saved state; predictions from the fix while the graph is not yet optimised; the counters.
#include "seqslam/loop_closure.h"

#include "ram_state.h"
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
  bad = LoopClosureConfig{};
  bad.relocalise_verify = Q31_32::from_int(1001);
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  bad.relocalise_verify = Q31_32::from_int(-1);
  EXPECT_EQ(gate.configure(bad), Status::kOutOfRange);
  bad = LoopClosureConfig{};
  bad.relocalise_support = 0;
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
    c.relocalise_verify = Q31_32::from_int(0);  // accepted at once (verification: below)
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
    c.relocalise = 5;                           // relocalise_turn: the default 45 degrees
    c.relocalise_verify = Q31_32::from_int(0);  // the trail alone (verification: below)
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

// The lab in small: a rectangular loop of 120 known places, 20 cm apart, with four left turns:
// south side (places 0..39, x 0..7.8 m, heading 0), east side (40..59, x 8 m, heading 90),
// north side (60..99, y 4 m, heading 180), west side (100..119, x 0, heading 270). Turned by
// half a turn about its centre (4 m, 2 m) it is itself: place k looks (in its shape) like
// place k + 60, so a trail through one corner fits the opposite corner just as well.
constexpr int32_t kLoopPlaces = 120;

Pose2 loop_place(int32_t k) {
  k %= kLoopPlaces;
  if (k < 40) return pose_at(20 * k, 0, 0);
  if (k < 60) return pose_at(800, 20 * (k - 40), 90);
  if (k < 100) return pose_at(800 - 20 * (k - 60), 400, 180);
  return pose_at(0, 400 - 20 * (k - 100), 270);
}

// The robot's pass: along the south side's eastern half and round its corner up the east side,
// truly at place 20 + j (j = 0..39); the corner is at j = 20.
int32_t robot_place(int64_t j) {
  return static_cast<int32_t>((20 + j) % kLoopPlaces);
}

struct PassCase {
  Pose2 frame{};                     // odometry = frame composed with the true pose (kidnap)
  int64_t aliased_until = 0;         // matches point at the opposite place before this j
  double nudge_m = 0;                // odometry off sideways at j = kNudgeAt only
  bool lost_after_proposal = false;  // no answers after j = 20
};
constexpr int64_t kPassPlaces = 40;
constexpr int64_t kNudgeAt = 25;

Pose2 pass_odometry(const PassCase& c, int64_t j) {
  Pose2 truth = loop_place(robot_place(j));
  if (j == kNudgeAt && c.nudge_m != 0) {
    const RelativePose2 side{
        Q31_32::from_int(0),
        Q31_32::from_ratio(static_cast<int64_t>(c.nudge_m * 1e6 + 0.5), 1000000), Angle{}};
    truth = compose(truth, side);
  }
  return compose(c.frame, RelativePose2{truth.x, truth.y, truth.heading});
}

// The known loop (nodes 0..119) and the robot's own nodes at its odometry poses (120..159:
// dead reckoning, the graph's estimate before any fix).
Graph& pass_graph(const PassCase& c) {
  Graph& g = fresh_graph();
  for (int32_t k = 0; k < kLoopPlaces; ++k)
    g.add(loop_place(k));
  for (int64_t j = 0; j < kPassPlaces; ++j)
    g.add(pass_odometry(c, j));
  return g;
}

struct PassResult {
  int64_t relocalised_at = -1;
  int32_t fix_place = -1;
  uint32_t closures = 0, wrong_closures = 0;
  LoopClosureDecision last;
};

// Places j = from..to-1 of the pass through `gate`.
PassResult run_pass(LoopClosureGate& gate, const Graph& g, const PassCase& c, int64_t from = 0,
                    int64_t to = kPassPlaces) {
  PassResult r;
  for (int64_t j = from; j < to; ++j) {
    const int32_t truth = robot_place(j);
    const int32_t place = j < c.aliased_until ? (truth + 60) % kLoopPlaces : truth;
    const Match m = c.lost_after_proposal && j > 20 ? unsure(-1) : confident(place);
    r.last = decide(gate, g, m, static_cast<uint32_t>(kLoopPlaces + j), pass_odometry(c, j),
                    kLoopPlaces);
    if (r.last.kind == LoopClosureClass::kRelocalised && r.relocalised_at < 0) {
      r.relocalised_at = j;
      r.fix_place = static_cast<int32_t>(gate.fix_node());
    }
    if (r.last.kind == LoopClosureClass::kClosure) {
      ++r.closures;
      if (place != truth) ++r.wrong_closures;
    }
  }
  return r;
}

// relocalise 5, relocalise_turn 45 degrees, verified over `places` places of 20 cm.
LoopClosureConfig verifying(int64_t places) {
  LoopClosureConfig c;
  c.relocalise = 5;
  c.relocalise_verify = Q31_32::from_ratio(20 * places, 100);
  return c;
}

const Pose2 kKidnapped = pose_at(3000, -2000, 90);  // the odometry's frame after the kidnap

// The constructed case of the issue: two corners that look alike. The odometry is right; the
// matcher's sequences point at the opposite side of the loop through the south-east corner
// (it aliases the north-west one) until 2 m past it, then at the true places. The trail turns
// alike by both, so without verification it relocalises to the wrong corner at once; with it,
// the true matches, which the odometry explains, drop the hypothesis before it is accepted,
// and close. A true relocalisation (kidnapped: odometry in another frame, true matches) is
// accepted once verified, at the right place.
TEST(LoopClosure, VerificationRejectsACornerThatAliasesAnother) {
  for (const int64_t verify : {int64_t{0}, int64_t{15}}) {
    PassCase alias;
    alias.aliased_until = 30;
    LoopClosureGate gate;
    ASSERT_EQ(gate.configure(verifying(verify)), Status::kOk) << verify;
    const PassResult a = run_pass(gate, pass_graph(alias), alias);
    if (verify == 0) {
      // The constructed corner does alias: the trail alone relocalises to the opposite side
      // at the corner (j 20), and what follows closes against the wrong side.
      EXPECT_EQ(a.relocalised_at, 20) << verify;
      EXPECT_EQ(a.fix_place, (robot_place(20) + 60) % kLoopPlaces) << verify;
      EXPECT_GT(a.wrong_closures, 0u) << verify;
    } else {
      EXPECT_EQ(a.relocalised_at, -1) << verify;
      EXPECT_EQ(gate.stats().hypotheses, 1u) << verify;
      EXPECT_EQ(gate.stats().hypotheses_dropped, 1u) << verify;
      EXPECT_FALSE(gate.verifying()) << verify;
      EXPECT_EQ(a.wrong_closures, 0u) << verify;
      EXPECT_EQ(a.closures, 8u) << verify;  // j 32..39: from the third true match on
    }

    PassCase kid;
    kid.frame = kKidnapped;
    LoopClosureGate gate2;
    ASSERT_EQ(gate2.configure(verifying(verify)), Status::kOk) << verify;
    const PassResult k = run_pass(gate2, pass_graph(kid), kid);
    // Proposed at the corner, accepted once the robot has driven `verify` places further
    // (the odometry's steps are 20 cm give or take rounding: one place either way).
    EXPECT_GE(k.relocalised_at, 20 + verify - 1) << verify;
    EXPECT_LE(k.relocalised_at, 20 + verify + 1) << verify;
    EXPECT_EQ(k.fix_place, robot_place(k.relocalised_at)) << verify;
    EXPECT_EQ(gate2.stats().hypotheses, 1u) << verify;
    EXPECT_EQ(gate2.stats().hypotheses_dropped, 0u) << verify;
    EXPECT_EQ(k.wrong_closures, 0u) << verify;
    EXPECT_EQ(k.closures, static_cast<uint32_t>(kPassPlaces - 1 - k.relocalised_at)) << verify;
  }
}

// Kidnapped and aliased at once: nothing the odometry explains, but the first true match
// after the alias disagrees with the hypothesis (the opposite side is metres from where it
// puts the robot) and drops it; the true trail that follows has no turn, so no
// relocalisation. A hypothesis no match confirms for relocalise_verify metres is dropped too.
TEST(LoopClosure, VerificationDropsAHypothesisTheNextMatchesDoNotConfirm) {
  PassCase c;
  c.frame = kKidnapped;
  c.aliased_until = 30;
  LoopClosureGate gate;
  ASSERT_EQ(gate.configure(verifying(15)), Status::kOk);
  const Graph& g = pass_graph(c);
  EXPECT_EQ(run_pass(gate, g, c, 0, 30).relocalised_at, -1);
  EXPECT_TRUE(gate.verifying());
  EXPECT_EQ(gate.hypothesis_node(), static_cast<uint32_t>((robot_place(29) + 60) % kLoopPlaces));
  const PassResult r = run_pass(gate, g, c, 30, 31);
  EXPECT_FALSE(gate.verifying());
  EXPECT_EQ(r.last.kind, LoopClosureClass::kRejectedInconsistent);
  EXPECT_EQ(gate.stats().hypotheses_dropped, 1u);
  EXPECT_EQ(run_pass(gate, g, c, 31, kPassPlaces).relocalised_at, -1);
  EXPECT_EQ(gate.stats().hypotheses, 1u);

  // Proposed at the corner (j 20), then no answers: dropped once 3 m (15 places) have passed
  // without an agreeing match, i.e. at j 36.
  PassCase lost;
  lost.frame = kKidnapped;
  lost.lost_after_proposal = true;
  LoopClosureGate gate2;
  ASSERT_EQ(gate2.configure(verifying(15)), Status::kOk);
  const Graph& g2 = pass_graph(lost);
  (void)run_pass(gate2, g2, lost, 0, 35);
  EXPECT_TRUE(gate2.verifying());
  (void)run_pass(gate2, g2, lost, 35, 37);
  EXPECT_FALSE(gate2.verifying());
  EXPECT_EQ(gate2.stats().hypotheses_dropped, 1u);
}

// The verification's bound against double arithmetic: the odometry is nudged sideways by
// `off` at one place (j 25), so the hypothesis puts the robot `off` from the true matched
// place, while the bound there is drift_base + drift_rate * (the step since the last agreeing
// match, sqrt(0.2^2 + off^2) m). 1 cm inside it the hypothesis holds and is accepted; 1 cm
// outside it is dropped at j 25.
TEST(LoopClosure, VerificationBoundMatchesDoubleReference) {
  for (const double inside : {1.0, -1.0}) {
    // The bound for an offset near 1 m (sqrt(0.2^2 + 1^2) = 1.0198039 m driven); off = bound
    // -+ 1 cm (the bound moves by 0.05 mm per cm of off: far below the margin).
    const double bound = 1.0 + 0.05 * 1.0198039027185569;
    PassCase c;
    c.frame = kKidnapped;
    c.nudge_m = bound - inside * 0.01;
    LoopClosureGate gate;
    ASSERT_EQ(gate.configure(verifying(15)), Status::kOk);
    const Graph& g = pass_graph(c);
    (void)run_pass(gate, g, c, 0, kNudgeAt);
    ASSERT_TRUE(gate.verifying());
    (void)run_pass(gate, g, c, kNudgeAt, kNudgeAt + 1);
    EXPECT_EQ(gate.verifying(), inside > 0) << c.nudge_m;
    EXPECT_EQ(run_pass(gate, g, c, kNudgeAt + 1, kPassPlaces).relocalised_at >= 0, inside > 0);
  }
}

// A run stopped while a relocalisation is being verified and continued from the saved state
// decides every later place as the run that never stopped, the acceptance included.
TEST(LoopClosure, VerificationContinuesFromASavedState) {
  PassCase c;
  c.frame = kKidnapped;
  const Graph& g = pass_graph(c);
  LoopClosureGate whole, first;
  ASSERT_EQ(whole.configure(verifying(15)), Status::kOk);
  ASSERT_EQ(first.configure(verifying(15)), Status::kOk);
  (void)run_pass(whole, g, c, 0, 28);
  (void)run_pass(first, g, c, 0, 28);
  ASSERT_TRUE(first.verifying());
  static test::RamState<1024> saved;
  saved.truncate(0);
  StateOut out(saved);
  first.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  LoopClosureGate resumed;
  ASSERT_EQ(resumed.configure(verifying(15)), Status::kOk);
  StateIn in(saved);
  resumed.state(in);
  ASSERT_EQ(in.status(), Status::kOk);
  EXPECT_TRUE(resumed.state_fits(kLoopPlaces + kPassPlaces));
  int64_t relocalised_at = -1;
  for (int64_t j = 28; j < kPassPlaces; ++j) {
    const PassResult a = run_pass(whole, g, c, j, j + 1);
    const PassResult r = run_pass(resumed, g, c, j, j + 1);
    EXPECT_EQ(r.last.kind, a.last.kind) << j;
    EXPECT_EQ(r.last.streak, a.last.streak) << j;
    EXPECT_EQ(r.last.distance.raw(), a.last.distance.raw()) << j;
    if (a.relocalised_at >= 0) relocalised_at = j;
  }
  EXPECT_GE(relocalised_at, 34);
  EXPECT_EQ(resumed.stats().hypotheses, whole.stats().hypotheses);
  EXPECT_EQ(resumed.fix_node(), whole.fix_node());
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
