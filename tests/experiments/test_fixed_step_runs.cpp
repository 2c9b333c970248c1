// The fixed-step method (solver: {method: rosenbrock}) on the UR5 twin under 20 kHz sampled control, against CVODE at
// rtol 1e-9 (the validation protocol's deterministic, noise-free case, docs/design.md "Fixed-step integration"), and
// the experiment file's checks of its keys.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

using ::testing::HasSubstr;

// The first 0.78 s of config/experiments/ur5_excitation.yaml (continuous control) with the overrides `sets`.
experiments::ExperimentResult runExcitation(const std::vector<std::string>& sets) {
  std::vector<std::string> all = {"duration=0.78"};
  all.insert(all.end(), sets.begin(), sets.end());
  auto e = experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"), all);
  return experiments::runInMemory(*e);
}

// The same with 20 kHz sampled control.
experiments::ExperimentResult runTwin(const std::vector<std::string>& solver) {
  std::vector<std::string> sets = {"+control.rate=20000"};
  sets.insert(sets.end(), solver.begin(), solver.end());
  return runExcitation(sets);
}

// Largest |a − b| over the columns starting with `prefix` (not q_set/q_fb/current_ref), absolute or relative to
// each column's range in `a`.
double worst(const sim::SignalTable& a, const sim::SignalTable& b, const std::string& prefix, bool relative) {
  double w = 0.0;
  for (size_t j = 0; j < a.columns.size(); ++j) {
    const std::string& c = a.columns[j];
    if (c.rfind(prefix, 0) != 0 || c.rfind("q_set", 0) == 0 || c.rfind("q_fb", 0) == 0 ||
        c.rfind("current_ref", 0) == 0)
      continue;
    const Eigen::VectorXd x = a.values.col(static_cast<Eigen::Index>(j)), y = b[c];
    const double range = relative ? x.maxCoeff() - x.minCoeff() : 1.0;
    w = std::max(w, (x - y).cwiseAbs().maxCoeff() / range);
  }
  return w;
}

// 0.78 s of the excitation with a velocity reversal of the wrist joints (at 0.756 s), where the LuGre bristles
// (σ₀ = 5e6 N·m/rad) stick: the stiffest moment of the run.
TEST(FixedStepTwin, TwoStepsPerControlPeriodMeetTheAccuracyOfTheValidationProtocol) {
  const auto ref = runTwin({"solver.rtol=1e-9", "solver.atol=1e-11"});
  const auto fixed = runTwin({"solver.method=rosenbrock", "+solver.step=2.5e-5"});
  ASSERT_EQ(ref.log.values.rows(), fixed.log.values.rows());
  EXPECT_EQ(fixed.result.stats.steps, 31200);  // 0.78 s / 25 µs: locked to the clock, no extra step
  EXPECT_EQ(fixed.result.stats.error_test_failures, 0);
  // Measured: 2.9e-6 rad, 1.04 % and 1.64 % of the ranges (the protocol asks 1e-4 rad, 2 % and 3 %); with one step per
  // period (solver.step 5e-5 s) 9.0e-6 rad, 3.2 % and 5.1 %, which fails here: the bristles' stick transient is
  // damped by the L-stable step rather than followed.
  EXPECT_LT(worst(ref.log, fixed.log, "q_", false), 1e-4);
  EXPECT_LT(worst(ref.log, fixed.log, "current_", true), 0.02);
  EXPECT_LT(worst(ref.log, fixed.log, "gear_torque_", true), 0.03);
  // One step per period with the adaptive Jacobian (jacobian_every: adaptive, θ = 0.2, the oscillations damped):
  // measured 4.7e-6 rad, 1.67 % and 2.66 %, within the protocol — a Jacobian kept from before the wrists' stick phase
  // damps the bristles' transient less than a fresh one at every step (3.2 %, 5.1 % above). Not a margin to build on:
  // θ = 0.05 gave 2.2 % and 3.4 %, θ = 0.5 2.4 % and 3.9 % (docs/design.md, "Jacobian reuse").
  const auto adaptive = runTwin({"solver.method=rosenbrock", "+solver.jacobian_every=adaptive"});
  ASSERT_EQ(ref.log.values.rows(), adaptive.log.values.rows());
  EXPECT_EQ(adaptive.result.stats.steps, 15600);
  EXPECT_LT(adaptive.result.stats.jac_evals, 15600 / 20);
  EXPECT_LT(worst(ref.log, adaptive.log, "q_", false), 1e-4);
  EXPECT_LT(worst(ref.log, adaptive.log, "current_", true), 0.02);
  EXPECT_LT(worst(ref.log, adaptive.log, "gear_torque_", true), 0.03);
  // The shipped realtime file's solver: the drive trains' oscillatory rows with γ = 1 − 1/√2 (resolved rather than
  // damped) and the adaptive Jacobian's tighter defect 0.02. Measured 3.79e-6 rad, 1.37 % and 2.15 %.
  const auto resolved =
      runTwin({"solver.method=rosenbrock", "+solver.jacobian_every=adaptive", "+solver.oscillations=resolve"});
  ASSERT_EQ(ref.log.values.rows(), resolved.log.values.rows());
  EXPECT_EQ(resolved.result.stats.steps, 15600);
  EXPECT_LT(resolved.result.stats.jac_evals, 15600 / 5);
  EXPECT_LT(worst(ref.log, resolved.log, "q_", false), 1e-4);
  EXPECT_LT(worst(ref.log, resolved.log, "current_", true), 0.02);
  EXPECT_LT(worst(ref.log, resolved.log, "gear_torque_", true), 0.03);
}

