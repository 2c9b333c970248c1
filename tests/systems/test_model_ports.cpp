// Input ports on every model, not only the robot with drives and the joint rig (sim::Plant::inputPorts): the drive
// chain's torque sources and inertia loads, the passive robot's joint torques, the clamped robot's motor and load
// torques, the RobotR3 axis and FullRobot's current references and load torques. Each against something
// independent: a closed form, gravity torques from RNEA, the frozen controller, a saved state that restores the
// inputs.
#include <algorithm>
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/clamped_robot.hpp"
#include "jointsim/systems/drive_chain.hpp"
#include "jointsim/systems/passive_robot.hpp"
#include "jointsim/systems/robotr3_full.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

// One inertia of 2 kg·m² driven by a source whose profile is 1 N·m.
systems::DriveChainSetup oneInertia() {
  systems::DriveChainSetup s;
  s.inertias = {{"shaft", 2.0, 0.0, 0.0}};
  systems::ChainElement src;
  src.name = "motor";
  src.type = systems::ChainElementType::TorqueSource;
  src.b = 0;
  src.torque = control::Profile::constant(1.0);
  s.elements = {src};
  s.duration = 10.0;
  return s;
}

sim::CvodeOptions tight() {
  sim::CvodeOptions o = systems::DriveChainSetup::defaultSolver();
  o.rtol = 1e-10;
  o.atol = 1e-12;
  return o;
}

std::shared_ptr<experiments::Experiment> load(const std::string& file, const std::vector<std::string>& sets) {
  return std::shared_ptr<experiments::Experiment>(
      experiments::loadExperiment(test::sourcePath("config/experiments/" + file), sets));
}

// A copy of `plant` (a P) with a step profile at `port` at t = 0.137 s: that time must be one of its time events (so
// that no step of the integrator crosses the jump), besides the model's own events.
template <class P>
void expectAProfilesStepIsATimeEvent(const sim::Plant& plant, const std::string& port) {
  P copy = dynamic_cast<const P&>(plant);  // a copy is another plant, not frozen: it takes profiles
  const std::vector<double> own = copy.timeEvents(10.0);
  copy.setInputProfile(sim::inputIndex(copy, port), control::Profile::step(0.0, 0.1, 0.137));
  const std::vector<double> events = copy.timeEvents(10.0);
  EXPECT_NE(std::find(events.begin(), events.end(), 0.137), events.end()) << copy.name() << ", port " << port;
  for (double e : own) EXPECT_NE(std::find(events.begin(), events.end(), e), events.end()) << copy.name();
}

}  // namespace

// Every model with input profiles makes their breakpoints time events (the clamped robot did not: a load-torque step
// there was crossed by an integrator step).
TEST(ModelPorts, EveryModelMakesItsInputProfilesBreakpointsTimeEvents) {
  expectAProfilesStepIsATimeEvent<systems::DriveChain>(load("msl_friction.yaml", {})->plant(), "inertia2.load_torque");
  expectAProfilesStepIsATimeEvent<systems::PassiveRobot>(load("ur5_fall.yaml", {})->plant(), "elbow_joint.torque");
  expectAProfilesStepIsATimeEvent<systems::ClampedRobot>(load("irb140_clamping.yaml", {"curves=false"})->plant(),
                                                         "joint2.load_torque");
  expectAProfilesStepIsATimeEvent<systems::RobotR3Full>(load("robotr3_one_axis.yaml", {})->plant(), "axis.load_torque");
  expectAProfilesStepIsATimeEvent<systems::RobotR3Full>(load("robotr3_full_robot.yaml", {})->plant(), "r3.load_torque");
}

TEST(ModelPorts, DriveChainSourceAndLoadTorquesAgainstTheClosedForm) {
  const systems::DriveChain chain(oneInertia());
  const auto ports = chain.inputPorts();
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].name, "motor");
  EXPECT_EQ(ports[1].name, "shaft.load_torque");
  sim::Simulator s(chain, tight());
  EXPECT_FALSE(chain.inputActive(s.plantState(), 0));  // the profile drives until the port is set
  s.advanceTo(1.0);                                    // ω = 1 N·m · 1 s / 2 kg·m²
  EXPECT_NEAR(s.signal("shaft.w"), 0.5, 1e-9);
  chain.setInput(s.plantState(), sim::inputIndex(chain, "motor"), 4.0);
  chain.setInput(s.plantState(), sim::inputIndex(chain, "shaft.load_torque"), -1.0);
  EXPECT_TRUE(chain.inputActive(s.plantState(), 0));
  const std::string saved = s.saveState();
  s.advanceTo(2.0);  // ω = 0.5 + (4 − 1)·1/2
  EXPECT_NEAR(s.signal("shaft.w"), 2.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.signal("motor.tau"), 4.0);
  // A saved state carries the inputs: a fresh simulator restored from it continues the same way.
  sim::Simulator r(chain, tight());
  r.loadState(saved);
  EXPECT_DOUBLE_EQ(chain.input(r.plantState(), 0), 4.0);
  r.advanceTo(2.0);
  EXPECT_NEAR(r.signal("shaft.w"), 2.0, 1e-9);
  chain.releaseInput(s.plantState(), 0);  // back to the profile's 1 N·m, the load still −1 N·m
  EXPECT_FALSE(chain.inputActive(s.plantState(), 0));
  s.advanceTo(3.0);
  EXPECT_NEAR(s.signal("shaft.w"), 2.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.signal("motor.tau"), 1.0);
  EXPECT_THROW(chain.setInput(s.plantState(), 0, NAN), InputError);
  EXPECT_THROW(chain.setInput(s.plantState(), 2, 1.0), InputError);
}

