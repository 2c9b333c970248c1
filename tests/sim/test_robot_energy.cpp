// Energy of the UR5 simulated with CVODE through the passive-robot experiment: conserved without
// damping (relative drift < 1e-7 over 5 s), and dissipated at exactly the damping power with damping.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/passive_robot.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {
struct Log {
  std::vector<Eigen::VectorXd> rows;
};

systems::PassiveRobotParams ur5Fall() {
  systems::PassiveRobotParams p;
  p.q0.resize(6);
  p.q0 << 0.0, -1.2, 0.8, -0.5, 0.7, 0.0;
  p.qd0 = Eigen::VectorXd::Zero(6);
  p.qd0[0] = 0.3;
  p.duration = 5.0;
  p.log_rate = 1000.0;
  return p;
}
}  // namespace

TEST(Ur5Fall, EnergyConservedAtTightTolerance) {
  const auto model = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  auto p = ur5Fall();
  p.solver.rtol = 1e-11;
  p.solver.atol = 1e-12;
  const int n = model.nq, iT = 1 + 2 * n, iE = 3 + 2 * n;
  double E0 = 0, max_drift = 0, max_T = 0;
  bool first = true;
  systems::PassiveRobot plant(model, p);
  const auto r = sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) {
    if (first) E0 = row[iE];
    first = false;
    max_drift = std::max(max_drift, std::abs(row[iE] - E0));
    max_T = std::max(max_T, row[iT]);
  });
  EXPECT_NEAR(r.sim_time_s, 5.0, 1e-12);
  EXPECT_EQ(r.outputs, 5001);
  ASSERT_GT(max_T, 10.0) << "the robot should really fall (kinetic energy of tens of joules)";
  // Drift relative to the energy exchanged (the peak kinetic energy): the potential energy's zero is
  // arbitrary, so |E0| is no meaningful scale.
  EXPECT_LT(max_drift / max_T, 1e-7) << "drift " << max_drift << " J, peak kinetic energy " << max_T << " J";
}

TEST(Ur5Fall, DampingDissipatesExactlyTheDampingPower) {
  // E(t) − E(0) = −∫ Σ b_i q̇_i² dt, integrated from the log with the trapezoidal rule.
  const auto model = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  auto p = ur5Fall();
  p.duration = 2.0;
  p.log_rate = 4000.0;
  p.damping = Eigen::VectorXd::Constant(6, 0.8);
  p.damping[0] = 2.0;
  p.solver.rtol = 1e-10;
  p.solver.atol = 1e-12;
  const int n = model.nq, iE = 3 + 2 * n;
  std::vector<Eigen::VectorXd> rows;
  systems::PassiveRobot plant(model, p);
  sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& row) { rows.push_back(row); });
  double dissipated = 0, prev_power = 0, max_power = 0;
  bool energy_monotone = true;
  for (size_t k = 0; k < rows.size(); ++k) {
    const Eigen::VectorXd qd = rows[k].segment(1 + n, n);
    const double power = (p.damping.array() * qd.array().square()).sum();
    max_power = std::max(max_power, power);
    if (k > 0) {
      dissipated += 0.5 * (power + prev_power) * (rows[k][0] - rows[k - 1][0]);
      energy_monotone = energy_monotone && rows[k][iE] <= rows[k - 1][iE] + 1e-9;
    }
    prev_power = power;
  }
  const double dE = rows.back()[iE] - rows.front()[iE];
  ASSERT_GT(dissipated, 1.0);
  EXPECT_TRUE(energy_monotone);
  EXPECT_NEAR(-dE, dissipated, 1e-4 * dissipated);
}
