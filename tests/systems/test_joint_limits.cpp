// Joint limits (systems/joint_limits.hpp): the end-stop law and its energy, a pendulum resting on its stop
// against the static deflection k δ = τ_gravity (closed form), the torque-free UR5 swing kept within its limits
// by the stops (bound from energy: ½ k δ² ≤ E(0) − V_min) with energy that never increases at a contact, the
// same swing conserving energy with an undamped stop, the monitor of mode warn, and a robot with drives.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/joint_limits.hpp"
#include "jointsim/systems/passive_robot.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;
using systems::JointLimitMode;
using systems::JointLimitSettings;

namespace {

JointLimitSettings stop(double k = 1.0e5, double d = 100.0) {
  JointLimitSettings s;
  s.mode = JointLimitMode::Stop;
  s.stiffness = k;
  s.damping = d;
  return s;
}

/// A point mass m on a massless rod of length l about the y axis, q = 0 upright (an inverted pendulum: gravity
/// pushes it away from 0 with the torque m g l sin q), limits [lo, hi].
multibody::Model pendulum(double m, double l, double lo, double hi) {
  multibody::ModelBuilder b("pendulum", "base");
  multibody::JointSpec j;
  j.name = "hinge";
  j.type = multibody::JointType::Revolute;
  j.axis = {0, 1, 0};
  j.limits.lower = lo;
  j.limits.upper = hi;
  multibody::BodyInertia I;
  I.mass = m;
  I.com = {0, 0, l};
  I.inertia = Eigen::Matrix3d::Identity() * 1e-9;
  b.addLink("base", j, "bob", I);
  return b.build();
}

/// The torque-free UR5 swing of the hostile-input probe: arm up, elbow bent, released from rest; without
/// stops the elbow passes its ±π limit after 0.51 s and reaches −14.9 rad.
systems::PassiveRobotParams swing(const JointLimitSettings& limits, double duration = 5.0) {
  systems::PassiveRobotParams p;
  p.q0.resize(6);
  p.q0 << 0.0, -1.5708, 0.3, 0.0, 0.0, 0.0;
  p.duration = duration;
  p.log_rate = 500.0;
  p.solver.method = sim::Method::BDF;
  p.solver.rtol = 1e-8;
  p.solver.atol = 1e-10;
  p.joint_limits = limits;
  return p;
}

/// Lower bound of the potential energy over all configurations: −|g| Σ m_i r_i with r_i a bound of the
/// distance of body i's centre of mass from the base origin (sum of the joint offsets up the chain).
double potentialLowerBound(const multibody::Model& model) {
  double V = 0.0;
  for (int i = 0; i < model.nq; ++i) {
    double r = model.inertias[static_cast<size_t>(i)].com.norm();
    for (int j = i; j >= 0; j = model.parents[static_cast<size_t>(j)])
      r += model.joint_placements[static_cast<size_t>(j)].p.norm();
    V -= model.gravity.norm() * model.mass[static_cast<size_t>(i)] * r;
  }
  return V;
}

}  // namespace

TEST(EndStops, PushOnlyBeyondTheLimitAndNeverPull) {
  const auto model = pendulum(1.0, 1.0, -0.5, 0.5);
  const systems::EndStops stops(model, stop(1000.0, 10.0));
  ASSERT_TRUE(stops.active());
  Eigen::VectorXd q(1), qd(1), tau(1);
  double g[2];
  auto at = [&](double qi, double qdi) {
    q << qi;
    qd << qdi;
    stops.torques(q, qd, tau);
    stops.roots(q, g);
    return tau[0];
  };
  EXPECT_EQ(at(0.2, 5.0), 0.0);                      // inside: no torque
  EXPECT_NEAR(at(0.51, 0.0), -1000.0 * 0.01, 1e-9);  // spring, upper stop pushes down
  EXPECT_NEAR(at(0.51, 0.3), -(10.0 + 3.0), 1e-9);   // entering: spring + damper
  EXPECT_NEAR(at(0.51, -1.5), 0.0, 1e-9);            // leaving fast: the damper would pull, cut off
  EXPECT_NEAR(at(-0.52, 0.0), 1000.0 * 0.02, 1e-9);  // lower stop pushes up
  EXPECT_NEAR(at(-0.52, -0.1), 20.0 + 1.0, 1e-9);    // entering the lower stop
  EXPECT_NEAR(g[0], -0.52 - 0.5, 1e-15);             // roots: q − q_upper, q_lower − q
  EXPECT_NEAR(g[1], -0.5 + 0.52, 1e-15);
  q << 0.53;
  EXPECT_NEAR(stops.energy(q), 0.5 * 1000.0 * 0.03 * 0.03, 1e-12);
  // No stop without limits, nor in the other modes.
  EXPECT_FALSE(systems::EndStops(pendulum(1, 1, -INFINITY, INFINITY), stop()).active());
  EXPECT_FALSE(systems::EndStops(model, JointLimitSettings{}).active());
  EXPECT_THROW(systems::EndStops(model, stop(0.0, 1.0)), InputError);
  EXPECT_THROW(systems::EndStops(model, stop(1.0, -1.0)), InputError);
}

