// The constant model and the run's state: a plant is only read during a run, every simulator owns its state, and a
// snapshot of that state (in memory or as bytes) continues bit for bit as the original. Checked on the UR5 twin with
// 20 kHz sampled control and noisy, quantised sensors, the plant with the most run-time state (controller
// integrators, held outputs, encoder memory, the noise generator).
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

/// The UR5 excitation with sampled control at 20 kHz and noisy, quantised sensors on every drive, from copies of its
/// files in `dir`.
std::shared_ptr<experiments::Experiment> noisyTwin(const test::TempDir& dir, double duration) {
  std::string drives = test::readText(test::sourcePath("config/robots/ur5_drives.yaml"));
  drives.replace(drives.find("multibody: ur5.yaml"), 19, "multibody: " + test::sourcePath("config/robots/ur5.yaml"));
  for (size_t at = drives.find("    controller:"); at != std::string::npos;
       at = drives.find("    controller:", at + 200))
    drives.insert(at, "    sensors: {motor_quantum: 4.79e-5, joint_quantum: 3.83e-4, joint_noise: 2e-5, "
                      "current_noise: 0.01, current_quantum: 0.001}\n");
  std::ofstream(dir.path() / "drives.yaml") << drives;
  std::string exp = test::readText(test::sourcePath("config/experiments/ur5_excitation.yaml"));
  exp.replace(exp.find("robot: ../robots/ur5_drives.yaml"), 32, "robot: drives.yaml\ncontrol: {rate: 20000, seed: 7}");
  std::ofstream(dir.path() / "exp.yaml") << exp;
  return experiments::loadExperiment((dir.path() / "exp.yaml").string(),
                                     {"duration=" + std::to_string(duration), "solver.rtol=1e-4"});
}

/// Every entry equal, bit for bit (EXPECT_EQ on doubles), naming the first that differs.
void expectIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::string& what);

/// `run(arg_a)` and `run(arg_b)` one after the other, then at once in two threads: each thread's result equals its
/// sequential twin bit for bit. Returns the sequential results.
template <class Run, class Arg>
std::pair<Eigen::VectorXd, Eigen::VectorXd> expectThreadsAsSequential(const Run& run, Arg arg_a, Arg arg_b) {
  const Eigen::VectorXd a = run(arg_a), b = run(arg_b);
  Eigen::VectorXd pa, pb;
  std::thread ta([&] { pa = run(arg_a); });
  std::thread tb([&] { pb = run(arg_b); });
  ta.join();
  tb.join();
  expectIdentical(pa, a, "thread A");
  expectIdentical(pb, b, "thread B");
  return {a, b};
}

/// Every entry equal, bit for bit (EXPECT_EQ on doubles), naming the first that differs.
void expectIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (Eigen::Index i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << what << ": entry " << i;
}

TEST(PlantState, SnapshotAtHalfASecondContinuesBitForBitOnTheNoisySampledTwin) {
  const test::TempDir dir;
  const auto e = noisyTwin(dir, 1.0);
  const auto sim = experiments::makeSimulator(e);
  sim->advanceTo(0.5);
  const sim::Snapshot snap = sim->snapshot();
  const std::string bytes = sim->saveState();
  EXPECT_EQ(snap.time(), 0.5);
  sim->advanceTo(0.6);
  const Eigen::VectorXd y_06 = sim->state();
  sim->advanceTo(1.0);
  const Eigen::VectorXd y_end = sim->state(), s_end = sim->signals();

  // Restored in memory: the same continuation.
  sim->restore(snap);
  EXPECT_EQ(sim->time(), 0.5);
  sim->advanceTo(0.6);
  sim->advanceTo(1.0);
  expectIdentical(sim->state(), y_end, "restored in memory: state at 1 s");
  expectIdentical(sim->signals(), s_end, "restored in memory: signals at 1 s");

  // From bytes into a second simulator of the same experiment, and into one of the experiment loaded again (another
  // plant object of the same configuration, as in another process).
  const auto other = experiments::makeSimulator(e);
  other->loadState(bytes);
  other->advanceTo(0.6);
  expectIdentical(other->state(), y_06, "loaded from bytes: state at 0.6 s");
  const test::TempDir dir2;
  const auto again = experiments::makeSimulator(noisyTwin(dir2, 1.0));
  again->loadState(bytes);
  again->advanceTo(0.6);
  expectIdentical(again->state(), y_06, "another plant object of the same files: state at 0.6 s");

  // A copy continues alike and is independent: its inputs do not reach the original.
  sim->restore(snap);
  sim::Simulator copy(*sim);
  sim::Simulator twin(*sim);
  const auto& robot = dynamic_cast<const systems::RobotSystem&>(copy.plant());
  robot.setCommandPort(copy.plantState(), 2, systems::CommandPort::Voltage);
  robot.setCommand(copy.plantState(), 2, 5.0);
  copy.advanceTo(0.6);
  twin.advanceTo(0.6);
  sim->advanceTo(0.6);
  expectIdentical(sim->state(), y_06, "the original beside a changed copy");
  expectIdentical(twin.state(), y_06, "an unchanged copy");
  EXPECT_DOUBLE_EQ(copy.signal("voltage_elbow_joint"), 5.0);  // the copy runs its own input
  EXPECT_GT(std::abs(copy.state()[2] - y_06[2]), 1e-6);
  EXPECT_EQ(robot.commandPort(sim->plantState(), 2), systems::CommandPort::Setpoint);
}