TEST(ModelPorts, PassiveRobotHeldByItsGravityTorquesStaysAtRest) {
  // The UR5 at a bent pose held by τ = g(q) from RNEA (an algorithm apart from the ABA the plant integrates).
  auto exp = load("ur5_fall.yaml", {"duration=0.5", "initial_state.qd[0]=0"});
  sim::Simulator s(exp->plant(), exp->simulateOptions().solver);
  const auto& robot = dynamic_cast<const systems::PassiveRobot&>(exp->plant());
  const multibody::Model& model = robot.model();
  multibody::Data data(model);
  const Eigen::VectorXd q0 = s.state().head(model.nq);
  const Eigen::VectorXd g = multibody::gravityTorques(model, data, q0);
  ASSERT_GT(g.norm(), 1.0);
  for (int i = 0; i < model.nq; ++i)
    robot.setInput(s.plantState(), sim::inputIndex(robot, model.joint_names[static_cast<size_t>(i)] + ".torque"), g[i]);
  s.advanceTo(0.5);
  EXPECT_LT((s.state().head(model.nq) - q0).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(s.state().tail(model.nq).cwiseAbs().maxCoeff(), 1e-8);
  // Without them it falls.
  sim::Simulator f(exp->plant(), exp->simulateOptions().solver);
  f.advanceTo(0.5);
  EXPECT_GT((f.state().head(model.nq) - q0).cwiseAbs().maxCoeff(), 0.01);
}

TEST(ModelPorts, ClampedRobotMotorTorqueReplacesTheControllerWhichFreezes) {
  auto exp = load("irb140_clamping.yaml", {"duration=0.4", "curves=false"});
  const sim::Plant& plant = exp->plant();
  sim::Simulator s(plant, exp->simulateOptions().solver);
  s.advanceTo(0.1);
  const int port = sim::inputIndex(plant, "joint2.motor_torque");
  EXPECT_FALSE(plant.inputActive(s.plantState(), port));
  plant.setInput(s.plantState(), port, 0.25);
  EXPECT_TRUE(plant.inputActive(s.plantState(), port));
  s.advanceTo(0.2);
  EXPECT_DOUBLE_EQ(s.signal("joint2.motor_torque"), 0.25);
  const Eigen::VectorXd y1 = s.state();
  s.advanceTo(0.4);
  // The controller's integrator is the last state of the axis (φ_m, ω_m, x): constant while the port holds.
  const Eigen::Index x = plant.stateSize() - 3 * 6 + 3 * 1 + 2;  // axis 2 of 6
  EXPECT_EQ(s.state()[x], y1[x]);
  EXPECT_DOUBLE_EQ(s.signal("joint2.motor_torque"), 0.25);
}

TEST(ModelPorts, RobotR3CurrentReferencesAreTrackedAndLoadTorquesAct) {
  // FullRobot: a held current reference replaces the controller's; the op-amp current loop follows it.
  auto full = load("robotr3_full_robot.yaml", {"stop_time=0.3"});
  const sim::Plant& plant = full->plant();
  sim::Simulator s(plant, full->simulateOptions().solver);
  plant.setInput(s.plantState(), sim::inputIndex(plant, plant.inputPorts()[2].name), 1.5);  // axis 2 current
  s.advanceTo(0.1);
  const double pi_x = s.signal("axis2.controller.PI.x");
  s.advanceTo(0.3);
  EXPECT_EQ(s.signal("axis2.controller.PI.x"), pi_x) << "the PI integrator is frozen while the current is held";
  // The op-amp PI current loop follows the held reference up to the lag of a ramp (the back-EMF of the
  // accelerating motor): within 0.5 %.
  EXPECT_NEAR(s.signal("axis2.motor.La.i"), 1.5, 5e-3 * 1.5);
  // One axis: a load torque on the load inertia at rest with the current held at 0: J_L q̈ = τ_L − N τ_s; after the
  // gear spring settles the whole axis turns, so at the start (spring still relaxed) q̈ = τ_L / J_L exactly.
  auto axis = load("robotr3_one_axis.yaml", {});
  const sim::Plant& a = axis->plant();
  sim::Simulator sa(a, axis->simulateOptions().solver);
  a.setInput(sa.plantState(), sim::inputIndex(a, "axis.current"), 0.0);
  a.setInput(sa.plantState(), sim::inputIndex(a, "axis.load_torque"), 2.0);
  Eigen::VectorXd ydot(a.stateSize());
  a.derivatives(sa.plantState(), 0.0, sa.state(), ydot);
  Eigen::VectorXd ydot0(a.stateSize());
  a.setInput(sa.plantState(), sim::inputIndex(a, "axis.load_torque"), 0.0);
  a.derivatives(sa.plantState(), 0.0, sa.state(), ydot0);
  const double J_L = 19.5;  // robotr3_one_axis.yaml load.inertia [kg·m²]
  EXPECT_NEAR(ydot[1] - ydot0[1], 2.0 / J_L, 1e-12);
  EXPECT_EQ(ydot[4], 0.0) << "the PI integrator is frozen while the current is held";
}

}  // namespace jointsim