TEST(EndStops, PendulumRestsOnItsStopWithTheStaticDeflection) {
  // m g l sin q pushes the pendulum (released at 0.3 rad, at rest) against its stop at 0.5 rad; joint damping
  // settles it. At rest k δ = m g l sin(0.5 + δ): solved by fixed-point iteration (contraction: m g l / k ≪ 1).
  const double m = 2.0, l = 0.8, k = 2.0e3, upper = 0.5;
  systems::PassiveRobotParams p;
  p.q0 = Eigen::VectorXd::Constant(1, 0.3);
  p.damping = Eigen::VectorXd::Constant(1, 2.0);
  p.duration = 20.0;
  p.log_rate = 10.0;
  p.solver.method = sim::Method::BDF;
  p.solver.rtol = 1e-10;
  p.solver.atol = 1e-12;
  p.joint_limits = stop(k, 5.0);
  systems::PassiveRobot plant(pendulum(m, l, -upper, upper), p);
  std::vector<Eigen::VectorXd> rows;
  const auto r =
      sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) { rows.push_back(row); });
  double delta = 0.0;
  for (int it = 0; it < 100; ++it) delta = m * 9.81 * l * std::sin(upper + delta) / k;
  EXPECT_NEAR(rows.back()[1] - upper, delta, 1e-7 * delta) << "static deflection k δ = m g l sin(q)";
  EXPECT_NEAR(rows.back()[2], 0.0, 1e-8);
  EXPECT_GE(r.events, 1) << "the contact is located as a root";
  // The stop's torque balances gravity: signal end_stop_torque_hinge.
  const int torque = test::rowIndex(plant, "end_stop_torque_hinge");
  EXPECT_NEAR(rows.back()[torque], -m * 9.81 * l * std::sin(upper + delta), 1e-6);
}

TEST(EndStops, TorqueFreeUr5SwingStaysWithinItsLimitsAndNeverGainsEnergy) {
  const auto model = multibody::loadRobot(test::sourcePath("config/robots/ur5.urdf"));
  const double k = 1.0e5;
  systems::PassiveRobot plant(model, swing(stop(k, 100.0)));
  const int n = model.nq, iE = test::rowIndex(plant, "total_energy"), iS = test::rowIndex(plant, "end_stop_energy");
  std::vector<Eigen::VectorXd> rows;
  const auto r =
      sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) { rows.push_back(row); });
  const double E0 = rows.front()[iE];
  // ½ k δ² ≤ E(0) − (T + V) ≤ E(0) − V_min: the deepest any stop can be pressed in.
  const double delta_max = std::sqrt(2.0 * (E0 - potentialLowerBound(model)) / k);
  EXPECT_LT(delta_max, 0.1);
  double deepest = 0.0, max_rise = 0.0, contact_energy = 0.0;
  for (size_t s = 0; s < rows.size(); ++s) {
    for (int i = 0; i < n; ++i) {
      const auto& L = model.limits[static_cast<size_t>(i)];
      const double q = rows[s][1 + i];
      EXPECT_GE(q, L.lower - delta_max) << model.joint_names[static_cast<size_t>(i)] << " at t = " << rows[s][0];
      EXPECT_LE(q, L.upper + delta_max) << model.joint_names[static_cast<size_t>(i)] << " at t = " << rows[s][0];
      deepest = std::max({deepest, q - L.upper, L.lower - q});
    }
    if (s > 0) max_rise = std::max(max_rise, rows[s][iE] - rows[s - 1][iE]);
    contact_energy = std::max(contact_energy, rows[s][iS]);
  }
  EXPECT_GT(deepest, 1e-3) << "the swing reaches the stops";
  EXPECT_GT(contact_energy, 0.0);
  EXPECT_GE(r.events, 2);
  // Energy (robot + stops) never increases, beyond the integration error (rtol 1e-8 of ~100 J).
  EXPECT_LT(max_rise, 1e-4 * std::abs(E0)) << "energy rose at a contact";
  EXPECT_LT(rows.back()[iE], E0 - 10.0) << "the damped stops dissipate";
}