TEST(PlantState, TwoSimulatorsOfOneExperimentInTwoThreadsEqualTheSequentialRuns) {
  const test::TempDir dir;
  const auto e = noisyTwin(dir, 0.2);
  auto runOne = [&e](double voltage) {
    const auto s = experiments::makeSimulator(e);
    if (voltage != 0.0) {
      const auto& robot = dynamic_cast<const systems::RobotSystem&>(s->plant());
      robot.setCommandPort(s->plantState(), 1, systems::CommandPort::Voltage);
      robot.setCommand(s->plantState(), 1, voltage);
    }
    for (int k = 0; k < 100; ++k) s->advance(1e-3);
    return Eigen::VectorXd(s->state());
  };
  const auto [a, b] = expectThreadsAsSequential(runOne, 0.0, 2.0);
  EXPECT_NE(a, b) << "the two runs differ (the voltage port of one did not reach the other)";
  // The experiment's own run is untouched by the simulators' inputs.
  const experiments::ExperimentResult r1 = experiments::runInMemory(*e);
  runOne(2.0);
  const experiments::ExperimentResult r2 = experiments::runInMemory(*e);
  ASSERT_EQ(r1.log.values.rows(), r2.log.values.rows());
  EXPECT_EQ(r1.log.values, r2.log.values);
}

TEST(PlantState, OneConstantModelWithTwoStatesInTwoThreadsEvaluatesAsSequentially) {
  const test::TempDir dir;
  const auto e = noisyTwin(dir, 0.2);
  const sim::Plant& plant = e->plant();
  const Eigen::VectorXd y0 = plant.initialState();
  // Points along a perturbed state, evaluated with the state's samples in between (noise, held outputs).
  auto evaluate = [&](unsigned salt) {
    const auto state = plant.makeState();
    plant.start(*state, 0.0, y0);
    Eigen::VectorXd y = y0, yd(y0.size()), out(static_cast<Eigen::Index>(plant.signalNames().size()));
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(y0.size());
    for (int k = 0; k < 400; ++k) {
      const double t = 5e-5 * k;
      y[0] = y0[0] + 1e-3 * std::sin(0.1 * k + salt);
      plant.sample(*state, t, y);
      plant.derivatives(*state, t, y, yd);
      plant.signals(*state, t, y, out);
      sum += yd;
      sum[0] += out.sum();
    }
    return sum;
  };
  expectThreadsAsSequential(evaluate, 1U, 2U);
}

TEST(PlantState, ResetStartsAFreshRunAndBadSnapshotsAreRefused) {
  const test::TempDir dir;
  const auto e = noisyTwin(dir, 0.2);
  const auto s = experiments::makeSimulator(e);
  const auto& robot = dynamic_cast<const systems::RobotSystem&>(s->plant());
  for (int k = 0; k < 30; ++k) s->advance(1e-3);
  const Eigen::VectorXd y30 = s->state();
  robot.setCommandPort(s->plantState(), 0, systems::CommandPort::Voltage);
  robot.setCommand(s->plantState(), 0, -3.0);
  s->advance(0.01);
  // reset(): the inputs cleared, controllers, sensors and the noise generator as at the start.
  s->reset();
  EXPECT_EQ(robot.commandPort(s->plantState(), 0), systems::CommandPort::Setpoint);
  for (int k = 0; k < 30; ++k) s->advance(1e-3);
  expectIdentical(s->state(), y30, "after reset()");

  // Bytes that do not fit are refused and leave the simulator as it was.
  const std::string good = s->saveState();
  const double t = s->time();
  const Eigen::VectorXd y = s->state();
  for (const std::string& bad : {std::string(), good.substr(0, good.size() / 2), good + "x", std::string(100, 'j')})
    EXPECT_THROW(s->loadState(bad), InputError);
  std::string other_plant = good;
  other_plant[other_plant.find("robot with drives") + 2] = 'X';
  EXPECT_THROW(s->loadState(other_plant), InputError);
  EXPECT_EQ(s->time(), t);
  expectIdentical(s->state(), y, "after refused loads");
  // A state of another plant object is refused where it is used.
  const test::TempDir dir2;
  const auto e2 = noisyTwin(dir2, 0.2);
  const auto foreign = e2->plant().makeState();
  Eigen::VectorXd yd(y.size());
  EXPECT_THROW(e->plant().derivatives(*foreign, 0.0, y, yd), InputError);
  sim::Simulator s2(e2->plant());
  EXPECT_THROW(s->restore(s2.snapshot()), InputError);
}

}  // namespace
}  // namespace jointsim

