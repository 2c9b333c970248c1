// Relative replay (RobotSystem::setRelativeReplay, `relative_replay` of tracking experiments): a reference recorded
// on another robot is followed relative to where the twin is. Checked on the UR5 twin with a logged move of the
// shoulder, starting 2 mrad off the log's first position: the move ends where the twin started plus the logged
// displacement (closed form), a rest holds the joint where it stopped (the reference equals the measured angle at
// the rest's start), the absolute replay (the default) ends on the log's positions instead, and a snapshot taken
// before a re-anchoring continues bit for bit.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/control/trajectory.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

constexpr double kH = 0.008;                  // the log's sample period [s] (125 Hz)
constexpr double kMoveStart = 0.2, kT = 0.5;  // the shoulder's move [s]
constexpr double kDelta = 0.2;                // its displacement [rad]
constexpr double kOffset = 2e-3;              // the twin's start off the log's first positions [rad]
constexpr double kEnd = 1.3;                  // the log's length [s]

// The log: every joint rests at q_log0 but the shoulder lift, which moves by kDelta with v = (2Δ/T) sin²(π u).
std::shared_ptr<control::LoggedTrajectory> shoulderMove(const Eigen::VectorXd& q_log0) {
  const double pi = std::acos(-1.0);
  const auto K = static_cast<Eigen::Index>(std::lround(kEnd / kH)) + 1;
  std::vector<double> t(static_cast<size_t>(K));
  Eigen::MatrixXd q(6, K), qd = Eigen::MatrixXd::Zero(6, K), qdd = Eigen::MatrixXd::Zero(6, K);
  for (Eigen::Index k = 0; k < K; ++k) {
    const double s = kH * static_cast<double>(k), u = std::clamp((s - kMoveStart) / kT, 0.0, 1.0);
    t[static_cast<size_t>(k)] = s;
    q.col(k) = q_log0;
    q(1, k) += kDelta * (u - std::sin(2 * pi * u) / (2 * pi));
    qd(1, k) = 2 * kDelta / kT * std::sin(pi * u) * std::sin(pi * u);
    qdd(1, k) = 2 * kDelta * pi / (kT * kT) * std::sin(2 * pi * u);
  }
  return std::make_shared<control::LoggedTrajectory>(t, q, qd, qdd, 0.0);
}

struct Replay {
  std::unique_ptr<systems::RobotSystem> robot;
  std::unique_ptr<sim::Simulator> sim;
};

Replay twin(bool relative, const Eigen::VectorXd& q_log0) {
  Replay r;
  r.robot = std::make_unique<systems::RobotSystem>(
      systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml")));
  r.robot->setTrajectory(shoulderMove(q_log0));
  r.robot->setRelativeReplay(relative);
  r.robot->setInitialPositions(q_log0.array() + kOffset);
  r.sim = std::make_unique<sim::Simulator>(*r.robot, sim::stiffDriveSolver(1e-6, 1e-9));
  return r;
}

Eigen::VectorXd logStart() {
  Eigen::VectorXd q(6);
  q << 0.0, -1.2, 1.2, -1.5, -1.5708, 0.0;
  return q;
}

}  // namespace