TEST(EndStops, UndampedStopsConserveEnergy) {
  const auto model = multibody::loadRobot(test::sourcePath("config/robots/ur5.urdf"));
  auto p = swing(stop(1.0e5, 0.0), 2.0);
  p.solver.rtol = 1e-10;
  p.solver.atol = 1e-12;
  systems::PassiveRobot plant(model, p);
  const int iE = test::rowIndex(plant, "total_energy");
  double E0 = NAN, drift = 0.0;
  const auto r = sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) {
    if (std::isnan(E0)) E0 = row[iE];
    drift = std::max(drift, std::abs(row[iE] - E0));
  });
  EXPECT_GE(r.events, 1);
  EXPECT_LT(drift, 1e-5 * std::abs(E0));
}

TEST(JointLimitMonitor, WarnReportsTheSwingPastTheElbowLimit) {
  const auto model = multibody::loadRobot(test::sourcePath("config/robots/ur5.urdf"));
  systems::PassiveRobot plant(model, swing(JointLimitSettings{}));
  EXPECT_FALSE(plant.endStops().active());
  std::vector<int> columns;
  for (int i = 0; i < model.nq; ++i) columns.push_back(1 + i);
  systems::JointLimitMonitor monitor(model, columns, JointLimitSettings{});
  double elbow_min = 0.0;
  double first_out = NAN;
  sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) {
    monitor.observe(row);
    elbow_min = std::min(elbow_min, row[3]);
    if (std::isnan(first_out) && std::abs(row[3]) > M_PI) first_out = row[0];
  });
  const auto v = monitor.violations();
  ASSERT_FALSE(v.empty());
  const auto elbow = std::find_if(v.begin(), v.end(), [](const auto& x) { return x.joint == "elbow_joint"; });
  ASSERT_NE(elbow, v.end());
  EXPECT_DOUBLE_EQ(elbow->first_time, first_out);
  EXPECT_GT(elbow->max_excursion, 5.0);
  EXPECT_DOUBLE_EQ(elbow->max_excursion, std::max(-M_PI - elbow_min, elbow->max_position - M_PI));
  EXPECT_THAT(monitor.describe().at(static_cast<size_t>(elbow - v.begin())),
              ::testing::StartsWith("joint elbow_joint left its range [-3.1416, 3.1416] rad at t = "));
  monitor.reset();
  EXPECT_TRUE(monitor.violations().empty());
}

TEST(EndStops, RobotWithDrivesGetsStopsRootsAndSignals) {
  auto sys = systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml"));
  const size_t signals = sys.signalNames().size();
  EXPECT_EQ(sys.rootCount(), 0);
  sys.setJointLimits(stop());
  EXPECT_EQ(sys.rootCount(), 12);
  EXPECT_EQ(sys.signalNames().size(), signals + 6);
  EXPECT_EQ(sys.signalNames().back(), "end_stop_torque_wrist_3_joint[N·m]");
  sys.setJointLimits(JointLimitSettings{});
  EXPECT_EQ(sys.rootCount(), 0);
  EXPECT_EQ(sys.signalNames().size(), signals);
  // Beyond its upper limit the shoulder pan feels the stop, and the energy holds the stop's ½ k δ².
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(6);
  q0[0] = 2 * M_PI + 0.01;
  sys.setJointLimits(stop(1.0e5, 0.0));
  const Eigen::VectorXd y = sys.initialState(q0);
  const double E_stop = sys.mechanicalEnergy(y);
  EXPECT_NEAR(sys.driveSignals(*sys.makeState(), 0.0, y).tau_stop[0], -1.0e5 * 0.01, 1e-6);
  sys.setJointLimits(JointLimitSettings{});
  EXPECT_NEAR(E_stop - sys.mechanicalEnergy(y), 0.5 * 1.0e5 * 0.01 * 0.01, 1e-9);
  EXPECT_EQ(sys.driveSignals(*sys.makeState(), 0.0, y).tau_stop[0], 0.0);
}