// Continuous control (the cascade's PWM saturation and the LuGre break-aways inside the step) at 100 µs and 250 µs:
// before the fixed-step method shortened the steps whose linearisation has a growing mode it cannot follow
// (det(I − γhW) < 0, FixedStepIntegrator::step), the wrist joints' LuGre negative damping at the reversal was damped
// away and wrist_3 ended 0.17 rad off with no error. Now the first step that sees the mode is shortened, the full step
// before it (which ran into the mode unseen) is retaken with the shorter steps, and the steps grow back over a few
// µs: the angles follow the reference. What remains (docs/design.md): at the wrist_3 reversal the joint slips where
// the reference sticks for a few ms, and its current is off for those samples (measured 41 % of its range at 100 µs,
// 95 % at 250 µs; 3 % at 50 µs) — continuous current loops want steps ≤ 50 µs. At 500 µs the run stops.
TEST(FixedStepTwin, AStepTooLongForAGrowingModeIsShortenedAndRetakenOrTheRunStops) {
  const auto ref = runExcitation({"solver.rtol=1e-9", "solver.atol=1e-11"});
  for (const char* step : {"+solver.step=1e-4", "+solver.step=2.5e-4"}) {
    const auto fixed = runExcitation({"solver.method=rosenbrock", step});
    ASSERT_EQ(ref.log.values.rows(), fixed.log.values.rows());
    EXPECT_GT(fixed.result.stats.split_steps, 0) << step;
    EXPECT_GT(fixed.result.stats.retaken_steps, 0) << step;
    // Measured: 1.2e-4 rad at both steps; unshortened 0.17 rad.
    EXPECT_LT(worst(ref.log, fixed.log, "q_", false), 3e-4) << step;
  }
  EXPECT_EQ(ref.result.stats.split_steps, 0);  // CVODE never splits
  try {
    runExcitation({"solver.method=rosenbrock", "+solver.step=5e-4"});
    FAIL() << "no error";
  } catch (const SolverError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the step is too large for the dynamics at t = 0.76"));
    EXPECT_THAT(e.what(), HasSubstr("wrist"));
    EXPECT_THAT(e.what(), HasSubstr("smaller solver.step, or BDF"));
    EXPECT_EQ(e.flag(), "STEP_UNSTABLE");
  }
}

