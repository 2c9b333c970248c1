// The UR5 with drives assembled into one ODE: rigid-gear joint torques equal RNEA of the simulated motion,
// strain-wave-gear speed ratio 101, energy conservation of the torque-free frictionless system, and the
// gravity-preloaded start at rest.
#include <cmath>
#include <memory>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {
const double kGains[6][5] = {{7400, 1.0, 0.1, 10, 10000}, {7500, 1.0, 0.2, 10, 10000}, {7500, 0.5, 0.1, 30, 10000},
                             {2900, 0.8, 0.2, 30, 10000}, {3000, 1.0, 0.2, 30, 10000}, {3250, 1.0, 0.2, 30, 10000}};

std::vector<systems::DriveSpec> ur5Drives(const multibody::Model& m,
                                          const std::function<std::shared_ptr<const drive::Transmission>(int)>& gear,
                                          bool controlled) {
  std::vector<systems::DriveSpec> drives;
  for (int k = 0; k < 6; ++k) {
    systems::DriveSpec d;
    d.joint = m.joint_names[static_cast<size_t>(k)];
    d.motor = drive::DcMotorParams::ur5(k + 1);
    d.transmission = gear(k);
    if (controlled) {
      d.controller.type = control::ControllerType::VoltageCascade;
      d.controller.P_pos = kGains[k][0];
      d.controller.P_vel = kGains[k][1];
      d.controller.I_vel = kGains[k][2];
      d.controller.P_cur = kGains[k][3];
      d.controller.I_cur = kGains[k][4];
    } else {
      d.electrics = false;
    }
    drives.push_back(d);
  }
  return drives;
}

// Smooth reference: q_set = q0 + A sin(ω t) with its derivatives.
systems::SetpointFunction sineSetpoints(Eigen::VectorXd q0, double A, double w) {
  return [q0, A, w](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                    Eigen::Ref<Eigen::VectorXd> qdd) {
    q = q0.array() + A * std::sin(w * t);
    qd.setConstant(A * w * std::cos(w * t));
    qdd.setConstant(-A * w * w * std::sin(w * t));
  };
}

Eigen::VectorXd homePose() {
  Eigen::VectorXd q(6);
  q << 0.2, -1.2, 1.0, -0.8, 0.5, 0.1;
  return q;
}
}  // namespace

