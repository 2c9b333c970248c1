// Command ports of the robot with drives (systems::RobotSystem) driven through sim::Simulator: each port against
// a closed form on a single gravity-free joint, the external wrench against the Jacobian transpose, bad inputs,
// and a set-point → voltage → set-point switch on the UR5 twin.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

using systems::CommandPort;

constexpr double kN = 10.0;   // gear ratio
constexpr double kIzz = 0.2;  // link inertia about the joint axis [kg·m²]

/// One revolute joint about the vertical axis (gravity along −z exerts no torque), a rigid gear, a DC motor and
/// the cascade controller; no friction.
systems::RobotSystem singleJoint(bool electrics = true) {
  multibody::ModelBuilder b("turntable", "base");
  multibody::JointSpec j;
  j.name = "j1";
  j.axis = {0, 0, 1};
  multibody::BodyInertia I;
  I.mass = 1.0;
  I.inertia = Eigen::Vector3d(0.15, 0.15, kIzz).asDiagonal();
  b.addLink("base", j, "disc", I);
  b.addFrame("rim", "disc", {Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.5, 0.0, 0.0)});
  systems::DriveSpec d;
  d.joint = "j1";
  d.electrics = electrics;
  d.transmission = std::make_shared<drive::RigidGear>(kN);
  if (electrics) {
    d.controller.type = control::ControllerType::VoltageCascade;
    d.controller.P_pos = 50;
    d.controller.P_vel = 0.2;
    d.controller.I_vel = 2.0;
    d.controller.P_cur = 10;
    d.controller.I_cur = 5000;
  } else {
    d.controller.type = control::ControllerType::TorqueCascade;
    d.controller.kp = 20;
    d.controller.ks = 0.05;
    d.controller.Ts = 0.02;
  }
  return systems::RobotSystem(b.build(), {d});
}

sim::CvodeOptions tight() {
  sim::CvodeOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  o.max_step = 1e-3;
  return o;
}

/// A joint rig with a rigid gear N = 4, rotor 2e-3 kg·m², load 0.5 kg·m², a torque input whose profile is 1 N·m.
systems::JointRigSetup rigidRig() {
  systems::JointRigSetup setup;
  setup.rotor_inertia = 2e-3;
  setup.load_inertia = 0.5;
  setup.transmission = std::make_shared<drive::RigidGear>(4.0);
  setup.profile = control::Profile::constant(1.0);
  return setup;
}

double jointInertia(const systems::RobotSystem& r) { return kIzz + kN * kN * r.drives()[0].motor.J_M; }

TEST(CommandPorts, VoltageGivesTheMotorsNoLoadSpeed) {
  systems::RobotSystem r = singleJoint();
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::Voltage);
  r.setCommand(s.plantState(), 0, 12.0);
  s.advanceTo(1.5);  // mechanical time constant J R / (k_t k_e) ≈ 40 ms
  const auto& m = r.drives()[0].motor;
  EXPECT_NEAR(s.signal("motor_velocity_j1"), 12.0 / m.ke, 1e-6 * 12.0 / m.ke);
  EXPECT_DOUBLE_EQ(s.signal("voltage_j1"), 12.0);
  // Beyond the supply the PWM saturates at V_supply.
  r.setCommand(s.plantState(), 0, 1e3);
  s.advance(1.5);
  EXPECT_DOUBLE_EQ(s.signal("voltage_j1"), m.V_supply);
  EXPECT_NEAR(s.signal("motor_velocity_j1"), m.V_supply / m.ke, 1e-6 * m.V_supply / m.ke);
}

TEST(CommandPorts, MotorTorqueAcceleratesTheReflectedInertia) {
  systems::RobotSystem r = singleJoint();
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::MotorTorque);
  r.setCommand(s.plantState(), 0, 0.5);
  s.advanceTo(0.3);
  const double a = kN * 0.5 / jointInertia(r);  // q̈ = N τ / (J_l + N² J_M)
  EXPECT_NEAR(s.signal("q_j1"), 0.5 * a * 0.09, 1e-8);
  EXPECT_NEAR(s.signal("qd_j1"), a * 0.3, 1e-8);
  // The bypassed electrics: the current has relaxed to τ/k_t (L/R ≈ 3 ms).
  EXPECT_NEAR(s.signal("current_j1"), 0.5 / r.drives()[0].motor.kt, 1e-6);
}