TEST(RelativeReplay, TheMoveStartsWhereTheTwinIsAndTheRestHoldsWhereItStopped) {
  const Eigen::VectorXd q_log0 = logStart();
  const Eigen::VectorXd q0 = q_log0.array() + kOffset;
  Replay rel = twin(true, q_log0);
  ASSERT_TRUE(rel.robot->relativeReplay());
  // Before the move: every reference is the twin's own start, not the log's.
  rel.sim->advanceTo(0.1);
  EXPECT_NEAR(rel.sim->signal("q_set_shoulder_lift_joint"), q0[1], 1e-12);
  EXPECT_NEAR(rel.sim->signal("q_set_wrist_1_joint"), q0[3], 1e-12);
  // The move's end: the first sample at rest, where a time event re-anchors the reference on the measured angle.
  const auto rests = shoulderMove(q_log0)->rests()[1];
  ASSERT_EQ(rests.size(), 2u);
  const double t_rest = rests[1].first;
  EXPECT_NEAR(t_rest, kH * std::ceil((kMoveStart + kT) / kH - 1e-9), 1e-12);
  rel.sim->advanceTo(t_rest);
  const double q_stop = rel.sim->state()[1];
  EXPECT_NEAR(q_stop, q0[1] + kDelta, 2e-4);  // the logged displacement from where the twin started
  rel.sim->advanceTo(t_rest + 0.05);
  EXPECT_NEAR(rel.sim->signal("q_set_shoulder_lift_joint"), q_stop, 1e-9);  // held where it stopped
  rel.sim->advanceTo(kEnd + 0.2);
  EXPECT_NEAR(rel.sim->signal("q_set_shoulder_lift_joint"), q_stop, 1e-9);
  EXPECT_NEAR(rel.sim->state()[1], q_stop, 1e-4);
  for (int j : {0, 2, 3, 4, 5}) EXPECT_NEAR(rel.sim->state()[j], q0[j], 1e-4) << j;

  // The absolute replay (the default) is pulled onto the log's positions instead: 2 mrad away.
  Replay abs = twin(false, q_log0);
  EXPECT_FALSE(abs.robot->relativeReplay());
  abs.sim->advanceTo(kEnd + 0.2);
  EXPECT_NEAR(abs.sim->signal("q_set_shoulder_lift_joint"), q_log0[1] + kDelta, 1e-12);
  EXPECT_NEAR(abs.sim->state()[1], q_log0[1] + kDelta, 2e-4);
  EXPECT_GT(std::abs(abs.sim->state()[1] - rel.sim->state()[1]), 0.9 * kOffset);
}

TEST(RelativeReplay, ASnapshotBeforeAReanchoringContinuesBitForBit) {
  Replay r = twin(true, logStart());
  r.sim->advanceTo(0.5);  // in the move: the rest starting at 0.7 s re-anchors later
  const sim::Snapshot snap = r.sim->snapshot();
  const std::string bytes = r.sim->saveState();
  r.sim->advanceTo(1.0);
  const Eigen::VectorXd y_end = r.sim->state();
  const double set_end = r.sim->signal("q_set_shoulder_lift_joint");
  r.sim->restore(snap);
  r.sim->advanceTo(1.0);
  for (Eigen::Index i = 0; i < y_end.size(); ++i) ASSERT_EQ(r.sim->state()[i], y_end[i]) << i;
  EXPECT_EQ(r.sim->signal("q_set_shoulder_lift_joint"), set_end);
  // From bytes into another simulator of the same robot.
  Replay other = twin(true, logStart());
  other.sim->loadState(bytes);
  other.sim->advanceTo(1.0);
  for (Eigen::Index i = 0; i < y_end.size(); ++i) ASSERT_EQ(other.sim->state()[i], y_end[i]) << i;
}

TEST(RelativeReplay, UnderSampledControlTheStartAnchorsOnTheMeasuredAngles) {
  // Sampled control (1 kHz outer loops, 20 kHz current loops): the anchors at the start come from the state's
  // measured angles (the held measurement is not taken yet), so the twin holds its start pose.
  const Eigen::VectorXd q_log0 = logStart();
  const Eigen::VectorXd q0 = q_log0.array() + kOffset;
  auto robot = std::make_unique<systems::RobotSystem>(
      systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml")));
  robot->setTrajectory(shoulderMove(q_log0));
  robot->setRelativeReplay(true);
  robot->setSampledControl(1000.0, 1, 20000.0);
  robot->setInitialPositions(q0);
  sim::Simulator sim(*robot, sim::stiffDriveSolver(1e-6, 1e-9));
  sim.advanceTo(0.15);
  // (The sampled twin settles by up to 3e-4 rad on the wrists after its start, relative replay or not; anchored on
  // an unset measurement, the reference would be the zero pose, a radian away.)
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(sim.state()[j], q0[j], 1e-3) << j;
  EXPECT_NEAR(sim.signal("q_set_shoulder_lift_joint"), q0[1], 1e-12);
}