TEST(RobotSystem, RigidGearJointTorqueEqualsRneaOfSimulatedMotion) {
  const auto ur5 = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  systems::RobotSystem sys(ur5, ur5Drives(
                                    ur5, [](int) { return std::make_shared<drive::RigidGear>(101.0); }, true));
  sys.setSetpoints(sineSetpoints(homePose(), 0.3, 2.0));
  sim::CvodeOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.max_order = 2;
  const auto st = sys.makeState();
  sim::CvodeIntegrator integ(
      sys.stateSize(),
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        sys.derivatives(*st, t, y, yd);
      },
      o);
  Eigen::VectorXd y = sys.initialState(homePose());
  integ.initialize(0.0, y);
  multibody::Data data(ur5);
  double max_track = 0;
  for (double t = 0.1; t <= 1.0 + 1e-9; t += 0.1) {
    integ.advance(t, y);
    const auto& s = sys.driveSignals(*st, t, y);
    // The drives' output torques are exactly what the rigid arm needs for the simulated motion.
    const Eigen::VectorXd tau = multibody::rnea(ur5, data, y.head(6), y.segment(6, 6), s.qdd);
    EXPECT_TRUE(test::MatricesNear(s.tau_gear, tau, 1e-9)) << "t = " << t;
    max_track = std::max(max_track, (s.q_set - y.head(6)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(max_track, 1e-3) << "the [Raviola2023] cascade tracks the reference";
}

TEST(RobotSystem, StartsAtRestHoldingGravity) {
  const auto ur5 = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  systems::RobotSystem sys(ur5, ur5Drives(
                                    ur5,
                                    [](int k) {
                                      return std::make_shared<drive::StrainWaveGear>(
                                          k < 3 ? drive::StrainWaveGearParams::ur5SizeA()
                                                : drive::StrainWaveGearParams::ur5SizeB());
                                    },
                                    true));
  const Eigen::VectorXd y0 = sys.initialState(homePose());
  Eigen::VectorXd yd(sys.stateSize());
  const auto st = sys.makeState();
  sys.start(*st, 0.0, y0);  // no trajectory: the reference holds the start pose
  sys.derivatives(*st, 0.0, y0, yd);
  // Every state derivative vanishes: joints at rest, gears in static equilibrium, currents and integrators steady.
  EXPECT_LT(yd.cwiseAbs().maxCoeff(), 1e-6) << "max |ydot| at index " << [&] {
    Eigen::Index i;
    yd.cwiseAbs().maxCoeff(&i);
    return i;
  }();
}

TEST(RobotSystem, StrainWaveGearSpeedRatio101) {
  const auto ur5 = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  systems::RobotSystem sys(ur5, ur5Drives(
                                    ur5,
                                    [](int k) {
                                      auto p = k < 3 ? drive::StrainWaveGearParams::ur5SizeA()
                                                     : drive::StrainWaveGearParams::ur5SizeB();
                                      return std::make_shared<drive::StrainWaveGear>(p);
                                    },
                                    true));
  // Base joint turns at a constant 0.5 rad/s after a smooth start; the others hold.
  const Eigen::VectorXd q0 = homePose();
  sys.setSetpoints(
      [q0](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd) {
        q = q0;
        qd.setZero();
        qdd.setZero();
        const double T = 0.2, v = 0.5;  // quadratic blend to 0.5 rad/s over 0.2 s
        if (t < T) {
          q[0] += 0.5 * v / T * t * t;
          qd[0] = v / T * t;
          qdd[0] = v / T;
        } else {
          q[0] += 0.5 * v * T + v * (t - T);
          qd[0] = v;
        }
      });
  sim::CvodeOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.max_order = 2;
  o.max_step = 1e-3;
  const auto st = sys.makeState();
  sim::CvodeIntegrator integ(
      sys.stateSize(),
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        sys.derivatives(*st, t, y, yd);
      },
      o);
  Eigen::VectorXd y = sys.initialState(q0);
  integ.initialize(0.0, y);
  integ.setStopTime(0.2);
  integ.advance(0.2, y);
  integ.initialize(0.2, y);
  integ.advance(1.0, y);
  const auto& s = sys.driveSignals(*st, 1.0, y);
  EXPECT_NEAR(y[6], 0.5, 1e-4);
  EXPECT_NEAR(s.qdm[0] / y[6], 101.0, 1e-4);
}

TEST(RobotSystem, TorqueFreeFrictionlessRunConservesEnergy) {
  // Uncontrolled, frictionless, undamped elastic gears with rotor inertias: all energy is mechanical.
  const auto ur5 = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  systems::RobotSystem sys(ur5, ur5Drives(
                                    ur5,
                                    [](int k) {
                                      return std::make_shared<drive::ElasticGear>(drive::ElasticGearParams{
                                          101.0, k < 3 ? 1.4e5 : 2.6e4, 0.0, drive::ComplianceSide::Output});
                                    },
                                    false));
  sim::CvodeOptions o;
  o.method = sim::Method::Adams;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  const auto st = sys.makeState();
  sim::CvodeIntegrator integ(
      sys.stateSize(),
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        sys.derivatives(*st, t, y, yd);
      },
      o);
  Eigen::VectorXd y = sys.initialState(homePose());
  integ.initialize(0.0, y);
  const double E0 = sys.mechanicalEnergy(y);
  double max_dev = 0, max_T = 0;
  multibody::Data data(sys.model());
  for (int k = 1; k <= 200; ++k) {
    integ.advance(0.01 * k, y);
    max_dev = std::max(max_dev, std::abs(sys.mechanicalEnergy(y) - E0));
    max_T = std::max(max_T, multibody::kineticEnergy(sys.model(), data, y.head(6), y.segment(6, 6)));
  }
  ASSERT_GT(max_T, 1.0) << "the arm really falls";
  EXPECT_LT(max_dev / max_T, 1e-6) << "drift " << max_dev << " J, peak kinetic energy " << max_T << " J";
}