TEST(CommandPorts, CurrentReferenceIsTrackedAndGivesTorqueConstantTimesCurrent) {
  systems::RobotSystem r = singleJoint();
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::Current);
  r.setCommand(s.plantState(), 0, 2.0);
  s.advanceTo(0.2);
  // The motor speeds up at a constant rate, so the back-EMF k_e ω_m is a ramp disturbance of the current PI loop:
  // it leaves the steady error k_e ω̇_m / I_cur. With ω̇_m = N² k_t i / J: i = i_ref / (1 + k_e N² k_t / (J I_cur)).
  const auto& m = r.drives()[0].motor;
  const double J = jointInertia(r);
  const double i_ss = 2.0 / (1.0 + m.ke * kN * kN * m.kt / (J * 5000.0));
  EXPECT_NEAR(s.signal("current_j1"), i_ss, 1e-6);
  EXPECT_DOUBLE_EQ(s.signal("current_ref_j1"), 2.0);
  const double qd1 = s.signal("qd_j1");
  s.advance(0.1);
  const double a = kN * m.kt * i_ss / J;
  EXPECT_NEAR((s.signal("qd_j1") - qd1) / 0.1, a, 1e-6 * a);
}

TEST(CommandPorts, MotorVelocityAndHeldSetpointsReachTheirReferences) {
  systems::RobotSystem r = singleJoint();
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::MotorVelocity);
  r.setCommand(s.plantState(), 0, 50.0);
  s.advanceTo(4.0);
  EXPECT_NEAR(s.signal("motor_velocity_j1"), 50.0, 1e-4);
  // Back to the set-point port, holding 0.3 rad: no load torque, so the PI loops remove every error.
  r.setCommandPort(s.plantState(), 0, CommandPort::Setpoint);
  r.setSetpoint(s.plantState(), 0, 0.3);
  s.advance(4.0);
  EXPECT_NEAR(s.signal("q_j1"), 0.3, 1e-5);
  EXPECT_DOUBLE_EQ(s.signal("q_set_j1"), 0.3);
}

TEST(CommandPorts, TorqueControlledDriveAcceptsVelocityButNotCurrentOrVoltage) {
  systems::RobotSystem r = singleJoint(false);
  const auto st = r.makeState();
  EXPECT_THROW(r.setCommandPort(*st, 0, CommandPort::Voltage), InputError);
  EXPECT_THROW(r.setCommandPort(*st, 0, CommandPort::Current), InputError);
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::MotorVelocity);
  r.setCommand(s.plantState(), 0, 20.0);
  s.advanceTo(4.0);
  EXPECT_NEAR(s.signal("motor_velocity_j1"), 20.0, 1e-4);
}

