// A joint rig whose load torque comes from its experiment file: a motor start-up against a load step, against the
// closed form of the first-order speed response.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {
// Motor torque 2 N·m from t = 0 through a rigid gear N = 10 into a load of J_l = 0.5 kg·m² with viscous damping
// b_l = 0.2 N·m·s/rad; J_m = 1e-3 kg·m². A load torque step of −15 N·m on the output at t = 1 s.
const char* kRig = R"(experiment: {name: start_up, type: joint_rig}
rotor_inertia: 1.0e-3
transmission: {type: rigid, ratio: 10}
load:
  inertia: 0.5
  damping: 0.2
  torque: {type: step, initial: 0, final: -15, time: 1.0}
input:
  type: torque
  profile: {type: constant, value: 2.0}
duration: 3.0
log_rate: 100
solver: {rtol: 1.0e-10, atol: 1.0e-12}
)";
}  // namespace

// On the motor shaft: J_eff ω̇ = τ_M + (τ_L(t) − b_l ω/N)/N with J_eff = J_m + J_l/N² (= 6e-3 kg·m²), i.e.
// ω̇ = (ω∞ − ω)/T, T = J_eff N²/b_l = 3 s, ω∞ = N(N τ_M + τ_L)/b_l: 1000 rad/s before the step, 250 after it.
TEST(JointRigLoadTorque, StartUpAgainstALoadStepFromTheFileMatchesTheClosedForm) {
  const test::TempDir dir;
  const std::string path = (dir / "start_up.yaml").string();
  std::ofstream(path) << kRig;
  auto experiment = experiments::loadExperiment(path);
  const auto result = experiments::runInMemory(*experiment);
  const auto& log = result.log;
  const int w = log.column("motor_velocity[rad/s]"), load = log.column("load_torque[N·m]");
  const double T = 3.0, N = 10.0;
  const double w1 = 1000.0 * (1 - std::exp(-1.0 / T));  // at the step
  for (Eigen::Index r = 0; r < log.values.rows(); ++r) {
    const double t = log.values(r, 0);
    const double expected = t <= 1.0 ? 1000.0 * (1 - std::exp(-t / T)) : 250.0 + (w1 - 250.0) * std::exp(-(t - 1) / T);
    ASSERT_NEAR(log.values(r, w), expected, 1e-6 * 1000.0) << "t = " << t;
    ASSERT_EQ(log.values(r, load), t < 1.0 ? 0.0 : -15.0) << "t = " << t;
  }
  EXPECT_NEAR(log.values(log.values.rows() - 1, log.column("output_velocity[rad/s]")),
              (250.0 + (w1 - 250.0) * std::exp(-2.0 / T)) / N, 1e-6 * 100.0);
}

TEST(JointRigLoadTorque, AClampedOutputRefusesALoadTorqueNamingTheKey) {
  const test::TempDir dir;
  const std::string path = (dir / "clamped.yaml").string();
  std::ofstream(path) << R"(experiment: {name: c, type: joint_rig}
rotor_inertia: 1.0e-3
transmission: {type: elastic, ratio: 10, stiffness: 1000}
load:
  clamped: true
  torque: {type: constant, value: 1}
input: {type: torque, profile: {type: constant, value: 1}}
duration: 1
)";
  try {
    experiments::loadExperiment(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("load.torque"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("clamped.yaml"), std::string::npos) << e.what();
  }
}
