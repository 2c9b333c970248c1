// A user's PD loop at 1 kHz around the UR5 twin by motor voltage (examples/pd_voltage_ur5.cpp): the settings that
// make it fast (rtol 1e-4, the last Jacobian at restarts, max_gamma_change 0.5) checked against a tight run.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

struct Trace {
  std::vector<Eigen::VectorXd> q, i;  // joint angles [rad] and motor currents [A] at every sample
  sim::SolverStats stats;
};

/// The example's loop: every joint steps by 0.1 rad at 0.02 s (the hardest part of the example: every drive
/// accelerates against the voltage limit and every sample restarts the integrator), run to `duration`.
Trace runPd(const sim::CvodeOptions& solver, double duration) {
  systems::RobotSystem robot = systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml"));
  const int n = robot.dof();
  Eigen::VectorXd q0(n);
  q0 << 0.0, -1.2, 1.2, -1.5, -1.5708, 0.0;
  robot.setInitialPositions(q0);
  sim::Simulator sim(robot, solver);
  for (int k = 0; k < n; ++k) robot.setCommandPort(sim.plantState(), k, systems::CommandPort::Voltage);
  multibody::Data data(robot.model());
  Eigen::VectorXd V(n), q_ref = q0;
  Trace tr;
  while (sim.time() < duration - 1e-9) {
    if (sim.time() >= 0.02 - 1e-9) q_ref = q0.array() + 0.1;
    const Eigen::VectorXd q = sim.state().head(n);
    const Eigen::VectorXd& g = multibody::gravityTorques(robot.model(), data, q);
    Eigen::VectorXd cur(n);
    for (int k = 0; k < n; ++k) {
      const auto& d = robot.drives()[static_cast<size_t>(k)];
      const double N = d.transmission->ratio();
      V[k] = d.motor.R * g[k] / (N * d.motor.kt) + 200.0 * (q_ref[k] - q[k]) -
             5.0 * robot.motorVelocity(sim.state(), k) / N;
      cur[k] = sim.state()[robot.layout(k).current];
    }
    tr.q.push_back(q);
    tr.i.push_back(cur);
    robot.setCommands(sim.plantState(), V);
    sim.advance(1e-3);
  }
  tr.stats = sim.stats();
  return tr;
}

TEST(SampledPd, LooseToleranceStaysCloseToTightRun) {
  sim::CvodeOptions fast = sim::stiffDriveSolver(1e-4, 1e-9);
  fast.max_gamma_change = 0.5;
  sim::CvodeOptions tight = sim::stiffDriveSolver(1e-8, 1e-12);
  const Trace a = runPd(fast, 0.06), b = runPd(tight, 0.06);
  ASSERT_EQ(a.q.size(), b.q.size());
  double dq = 0.0, di = 0.0, i_peak = 0.0, moved = 0.0;
  for (size_t s = 0; s < a.q.size(); ++s) {
    dq = std::max(dq, (a.q[s] - b.q[s]).cwiseAbs().maxCoeff());
    di = std::max(di, (a.i[s] - b.i[s]).cwiseAbs().maxCoeff());
    i_peak = std::max(i_peak, b.i[s].cwiseAbs().maxCoeff());
    moved = std::max(moved, (b.q[s] - b.q[0]).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(moved, 0.02);  // the arm did move: a transient, not a rest
  EXPECT_GT(i_peak, 5.0);  // the drives were pushed hard [A]
  EXPECT_LT(dq, 1e-5);     // joint angles [rad] (3.5 µrad measured over the example's 2 s)
  EXPECT_LT(di, 0.02);     // motor currents [A]
  // The restarts at the samples started with the last Jacobian.
  EXPECT_GT(a.stats.jac_reused, 10);
}

TEST(SampledPd, MotorVelocityIsTheMotorShaftState) {
  systems::RobotSystem robot = systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml"));
  Eigen::VectorXd y = robot.initialState();
  for (int k = 0; k < robot.dof(); ++k) {
    const auto& L = robot.layout(k);
    ASSERT_GE(L.motor, 0);  // compliant strain-wave gears: the motor has its own states [angle, speed]
    y[L.motor + 1] = 10.0 * (k + 1);
    EXPECT_EQ(robot.motorVelocity(y, k), 10.0 * (k + 1));
  }
}

}  // namespace
}  // namespace jointsim