TEST(CommandPorts, BadCommandsAreInputErrorsAndChangeNothing) {
  systems::RobotSystem r = singleJoint();
  const auto st = r.makeState();
  const long rev = st->inputRevision();
  EXPECT_THROW(r.setCommand(*st, 0, 1.0), InputError);  // under the set-point port
  r.setCommandPort(*st, 0, CommandPort::Voltage);
  const long rev2 = st->inputRevision();
  EXPECT_GT(rev2, rev);
  EXPECT_THROW(r.setCommand(*st, 0, std::nan("")), InputError);
  EXPECT_THROW(r.setCommand(*st, 0, INFINITY), InputError);
  EXPECT_THROW(r.setCommand(*st, 1, 1.0), InputError);
  EXPECT_THROW(r.setCommandPort(*st, -1, CommandPort::Voltage), InputError);
  EXPECT_THROW(r.setCommandPort(*st, "j9", CommandPort::Voltage), InputError);
  EXPECT_THROW(r.setCommands(*st, Eigen::VectorXd::Zero(2)), InputError);
  EXPECT_THROW(r.setSetpoint(*st, 0, std::nan("")), InputError);
  EXPECT_THROW(r.holdSetpoints(*st, Eigen::VectorXd::Zero(3)), InputError);
  EXPECT_THROW(r.setExternalWrench(*st, "nowhere", Eigen::Matrix<double, 6, 1>::Ones()), InputError);
  EXPECT_THROW(r.setExternalWrench(*st, "base", Eigen::Matrix<double, 6, 1>::Ones()), InputError);
  EXPECT_THROW(systems::parsePort("pwm"), InputError);
  EXPECT_EQ(st->inputRevision(), rev2);
  EXPECT_EQ(r.command(*st, 0), 0.0);
  // The same value again is not a change.
  r.setCommand(*st, 0, 3.0);
  const long rev3 = st->inputRevision();
  r.setCommand(*st, 0, 3.0);
  r.setCommandPort(*st, 0, CommandPort::Voltage);
  EXPECT_EQ(st->inputRevision(), rev3);
  EXPECT_EQ(systems::parsePort("motor_torque"), CommandPort::MotorTorque);
}

TEST(CommandPorts, ExternalWrenchActsAsTheJacobianTransposeSays) {
  // Two-link planar arm with rigid drives under zero motor torque: adding a world wrench W at a frame changes
  // q̈ by M⁻¹ J(q)ᵀ W (M with the reflected rotor inertias), an independent path from the body-frame wrench
  // that the articulated-body algorithm receives.
  multibody::Model model = multibody::loadRobot(test::sourcePath("tests/data/planar2.urdf"));
  std::vector<systems::DriveSpec> drives;
  for (const auto& name : model.joint_names) {
    systems::DriveSpec d;
    d.joint = name;
    d.electrics = false;
    d.transmission = std::make_shared<drive::RigidGear>(5.0);
    drives.push_back(d);
  }
  systems::RobotSystem r(model, drives);
  const auto st = r.makeState();
  const std::string frame = r.model().tip_frame;
  for (int k = 0; k < 2; ++k) r.setCommandPort(*st, k, CommandPort::MotorTorque);
  Eigen::VectorXd y = r.initialState(Eigen::Vector2d(0.4, -0.7));
  y.segment(2, 2) << 0.3, -0.2;
  Eigen::VectorXd yd0(y.size()), yd1(y.size());
  r.derivatives(*st, 0.0, y, yd0);
  Eigen::Matrix<double, 6, 1> W;
  W << 3.0, -2.0, 5.0, 0.4, -0.3, 0.7;  // [f (N); n (N·m)], world axes, at the frame origin
  r.setExternalWrench(*st, frame, W);
  r.derivatives(*st, 0.0, y, yd1);
  multibody::Data data(r.model());
  const Eigen::MatrixXd M = multibody::crba(r.model(), data, y.head(2));
  const Eigen::MatrixXd J = multibody::frameJacobian(r.model(), data, y.head(2), r.model().frameIndex(frame));
  const Eigen::VectorXd expected = M.ldlt().solve(J.transpose() * W);
  EXPECT_TRUE(test::MatricesNear(yd1.segment(2, 2) - yd0.segment(2, 2), expected, 1e-10));
  // Removing it restores the free motion.
  r.setExternalWrench(*st, frame, Eigen::Matrix<double, 6, 1>::Zero());
  r.derivatives(*st, 0.0, y, yd1);
  EXPECT_TRUE(test::MatricesNear(yd1, yd0, 0.0));
}

