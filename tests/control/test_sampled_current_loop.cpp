// Stability of the cascade's current loop under sampled control: the closed-form spectral radius against the
// growth of the iterated loop, and the refusal of an unstable rate with the rate from which it is stable.
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/joint_controller.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

control::JointControllerParams cascade(double P_cur, double I_cur) {
  control::JointControllerParams p;
  p.type = control::ControllerType::Cascade002;
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
