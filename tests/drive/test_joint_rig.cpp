// Joint rig assembly against hand-derived results: rigid drive under constant torque, DC-motor-driven
// load at steady speed, velocity PI tracking, clamped elasto-backlash clamping curve, input restarts.
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/drive/transmissions.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "test_util.hpp"

using namespace jointsim;
using namespace jointsim::systems;

namespace {
std::vector<Eigen::VectorXd> run(JointRig& rig) {
  std::vector<Eigen::VectorXd> rows;
  sim::simulate(rig, rig.simulateOptions(), [&](const Eigen::VectorXd& r) { rows.push_back(r); });
  return rows;
}
}  // namespace

TEST(JointRig, RigidGearConstantTorqueClosedForm) {
  JointRigSetup s;
  s.transmission = std::make_shared<drive::RigidGear>(50.0);
  s.rotor_inertia = 2e-4;
  s.load_inertia = 1.5;
  s.profile = control::Profile::constant(0.3);
  s.duration = 1.0;
  s.log_rate = 10;
  JointRig rig(s);
  EXPECT_EQ(rig.stateSize(), 2);
  const auto rows = run(rig);
  const double J_eff = 2e-4 + 1.5 / 2500.0;
  const double t = rows.back()[0];
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "motor_angle")], 0.5 * 0.3 / J_eff * t * t, 1e-6);
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "output_velocity")], 0.3 / J_eff * t / 50.0, 1e-7);
  // The gear delivers N times the torque it takes from the motor; the load accelerates with it.
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "transmission_torque_out")], 1.5 * 0.3 / J_eff / 50.0, 1e-9);
}

TEST(JointRig, DcMotorDrivesViscousLoadToHandDerivedSpeed) {
  // Steady state: k_t i = b_l ω / N² (viscous load reflected) and V = R i + k_e ω.
  JointRigSetup s;
  s.motor = drive::DcMotorParams::ur5(1);
  s.transmission = std::make_shared<drive::RigidGear>(101.0);
  s.input = RigInput::Voltage;
  s.profile = control::Profile::step(0.0, 24.0, 0.01);
  s.load_inertia = 1.2;
  s.load_damping = 40.0;
  s.duration = 3.0;
  s.log_rate = 100;
  JointRig rig(s);
  const auto rows = run(rig);
  const auto& p = *s.motor;
  const double b_m = 40.0 / (101.0 * 101.0);
  const double omega = p.kt * 24.0 / (p.R * b_m + p.kt * p.ke);
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "motor_velocity")], omega, 1e-6 * omega);
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "motor_current")], b_m * omega / p.kt, 1e-5);
  EXPECT_EQ(rows[0][test::rowIndex(rig, "motor_voltage")], 0.0);
}

TEST(JointRig, VelocityPiTracksStepWithElasticGear) {
  JointRigSetup s;
  s.transmission =
      std::make_shared<drive::ElasticGear>(drive::ElasticGearParams{20.0, 5.0, 0.02, drive::ComplianceSide::Motor});
  s.rotor_inertia = 1e-3;
  s.load_inertia = 0.5;
  s.load_damping = 2.0;
  s.input = RigInput::VelocityPI;
  s.pi = {0.5, 5.0, 10.0, false, Side::Output};
  s.profile = control::Profile::step(0.0, 1.0, 0.1);
  s.duration = 8.0;
  s.log_rate = 50;
  JointRig rig(s);
  const auto rows = run(rig);
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "output_velocity")], 1.0, 1e-4);
  // Holding 1 rad/s against b_l = 2 N·m·s/rad takes 2 N·m at the output, 0.1 N·m at the motor.
  EXPECT_NEAR(rows.back()[test::rowIndex(rig, "motor_torque")], 2.0 / 20.0, 1e-3);
}

TEST(JointRig, ClampedBacklashCurveSlopeAndGap) {
  // Clamped output, motor-side elasto-backlash, no friction: slow torque triangle. Outside the gap the
  // motor angle follows (τ − d φ̇)/c ± b/2 (spring plus damper lag; rotor inertia negligible).
  const double c = 25.7, b = 0.0102;
  JointRigSetup s;
  s.transmission = std::make_shared<drive::ElastoBacklash>(
      drive::ElastoBacklashParams{1.0, c, 0.5, b, drive::ComplianceSide::Motor});
  s.rotor_inertia = 1e-3;
  s.clamped = true;
  s.profile = control::Profile::triangle(2.0, 20.0);
  s.duration = 20.0;
  s.log_rate = 100;
  JointRig rig(s);
  const auto rows = run(rig);
  const int ia = test::rowIndex(rig, "motor_angle"), iv = test::rowIndex(rig, "motor_velocity"),
            it = test::rowIndex(rig, "command_torque");
  double max_err = 0, max_lag = 0;
  for (const auto& r : rows) {
    const double tau = r[it], phi = r[ia], lag = 0.5 * r[iv] / c;
    // Skip the gap itself and 0.1 s (5 relaxation times d/c) after each reversal at t = 5, 15 s.
    const bool after_reversal = std::fmod(r[0] + 5.0, 10.0) < 0.1 && r[0] > 1.0;
    if (std::abs(tau) > 0.05 && !after_reversal) {
      max_err = std::max(max_err, std::abs(phi - ((tau - 0.5 * r[iv]) / c + std::copysign(b / 2, tau))));
      max_lag = std::max(max_lag, std::abs(lag));
    }
  }
  EXPECT_GT(max_lag, 1e-4) << "the damper lag is large enough for the check to matter";
  EXPECT_LT(max_err, 1e-5) << "curve phi = (tau - d phi_dot)/c ± b/2 (0.2 % of b/2)";
}