TEST(CommandPorts, SetpointVoltageSetpointSwitchOnTheUr5TwinIsBumpless) {
  // The UR5 twin holding its start pose; mid-run the elbow goes to the voltage port (commanded the voltage it
  // had), then back to the set-point port. The voltage is continuous at both switches (bumpless transfer: the
  // controller integrators are re-initialised), and the joint stays within the physics of the open-loop phase.
  std::shared_ptr<experiments::Experiment> e =
      experiments::loadExperiment(test::sourcePath("config/experiments/ur5_pick_and_place.yaml"));
  auto s = experiments::makeSimulator(e);
  const auto& r = dynamic_cast<const systems::RobotSystem&>(s->plant());
  const int k = r.model().jointIndex("elbow_joint");
  const Eigen::VectorXd q0 = s->state().head(6);
  r.holdSetpoints(s->plantState(), q0);
  const int iv = s->signalIndex("voltage_elbow_joint"), iq = s->signalIndex("q_elbow_joint");
  double worst = 0.0;
  auto run = [&](double until) {
    while (s->time() < until - 1e-12) {
      s->advance(1e-3);
      worst = std::max(worst, std::abs(s->signals()[iq] - q0[k]));
    }
  };
  run(0.2);
  const double v_before = s->signals()[iv];
  r.setCommandPort(s->plantState(), k, CommandPort::Voltage);
  r.setCommand(s->plantState(), k, v_before);
  s->advance(1e-7);
  EXPECT_NEAR(s->signals()[iv], v_before, 1e-6);
  run(0.3);
  const double v_open = s->signals()[iv];
  EXPECT_DOUBLE_EQ(v_open, v_before);
  const double drift = std::abs(s->signals()[iq] - q0[k]);
  r.setCommandPort(s->plantState(), k, CommandPort::Setpoint);
  s->advance(1e-7);
  EXPECT_NEAR(s->signals()[iv], v_open, 1e-3);  // bumpless: the cascade continues from the applied voltage
  run(0.8);
  EXPECT_LT(std::abs(s->signals()[iq] - q0[k]), 1e-4);  // back on the held pose
  EXPECT_LT(worst, std::max(2.0 * drift, 1e-4));        // no excursion beyond the open-loop drift
}

TEST(CommandPorts, TheTwinIsTimeInvariantOnlyWhenEveryDriveBypassesItsController) {
  // The excitation's twin (continuous control, a Fourier reference of t). While a controller runs, f(t, y) moves with
  // t; with every drive on the voltage or motor-torque port nothing in f reads t (the reference and the sensor faults'
  // episodes reach it only through a controller), so timeInvariant() may say so: f is then bit for bit the same at
  // any t, and the fixed-step method differences no ∂f/∂t (one right-hand side less per Jacobian).
  std::shared_ptr<experiments::Experiment> e =
      experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"));
  sim::CvodeOptions o;
  o.method = sim::Method::Rosenbrock;
  o.fixed_step = 1e-3;
  sim::Simulator s(e->plant(), o);
  const auto& r = dynamic_cast<const systems::RobotSystem&>(s.plant());
  Eigen::VectorXd y = s.state();
  y.segment(6, 6).setConstant(0.1);  // moving joints
  Eigen::VectorXd f1(y.size()), f2(y.size());
  auto differs = [&] {
    r.derivatives(s.plantState(), 2.3, y, f1);
    r.derivatives(s.plantState(), 4.1, y, f2);
    return (f1 - f2).cwiseAbs().maxCoeff();
  };
  EXPECT_FALSE(r.timeInvariant(s.plantState()));
  EXPECT_GT(differs(), 1e-3);
  for (int k = 0; k < 6; ++k)
    r.setCommandPort(s.plantState(), k, k < 3 ? CommandPort::Voltage : CommandPort::MotorTorque);
  EXPECT_TRUE(r.timeInvariant(s.plantState()));
  EXPECT_EQ(differs(), 0.0);
  for (CommandPort driven : {CommandPort::Setpoint, CommandPort::MotorVelocity, CommandPort::Current}) {
    r.setCommandPort(s.plantState(), 4, driven);
    EXPECT_FALSE(r.timeInvariant(s.plantState())) << static_cast<int>(driven);
  }
  r.setCommandPort(s.plantState(), 4, CommandPort::Voltage);
  s.advance(0.01);
  EXPECT_EQ(s.stats().rhs_evals_jacobian, 0);
  EXPECT_EQ(s.stats().jac_evals, 10);
}