// config/experiments/ur5_excitation_realtime.yaml: the excitation's trajectory, 20 kHz sampled control, the drives'
// sensors from its drives: key, the fixed-step method; solver.method=bdf turns it into a CVODE run.
TEST(FixedStepTwin, TheShippedRealtimeFileIsTheExcitationWithSensorsAndTheFixedStep) {
  const std::string file = test::sourcePath("config/experiments/ur5_excitation_realtime.yaml");
  auto run = [&](std::vector<std::string> sets) {
    sets.push_back("duration=0.02");
    auto e = experiments::loadExperiment(file, sets);
    return experiments::runInMemory(*e);
  };
  const auto fixed = run({});
  EXPECT_EQ(fixed.result.stats.steps, 400);  // 0.02 s / 50 µs: one step per control period
  EXPECT_EQ(fixed.result.stats.last_order, 2);
  EXPECT_EQ(fixed.result.period_wall.periods, 398);  // 400 samples (0 … 19.95 ms): the first two start the clock
  const auto bdf = run({"solver.method=bdf"});
  EXPECT_GT(bdf.result.stats.error_test_failures, 0);  // CVODE (a fixed-step method has no error test)
  // The same trajectory as ur5_excitation.yaml: the set-points agree to the last bit.
  auto plain = experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"),
                                           {"duration=0.02", "+control.rate=20000"});
  const auto ref = experiments::runInMemory(*plain);
  for (const char* c : {"q_set_shoulder_pan_joint[rad]", "q_set_wrist_3_joint[rad]"})
    EXPECT_EQ(fixed.log[c], ref.log[c]) << c;
  // The sensors act: the measured joint angle lies on the 2^14 counts/rev grid, and the noise seed changes the run.
  const Eigen::VectorXd fb = fixed.log["q_fb_elbow_joint[rad]"];
  for (Eigen::Index i = 0; i < fb.size(); ++i) EXPECT_NEAR(std::remainder(fb[i], 3.83e-4), 0.0, 1e-12) << i;
  const auto other = run({"control.seed=2"});
  EXPECT_NE(fixed.log["current_elbow_joint[A]"], other.log["current_elbow_joint[A]"]);
  // Under sampled control the twin's right-hand side does not depend on t (RobotSystem::timeInvariant): no difference
  // in time per Jacobian (and the analytic Jacobian counts none of its own). A load-torque profile of time makes it
  // depend on t again: one right-hand side per Jacobian.
  EXPECT_EQ(fixed.result.stats.rhs_evals_jacobian, 0);
  // jacobian_every: adaptive: the Jacobian is renewed where the linearisation defect says it moved (measured 40 of the
  // 400 steps with the defect 0.02 of resolved oscillations, most of them in the first ms: the start's transient; 12
  // with 0.2); `jacobian_every=1` renews it at every step. A kept Jacobian keeps its factorisations: I − γhW and the
  // one with the oscillatory rows scaled (oscillations: resolve).
  EXPECT_GT(fixed.result.stats.jac_evals, 1);
  EXPECT_LT(fixed.result.stats.jac_evals, 100);
  EXPECT_EQ(fixed.result.stats.lin_setups, 2 * fixed.result.stats.jac_evals);
  const auto damped = run({"solver.oscillations=damp"});
  EXPECT_LT(damped.result.stats.jac_evals, 40);
  EXPECT_EQ(damped.result.stats.lin_setups, damped.result.stats.jac_evals);
  EXPECT_EQ(run({"solver.jacobian_every=1"}).result.stats.jac_evals, 400);
  const test::TempDir tmp;
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string robot = "robot: ../robots/ur5_drives.yaml";
  ASSERT_NE(text.find(robot), std::string::npos);
  text.replace(text.find(robot), robot.size(), "robot: " + test::sourcePath("config/robots/ur5_drives.yaml"));
  std::ofstream(tmp / "loaded.yaml")
      << text << "\ninputs:\n  elbow_joint.load_torque: {type: sine, amplitude: 2, frequency: 5}\n";
  const auto loaded =
      experiments::runInMemory(*experiments::loadExperiment((tmp / "loaded.yaml").string(), {"duration=0.02"}));
  EXPECT_EQ(loaded.result.stats.rhs_evals_jacobian, loaded.result.stats.jac_evals);
  EXPECT_GT(loaded.result.stats.jac_evals, 0);
}

