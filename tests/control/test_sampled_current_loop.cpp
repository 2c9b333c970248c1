// Stability of the cascade's current loop under sampled control: the closed-form spectral radius against the
// growth of the iterated loop, and the refusal of an unstable rate with the rate from which it is stable.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/joint_controller.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

control::JointControllerParams cascade(double P_cur, double I_cur) {
  control::JointControllerParams p;
  p.type = control::ControllerType::VoltageCascade;
  p.P_cur = P_cur;
  p.I_cur = I_cur;
  return p;
}

/// The sampled loop iterated: the exact zero-order-hold response of L di/dt = u − R i over each period, the
/// controller's integrator by forward Euler. Returns the mean growth per period of the state (power iteration:
/// renormalised every period, the logarithms of the growth averaged after a settling phase).
double iteratedGrowth(const control::JointControllerParams& p, double R, double L, double Ts) {
  double i = 1.0, x = 0.3 / std::max(p.I_cur, 1.0), log_sum = 0.0;
  const int settle = 500, count = 2000;
  for (int k = 0; k < settle + count; ++k) {
    const double u = p.P_cur * (0.0 - i) + p.I_cur * x;
    x += Ts * (0.0 - i);
    const double i_inf = u / R;  // the steady current for the held voltage
    i = i_inf + (i - i_inf) * std::exp(-R * Ts / L);
    const double s = std::hypot(i, x * p.I_cur / R);  // both parts in amperes
    if (k >= settle) log_sum += std::log(s);
    i /= s;
    x /= s;
  }
  return std::exp(log_sum / count);
}

TEST(SampledCurrentLoop, RadiusMatchesTheGrowthOfTheIteratedLoop) {
  const double R = 0.30, L = 0.83e-3;  // UR5 joints 1-3
  for (double rate : {1000.0, 2000.0, 5000.0, 8000.0, 20000.0, 100000.0}) {
    const auto p = cascade(10.0, 10000.0);
    const double rho = control::sampledCurrentLoopRadius(p, R, L, 1.0 / rate);
    EXPECT_NEAR(iteratedGrowth(p, R, L, 1.0 / rate), rho, 2e-2 * rho) << rate << " Hz";
  }
  // Slow sampling against a fast loop: the P-part alone gives the pole a − (1 − a) P/R (the forward-Euler
  // integrator adds a pole near 1): at 2 kHz, a = e^{−0.18} and the pole is −4.67 for P = 10 V/A.
  const double a = std::exp(-0.3 * 5e-4 / 0.83e-3);
  EXPECT_NEAR(control::sampledCurrentLoopRadius(cascade(10.0, 0.0), R, L, 5e-4), std::abs(a - (1 - a) * 10 / 0.3),
              1e-12);
  EXPECT_EQ(control::sampledCurrentLoopRadius(control::JointControllerParams{}, R, L, 5e-4), 0.0);
}

TEST(SampledCurrentLoop, UnstableRateIsAnInputErrorNamingTheStableRate) {
  systems::RobotSystem sys = systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml"));
  try {
    sys.setSampledControl(2000.0, 1);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("drive 'shoulder_pan_joint'"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("unstable"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("stable from about"));
  }
  EXPECT_FALSE(sys.sampled());  // nothing changed
  // The twin's drives are stable at 20 kHz.
  EXPECT_NO_THROW(sys.setSampledControl(20000.0, 1));
}

}  // namespace

namespace {

std::string slurpFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// ur5_excitation (0.05 s, no sensor noise) with the given `control:` mapping, in memory.
sim::SignalTable trackingRun(const std::string& control) {
  const test::TempDir tmp("multirate");
  const auto& dir = tmp.path();
  std::string drives = slurpFile(test::sourcePath("config/robots/ur5_drives.yaml"));
  drives.replace(drives.find("multibody: ur5.yaml"), 19, "multibody: " + test::sourcePath("config/robots/ur5.yaml"));
  std::ofstream(dir / "drives.yaml") << drives;
  std::string exp = slurpFile(test::sourcePath("config/experiments/ur5_excitation.yaml"));
  exp.replace(exp.find("robot: ../robots/ur5_drives.yaml"), 32, "robot: drives.yaml\ncontrol: " + control);
  std::ofstream(dir / "exp.yaml") << exp;
  auto e = experiments::loadExperiment((dir / "exp.yaml").string(), {"duration=0.05", "log_rate=2000"});
  return experiments::runInMemory(*e).log;
}

TEST(SampledCurrentLoop, MultiRateRunsTheCurrentLoopWhereTheOuterRateWouldBeUnstable) {
  systems::RobotSystem sys = systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml"));
  EXPECT_THROW(sys.setSampledControl(2000.0, 1, 5000.0), InputError);   // the current loop unstable at 5 kHz
  EXPECT_THROW(sys.setSampledControl(2000.0, 1, 21000.0), InputError);  // not an integer multiple
  EXPECT_THROW(sys.setSampledControl(2000.0, 1, 1000.0), InputError);   // slower than the outer loops
  ASSERT_NO_THROW(sys.setSampledControl(2000.0, 1, 20000.0));
  EXPECT_DOUBLE_EQ(sys.samplePeriod(), 5e-5);
  EXPECT_DOUBLE_EQ(sys.currentRate(), 20000.0);
  // Position and velocity loops at 2 kHz around a 20 kHz current loop track like the all-20 kHz controller (the
  // outer loops' bandwidth is far below 2 kHz): the joint angles agree within 0.2 mrad, both follow the reference.
  const sim::SignalTable multi = trackingRun("{rate: 2000, current_rate: 20000}");
  const sim::SignalTable fast = trackingRun("{rate: 20000}");
  for (const char* joint : {"shoulder_pan_joint", "elbow_joint", "wrist_3_joint"}) {
    const std::string q = std::string("q_") + joint, q_set = std::string("q_set_") + joint;
    EXPECT_LE((multi[q] - fast[q]).cwiseAbs().maxCoeff(), 2e-4) << joint;
    EXPECT_LE((multi[q] - multi[q_set]).cwiseAbs().maxCoeff(), 2e-3) << joint;
  }
}

}  // namespace