// A load torque at the joint (the `j1.load_torque` input) with the motor torque held at 0: q̈ = τ_L / (J_l + N² J_M)
// (the rigid gear's rotor turns with the joint); released, the joint coasts at the speed it reached.
TEST(CommandPorts, LoadTorqueAcceleratesTheJointInertiaAndIsReleased) {
  systems::RobotSystem r = singleJoint();
  sim::Simulator s(r, tight());
  r.setCommandPort(s.plantState(), 0, CommandPort::MotorTorque);
  r.setCommand(s.plantState(), 0, 0.0);
  const int port = sim::inputIndex(r, "j1.load_torque");
  EXPECT_EQ(r.inputPorts()[static_cast<size_t>(port)].unit, "N·m");
  EXPECT_TRUE(r.inputActive(s.plantState(), port));
  EXPECT_EQ(r.input(s.plantState(), port), 0.0);
  r.setInput(s.plantState(), port, 0.3);
  EXPECT_EQ(r.input(s.plantState(), port), 0.3);
  s.advanceTo(0.3);
  const double a = 0.3 / jointInertia(r);
  EXPECT_NEAR(s.signal("q_j1"), 0.5 * a * 0.09, 1e-8);
  EXPECT_NEAR(s.signal("qd_j1"), a * 0.3, 1e-8);
  r.releaseInput(s.plantState(), port);
  EXPECT_EQ(r.input(s.plantState(), port), 0.0);
  s.advanceTo(0.5);
  EXPECT_NEAR(s.signal("qd_j1"), a * 0.3, 1e-8);
  EXPECT_NEAR(s.signal("q_j1"), 0.5 * a * 0.09 + a * 0.3 * 0.2, 1e-8);
  // A command port is not released, nor driven by a profile; a load torque must be finite.
  EXPECT_THROW(r.releaseInput(s.plantState(), sim::inputIndex(r, "j1.voltage")), InputError);
  EXPECT_THROW(r.setInput(s.plantState(), port, std::nan("")), InputError);
  systems::RobotSystem fresh = singleJoint();
  EXPECT_THROW(fresh.setInputProfile(sim::inputIndex(fresh, "j1.current"), control::Profile::constant(1.0)),
               InputError);
}