namespace jointsim {
namespace {

/// `bytes` with the first occurrence of `from` replaced by `to` (both the same length); fails the test if absent.
std::string replaced(std::string bytes, const std::string& from, const std::string& to) {
  const size_t at = bytes.find(from);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) bytes.replace(at, from.size(), to);
  return bytes;
}

std::string u64(std::uint64_t v) {
  ByteWriter w;
  w.u64(v);
  return w.bytes();
}

std::string f64(double v) {
  ByteWriter w;
  w.f64(v);
  return w.bytes();
}

static_assert(!std::is_constructible_v<sim::Simulator, systems::RobotSystem&&>,
              "a simulator of a temporary plant would outlive it");
static_assert(!std::is_constructible_v<sim::Simulator, const sim::Simulator&>,
              "copying a simulator takes a snapshot of it: not of a const one");

TEST(PlantState, SavedStatesThatTheSettersWouldRefuseAreRefused) {
  const auto e = std::shared_ptr<experiments::Experiment>(
      experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"), {"duration=0.1"}));
  const auto s = experiments::makeSimulator(e);
  const auto& robot = dynamic_cast<const systems::RobotSystem&>(s->plant());
  const int tip = robot.model().frameIndex(robot.model().tip_frame);
  Eigen::Matrix<double, 6, 1> w;
  w << 1.25, -2.5, 3.75, 0.0, 0.0, 0.0;
  robot.setExternalWrench(s->plantState(), robot.model().tip_frame, w);
  s->advance(2e-3);
  const std::string good = s->saveState();
  const double t = s->time();
  const Eigen::VectorXd y = s->state();
  // A wrench on the base frame (which setExternalWrench refuses: nothing moves it).
  const std::string wrench = u64(1) + u64(static_cast<std::uint64_t>(tip)) + u64(6) + f64(1.25);
  EXPECT_THROW(s->loadState(replaced(good, wrench, u64(1) + u64(0) + u64(6) + f64(1.25))), InputError);
  // A non-finite wrench.
  EXPECT_THROW(s->loadState(replaced(good, f64(1.25), f64(std::nan("")))), InputError);
  // A time far beyond the simulator's range (the sample and event arithmetic would lose its resolution).
  EXPECT_THROW(s->loadState(replaced(good, f64(t), f64(1e20))), InputError);
  EXPECT_EQ(s->time(), t);
  expectIdentical(s->state(), y, "after refused loads");
  s->loadState(good);  // the good bytes still load
  EXPECT_THROW(s->reset(1e20, y), InputError);

  // The robot is in use by a simulator: its configuration is fixed.
  EXPECT_TRUE(robot.frozen());
  auto& mutable_robot = const_cast<systems::RobotSystem&>(robot);  // as a user holding the robot itself could
  EXPECT_THROW(mutable_robot.setSampledControl(20000.0, 1), InputError);
  EXPECT_THROW(mutable_robot.setFaults({}), InputError);
  EXPECT_THROW(mutable_robot.setJointLimits(systems::JointLimitSettings{}), InputError);
  // A copy of the robot is another plant: configurable, and a state of one is refused by the other.
  systems::RobotSystem copy = robot;
  EXPECT_FALSE(copy.frozen());
  EXPECT_NE(copy.id(), robot.id());
  EXPECT_NO_THROW(copy.setSampledControl(20000.0, 1));
  Eigen::VectorXd yd(copy.stateSize());
  EXPECT_THROW(copy.derivatives(s->plantState(), 0.0, copy.initialState(), yd), InputError);
}

}  // namespace
}  // namespace jointsim