// A drive's sensors are parameters like any other (driveParameterTable "sensors"): bad keys and values are refused
// naming the file, the key and the rule.
TEST(FixedStepTwin, SensorChangesAreCheckedLikeEveryDriveParameter) {
  const std::string file = test::sourcePath("config/experiments/ur5_excitation.yaml");
  try {
    experiments::loadExperiment(file, {"+drives.elbow_joint.sensors.current_noice=0.01"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("ur5_excitation.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("no parameter 'current_noice'"));
    EXPECT_THAT(e.what(), HasSubstr("current_noise"));
  }
  try {
    experiments::loadExperiment(file, {"+drives.elbow_joint.sensors.current_noise=-1"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("drives.elbow_joint.sensors.current_noise"));
    EXPECT_THAT(e.what(), HasSubstr("outside its range"));
  }
}

// jacobian_every: a number of steps or adaptive (θ = 0.2 unless jacobian_defect says otherwise); both keys are checked
// with every method and used by the fixed step only, so `--set solver.method=bdf` runs a fixed-step file with CVODE.
TEST(FixedStepTwin, TheJacobianPolicyKeysAreCheckedAndKeptUnusedByCvode) {
  const std::string file = test::sourcePath("config/experiments/ur5_excitation_realtime.yaml");
  auto solver = [&](std::vector<std::string> sets) {
    return experiments::loadExperiment(file, sets)->simulateOptions().solver;
  };
  // The shipped file resolves the drive trains' oscillations, whose adaptive Jacobian has the tighter defect.
  const sim::CvodeOptions shipped = solver({});
  EXPECT_EQ(shipped.method, sim::Method::Rosenbrock);
  EXPECT_TRUE(shipped.resolve_oscillations);
  EXPECT_EQ(shipped.jacobian_every, sim::kAdaptiveJacobianEvery);
  EXPECT_EQ(shipped.jacobian_defect, sim::kResolveJacobianDefect);
  EXPECT_EQ(solver({"+solver.jacobian_defect=0.05"}).jacobian_defect, 0.05);
  const sim::CvodeOptions damped = solver({"solver.oscillations=damp"});
  EXPECT_FALSE(damped.resolve_oscillations);
  EXPECT_EQ(damped.jacobian_every, sim::kAdaptiveJacobianEvery);
  EXPECT_EQ(damped.jacobian_defect, 0.2);
  const sim::CvodeOptions tighter = solver({"solver.oscillations=damp", "+solver.jacobian_defect=0.05"});
  EXPECT_EQ(tighter.jacobian_every, sim::kAdaptiveJacobianEvery);
  EXPECT_EQ(tighter.jacobian_defect, 0.05);
  const sim::CvodeOptions every = solver({"solver.oscillations=damp", "solver.jacobian_every=4"});
  EXPECT_EQ(every.jacobian_every, 4);
  EXPECT_EQ(every.jacobian_defect, 0.0);
  // jacobian_defect alone means adaptive (with a Jacobian per step it would never act); beside a number both apply.
  const sim::CvodeOptions alone =
      experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"),
                                  {"+control.rate=20000", "solver.method=rosenbrock", "+solver.jacobian_defect=0.3"})
          ->simulateOptions()
          .solver;
  EXPECT_EQ(alone.jacobian_every, sim::kAdaptiveJacobianEvery);
  EXPECT_EQ(alone.jacobian_defect, 0.3);
  EXPECT_FALSE(alone.resolve_oscillations);  // the default: damp
  const sim::CvodeOptions both =
      solver({"solver.oscillations=damp", "solver.jacobian_every=50", "+solver.jacobian_defect=0.3"});
  EXPECT_EQ(both.jacobian_every, 50);
  EXPECT_EQ(both.jacobian_defect, 0.3);
  const sim::CvodeOptions bdf = solver({"solver.method=bdf"});
  EXPECT_EQ(bdf.method, sim::Method::BDF);
  EXPECT_TRUE(bdf.resolve_oscillations);  // checked and kept, unused by CVODE
  for (const auto& [set, key, expected] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"solver.jacobian_every=sometimes", "solver.jacobian_every", "a number of steps from 1 to 1e6, or adaptive"},
           {"solver.jacobian_every=0", "solver.jacobian_every", "a number of steps from 1 to 1e6, or adaptive"},
           {"+solver.jacobian_defect=0", "solver.jacobian_defect", "a relative linearisation defect > 0"},
           {"+solver.jacobian_defect=-1", "solver.jacobian_defect", "a relative linearisation defect > 0"},
           {"solver.oscillations=sometimes", "solver.oscillations", "resolve"},
           {"+solver.jacobian_defect=0.3", "solver.jacobian_defect", "at most 0.05 with oscillations: resolve"},
           {"solver.jacobian_every=4", "solver.jacobian_every", "1 or adaptive with oscillations: resolve"}}) {
    try {
      solver({set});
      FAIL() << "no error for " << set;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("ur5_excitation_realtime.yaml")) << set;
      EXPECT_THAT(e.what(), HasSubstr(key)) << set;
      EXPECT_THAT(e.what(), HasSubstr(expected)) << set;
    }
  }
}

TEST(FixedStepTwin, TheFilesStepIsCheckedAgainstTheControlPeriod) {
  const std::string file = test::sourcePath("config/experiments/ur5_excitation.yaml");
  try {
    experiments::loadExperiment(file, {"+control.rate=20000", "solver.method=rosenbrock", "+solver.step=3e-5"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("ur5_excitation.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("solver.step"));
    EXPECT_THAT(e.what(), HasSubstr("integer fraction"));
  }
  // Continuous control has no period to take the step from.
  try {
    experiments::loadExperiment(file, {"solver.method=rosenbrock"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("solver.method"));
    EXPECT_THAT(e.what(), HasSubstr("solver.step [s]"));
  }
  // With CVODE a step is checked and kept but unused (a fixed-step file runs with `--set solver.method=bdf`).
  EXPECT_EQ(experiments::loadExperiment(file, {"+solver.step=1e-5"})->simulateOptions().solver.method,
            sim::Method::BDF);
  EXPECT_THROW(experiments::loadExperiment(file, {"+solver.step=-1e-5"}), InputError);
  EXPECT_THROW(experiments::loadExperiment(file, {"solver.method=rk4"}), InputError);
  // With an explicit step a continuous plant runs with it.
  auto e = experiments::loadExperiment(file, {"solver.method=rosenbrock", "+solver.step=1e-4", "duration=0.01"});
  EXPECT_EQ(experiments::runInMemory(*e).result.stats.steps, 100);
}

}  // namespace
}  // namespace jointsim