// The UR5 twin (compliant strain-wave gears): a load torque τ_L at the elbow changes the joint accelerations by
// M(q)⁻¹ e_elbow τ_L at the same state (CRBA and a Cholesky solve, an algorithm apart from the twin's ABA) — from a
// value held at the port and from a step profile given by the tracking file's `inputs:` key, whose step time becomes
// a time event. A saved state keeps the held value.
TEST(InputPorts, LoadTorquesOnTheUr5TwinFromThePortAndFromTheFilesInputsKey) {
  const test::TempDir dir;
  const std::string path = (dir / "twin.yaml").string();
  std::ofstream(path) << "experiment: {name: twin_load, type: tracking}\nrobot: "
                      << test::sourcePath("config/robots/ur5_drives.yaml")
                      << "\ntrajectory: {type: point_to_point, start: [0.3, -1.2, 1.2, -1.5, -1.5708, 0.2], "
                         "segments: [{target: [0.3, -1.2, 1.2, -1.5, -1.5708, 0.3], velocity: 1, acceleration: 1}]}\n"
                         "inputs:\n  elbow_joint.load_torque: {type: step, initial: 0, final: 5, time: 0.05}\n"
                         "duration: 0.1\n";
  std::shared_ptr<experiments::Experiment> e = experiments::loadExperiment(path);
  const auto& r = dynamic_cast<const systems::RobotSystem&>(e->plant());
  const std::vector<double> events = r.timeEvents(0.1);
  EXPECT_NE(std::find(events.begin(), events.end(), 0.05), events.end());
  const int k = r.model().jointIndex("elbow_joint"), n = r.model().nq;
  Eigen::VectorXd q0(6);
  q0 << 0.3, -1.2, 1.2, -1.5, -1.5708, 0.2;
  Eigen::VectorXd y = r.initialState(q0);
  y.segment(n, n).setConstant(0.4);  // joints moving
  const std::unique_ptr<sim::PlantState> st = r.makeState();
  r.start(*st, 0.0, y);
  multibody::Data data(r.model());
  Eigen::MatrixXd M = multibody::crba(r.model(), data, y.head(n));
  const Eigen::VectorXd col = M.llt().solve(Eigen::VectorXd::Unit(n, k));
  auto qdd = [&](double t) {
    Eigen::VectorXd yd(y.size());
    r.derivatives(*st, t, y, yd);
    return Eigen::VectorXd(yd.segment(n, n));
  };
  // The twin's rotor states do not move the joint accelerations at a fixed state: only the reference does, through
  // the controllers, which act on the currents' derivatives, not on q̈.
  const Eigen::VectorXd before = qdd(0.0499), after = qdd(0.0501);
  EXPECT_LT((after - before - 5.0 * col).cwiseAbs().maxCoeff(), 1e-9 * (5.0 * col).cwiseAbs().maxCoeff());
  const int port = sim::inputIndex(r, "elbow_joint.load_torque");
  r.setInput(*st, port, -2.0);  // held: in place of the profile
  const Eigen::VectorXd held = qdd(0.0501);
  EXPECT_LT((held - before + 2.0 * col).cwiseAbs().maxCoeff(), 1e-9 * (2.0 * col).cwiseAbs().maxCoeff());
  // Through a simulator: a saved state restores the held value.
  auto s = experiments::makeSimulator(e);
  s->plant().setInput(s->plantState(), port, 1.5);
  const std::string bytes = s->saveState();
  auto s2 = experiments::makeSimulator(e);
  s2->loadState(bytes);
  EXPECT_EQ(s2->plant().input(s2->plantState(), port), 1.5);
}

TEST(CommandPorts, JointRigHoldsACommandAndTakesALoadTorque) {
  // Rigid gear N = 4, torque input: the held command τ and a load torque τ_l on the output give
  // q̈_m = (τ + τ_l / N) / (J_m + J_l / N²) from rest (closed form q_m = ½ q̈_m t²).
  systems::JointRig rig(rigidRig());
  sim::Simulator s(rig, tight());
  rig.setCommand(s.plantState(), 0.3);
  rig.setLoadTorque(s.plantState(), -0.4);
  EXPECT_THROW(rig.setCommand(s.plantState(), std::nan("")), InputError);
  EXPECT_THROW(rig.setLoadTorque(s.plantState(), INFINITY), InputError);
  s.advanceTo(0.5);
  const double a = (0.3 - 0.4 / 4.0) / (2e-3 + 0.5 / 16.0);
  EXPECT_NEAR(s.signal("motor_angle"), 0.5 * a * 0.25, 1e-9);
  EXPECT_DOUBLE_EQ(s.signal("command_torque"), 0.3);
  rig.releaseCommand(s.plantState());  // back to the profile (1 N·m)
  EXPECT_DOUBLE_EQ(s.signal("command_torque"), 1.0);
}