TEST(RobotSystem, Irb140CoupledWristWith000ControllersHoldsAndBalancesTorques) {
  // The IRB140 of [Olsson2017]: rigid gears (ratios of Listing 4.1, wrist reduction in G), motor inertia 0.014,
  // motor-side P/PI controllers ([Olsson2017, A.12], Listing 4.1 gains) commanding torque, wrist coupling matrix.
  const auto irb = multibody::loadRobot(test::sourcePath("config/robots/irb140.yaml"));
  const double ratio[6] = {104.4, 104.4, 100.74, 1, 1, 1};
  const double kp[6] = {0.008, 0.008, 0.008, 0.008, 0.008, 0.008}, ks[6] = {0.01, 0.01, 0.01, 0.002, 0.005, 0.001},
               Ts[6] = {0.11, 0.12, 0.28, 0.15, 0.24, 0.12};
  std::vector<systems::DriveSpec> drives;
  for (int k = 0; k < 6; ++k) {
    systems::DriveSpec d;
    d.joint = irb.joint_names[static_cast<size_t>(k)];
    d.motor.J_M = 0.014;
    d.electrics = false;
    d.transmission = std::make_shared<drive::RigidGear>(ratio[k]);
    d.controller.type = control::ControllerType::TorqueCascade;
    d.controller.kp = kp[k];
    d.controller.ks = ks[k];
    d.controller.Ts = Ts[k];
    drives.push_back(d);
  }
  Eigen::MatrixXd G = Eigen::MatrixXd::Identity(6, 6);
  G.bottomRightCorner(3, 3) = drive::CouplingMatrix::irb140Wrist();
  systems::RobotSystem sys(irb, drives, G);
  Eigen::VectorXd q0(6);
  q0 << 0.1, 0.2, -0.3, 0.2, 0.4, -0.1;
  sys.setSetpoints(
      [q0](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd) {
        q = q0;
        q[4] += 0.05 * std::sin(3 * t);
        qd.setZero();
        qd[4] = 0.15 * std::cos(3 * t);
        qdd.setZero();
        qdd[4] = -0.45 * std::sin(3 * t);
      });
  Eigen::VectorXd y = sys.initialState(q0);
  Eigen::VectorXd yd(sys.stateSize());
  const auto st = sys.makeState();
  sys.derivatives(*st, 0.0, y, yd);
  EXPECT_LT(yd.segment(6, 6).cwiseAbs().maxCoeff(), 1e-9) << "gravity held at the start";
  sim::CvodeOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  o.max_order = 2;
  sim::CvodeIntegrator integ(
      sys.stateSize(),
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& yy, Eigen::Ref<Eigen::VectorXd> d) {
        sys.derivatives(*st, t, yy, d);
      },
      o);
  integ.initialize(0.0, y);
  multibody::Data data(irb);
  // Reflected rotor inertia G⁻ᵀ diag(N² J_M) G⁻¹ (the coupled wrist makes it non-diagonal).
  Eigen::VectorXd rot(6);
  for (int k = 0; k < 6; ++k) rot[k] = ratio[k] * ratio[k] * 0.014;
  const Eigen::MatrixXd Ginv = G.inverse();
  const Eigen::MatrixXd R = Ginv.transpose() * rot.asDiagonal() * Ginv;
  EXPECT_GT(std::abs(R(4, 3)), 1e-3) << "the wrist coupling matters";
  for (double t = 0.2; t <= 1.0 + 1e-9; t += 0.2) {
    integ.advance(t, y);
    const auto& s = sys.driveSignals(*st, t, y);
    // Joint torques from the motors = rigid-body torques + reflected rotor inertia.
    const Eigen::VectorXd rhs = multibody::rnea(irb, data, y.head(6), y.segment(6, 6), s.qdd) + R * s.qdd;
    EXPECT_TRUE(test::MatricesNear(s.tau_joint, rhs, 1e-8)) << "t = " << t;
    EXPECT_LT((y.head(6) - s.q_set).cwiseAbs().maxCoeff(), 0.05) << "the low gains of [Olsson2017] still hold the arm";
  }
}
