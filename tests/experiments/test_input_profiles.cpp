// Input profiles from the experiment file (`inputs: {PORT: PROFILE}`, common to every type whose model has input
// ports): a load-torque step on a drive chain against the closed form, a current reference profile on the RobotR3
// axis in place of its controller, a value set at the port overriding the profile, and the errors.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/sim/simulator.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {
// A shaft of 2 kg·m² driven by 10 N·m, with a load torque of −4 N·m from t = 0.5 s (from the file).
const char* kChain = R"(experiment: {name: chain, type: drive_chain}
inertias: [{name: shaft, J: 2.0}]
elements:
  - {name: motor, type: torque, on: shaft, profile: {type: constant, value: 10}}
inputs:
  shaft.load_torque: {type: step, initial: 0, final: -4, time: 0.5}
duration: 1.0
log_rate: 100
)";
}  // namespace

// ω = 5 t up to 0.5 s, then 2.5 + 3 (t − 0.5); a value set at the port holds it instead of the profile. The tolerance
// after the step is that of every time event of the engine: the implicit step that lands on the event evaluates the
// right-hand side at the event time itself, where the profile already has its new value (an error of the jump times
// that last step, 1.3e-5 rad/s here, as for the drive chain's own source profiles).
TEST(InputProfiles, LoadTorqueStepOnADriveChainAgainstTheClosedForm) {
  const test::TempDir dir;
  const std::string path = (dir / "chain.yaml").string();
  std::ofstream(path) << kChain;
  auto e = experiments::loadExperiment(path);
  const auto r = experiments::runInMemory(*e);
  const Eigen::VectorXd t = r.log["time"], w = r.log["shaft.w"];
  for (Eigen::Index k = 0; k < t.size(); ++k)
    ASSERT_NEAR(w[k], t[k] <= 0.5 ? 5 * t[k] : 2.5 + 3 * (t[k] - 0.5), t[k] < 0.5 ? 1e-9 : 1e-4) << "t = " << t[k];
  std::shared_ptr<experiments::Experiment> shared(std::move(e));
  auto s = experiments::makeSimulator(shared);
  const int port = sim::inputIndex(s->plant(), "shaft.load_torque");
  s->plant().setInput(s->plantState(), port, 0.0);  // held at 0: no load step
  s->advanceTo(1.0);
  EXPECT_NEAR(s->signal("shaft.w"), 5.0, 1e-6);
}

// The RobotR3 axis's current reference from a sine profile: the logged reference is the profile at every row, the
// PI integrator stays at its start value.
TEST(InputProfiles, CurrentReferenceProfileReplacesTheRobotR3AxisController) {
  const test::TempDir dir;
  const std::string path = (dir / "axis.yaml").string();
  std::ifstream in(test::sourcePath("config/experiments/robotr3_one_axis.yaml"));
  std::ofstream(path) << in.rdbuf() << "inputs:\n  axis.current: {type: sine, amplitude: 2, frequency: 5}\n";
  auto e = experiments::loadExperiment(path, {"stop_time=0.3"});
  const auto r = experiments::runInMemory(*e);
  const Eigen::VectorXd t = r.log["time"], iref = r.log["axis.motor.i_ref"], x = r.log["axis.controller.PI.x"];
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    ASSERT_NEAR(iref[k], 2 * std::sin(2 * M_PI * 5 * t[k]), 1e-12) << "t = " << t[k];
    ASSERT_EQ(x[k], x[0]) << "t = " << t[k];
  }
}

TEST(InputProfiles, AnUnknownPortOrAModelWithoutProfilesIsAnErrorAtItsLine) {
  const test::TempDir dir;
  const std::string path = (dir / "chain.yaml").string();
  std::string text = kChain;
  text.replace(text.find("shaft.load_torque"), 17, "shaft.load");
  std::ofstream(path) << text;
  try {
    experiments::loadExperiment(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chain.yaml:6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("shaft.load_torque"), std::string::npos) << e.what();  // lists the inputs
  }
}