// The same ports through the plant interface (sim::Plant::inputPorts/setInput), as the FMU and Python use them: the
// table names every port the drive has with its unit, and a run driven through it equals, bit for bit, one driven
// through the robot's own setters.
TEST(InputPorts, TheRobotsPortsAsNamedInputsActAsItsOwnSetters) {
  systems::RobotSystem r = singleJoint();
  const auto ports = r.inputPorts();
  std::vector<std::string> names, units;
  for (const auto& p : ports) {
    names.push_back(p.name);
    units.push_back(p.unit);
    EXPECT_EQ(p.group, p.name == "j1.load_torque" ? "" : "j1");  // the load torque is no alternative command
    EXPECT_FALSE(p.description.empty());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"j1.q", "j1.qd", "j1.qdd", "j1.motor_velocity", "j1.current", "j1.voltage",
                                             "j1.motor_torque", "j1.load_torque"}));
  EXPECT_EQ(units, (std::vector<std::string>{"rad", "rad/s", "rad/s²", "rad/s", "A", "V", "N·m", "N·m"}));
  EXPECT_EQ(ports[5].mode, "voltage");
  EXPECT_EQ(ports[1].mode, "setpoint");
  // A torque-controlled drive has no current or voltage port.
  systems::RobotSystem t = singleJoint(false);
  for (const auto& p : t.inputPorts()) EXPECT_TRUE(p.name != "j1.current" && p.name != "j1.voltage") << p.name;
  try {
    (void)sim::inputIndex(t, "j1.voltage");
    FAIL() << "a port the drive lacks";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("j1.motor_torque"), std::string::npos) << e.what();  // lists the inputs
  }

  auto drive = [&](bool generic) {
    sim::Simulator s(r, tight());
    if (generic) {
      s.plant().setInput(s.plantState(), sim::inputIndex(r, "j1.voltage"), 12.0);
      EXPECT_TRUE(r.inputActive(s.plantState(), 5));
      EXPECT_FALSE(r.inputActive(s.plantState(), 0));
      EXPECT_EQ(r.input(s.plantState(), 5), 12.0);
    } else {
      r.setCommandPort(s.plantState(), 0, CommandPort::Voltage);
      r.setCommand(s.plantState(), 0, 12.0);
    }
    s.advanceTo(0.1);
    if (generic) {
      s.plant().setInput(s.plantState(), sim::inputIndex(r, "j1.q"), 0.7);
      s.plant().setInput(s.plantState(), sim::inputIndex(r, "j1.qd"), 0.1);
      EXPECT_EQ(r.commandPort(s.plantState(), 0), CommandPort::Setpoint);
      EXPECT_EQ(r.input(s.plantState(), 0), 0.7);
    } else {
      r.setCommandPort(s.plantState(), 0, CommandPort::Setpoint);
      r.setSetpoint(s.plantState(), 0, 0.7, 0.1);
    }
    s.advanceTo(0.3);
    return Eigen::VectorXd(s.state());
  };
  const Eigen::VectorXd a = drive(true), b = drive(false);
  EXPECT_EQ(a, b);
  EXPECT_GT(std::abs(a[0]), 0.1);  // it moved
  sim::Simulator s(r, tight());
  EXPECT_THROW(r.setInput(s.plantState(), 8, 1.0), InputError);
  EXPECT_THROW(r.setInput(s.plantState(), 5, std::nan("")), InputError);
  EXPECT_EQ(r.commandPort(s.plantState(), 0), CommandPort::Setpoint);  // the refused value changed nothing
}

TEST(InputPorts, TheJointRigsCommandAndLoadTorqueAreNamedInputs) {
  systems::JointRig rig(rigidRig());
  const auto ports = rig.inputPorts();
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].name, "command");
  EXPECT_EQ(ports[0].unit, "N·m");
  EXPECT_EQ(ports[1].name, "load_torque");
  sim::Simulator s(rig, tight());
  EXPECT_FALSE(rig.inputActive(s.plantState(), 0));  // the profile until a command is held
  rig.setInput(s.plantState(), 0, 0.3);
  rig.setInput(s.plantState(), sim::inputIndex(rig, "load_torque"), -0.4);
  EXPECT_TRUE(rig.inputActive(s.plantState(), 0));
  s.advanceTo(0.5);
  const double a = (0.3 - 0.4 / 4.0) / (2e-3 + 0.5 / 16.0);
  EXPECT_NEAR(s.signal("motor_angle"), 0.5 * a * 0.25, 1e-9);
  EXPECT_THROW(rig.setInput(s.plantState(), 2, 0.0), InputError);
}

}  // namespace
}  // namespace jointsim
