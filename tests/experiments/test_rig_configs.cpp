// The shipped joint-rig experiment files, run through the library entry point of `jointsim run`, against
// what their physics must show: the clamping curve of [KR300Thesis] (slope, backlash, hysteresis = 2 friction),
// the friction map of [Hauschild2003] (plateau torques = LuGre static map, eq. 4.21), and the UR5 strain-wave-gear
// joint tracking its velocity reference with output = motor / 101.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "jointsim/experiments/experiment.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {
struct Table {
  std::map<std::string, size_t> col;  // name without unit -> index
  std::vector<std::vector<double>> rows;
  double at(size_t r, const std::string& name) const { return rows[r][col.at(name)]; }
};

Table runConfig(const std::string& config, std::vector<std::string> overrides = {}) {
  const test::TempDir tmp(std::filesystem::path(config).stem().string());
  const auto dir = tmp / "out";
  experiments::RunOptions options;
  options.output_dir = dir.string();
  options.overrides = std::move(overrides);
  const auto report = experiments::runExperimentFile(test::sourcePath(config), options);
  EXPECT_EQ(report.status, "ok");
  std::ifstream in(report.csv_path);
  Table t;
  std::string line;
  std::getline(in, line);
  std::stringstream hs(line);
  size_t k = 0;
  for (std::string cell; std::getline(hs, cell, ',');) t.col[cell.substr(0, cell.find('['))] = k++;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<double> row;
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    t.rows.push_back(std::move(row));
  }
  return t;
}

// Least-squares line y = a + b x.
struct Line {
  double a = 0, b = 0;
  size_t n = 0;
};
Line fit(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  Line l;
  l.n = x.size();
  l.b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  l.a = (sy - l.b * sx) / n;
  return l;
}
}  // namespace

TEST(RigConfigs, Kr300ClampingCurveShowsTable61Parameters) {
  const double c = 25.7, b = 0.0102, F = 1.91, A = 5.0, T = 40.0;
  const Table t = runConfig("config/experiments/kr300_joint1_clamping.yaml");
  // Second cycle only. Rising torque: phase in [0, T/4) or [3T/4, T); falling: [T/4, 3T/4).
  std::vector<double> upR_phi, upR_tau, upL_phi, upL_tau, downR_phi, downR_tau;
  for (size_t r = 0; r < t.rows.size(); ++r) {
    const double time = t.at(r, "time");
    if (time < T) continue;
    const double phase = std::fmod(time, T) / T;
    const double tau = t.at(r, "motor_torque"), phi = t.at(r, "motor_angle");
    const bool rising = phase < 0.25 || phase >= 0.75;
    if (rising && tau > F + 0.8 && tau < A - 0.3) {
      upR_phi.push_back(phi);
      upR_tau.push_back(tau);
    }
    if (rising && tau > -A + 2 * F + 0.5 && tau < F - 0.5) {
      upL_phi.push_back(phi);
      upL_tau.push_back(tau);
    }
    if (!rising && tau > 0.5 && tau < A - 2 * F - 0.3) {
      downR_phi.push_back(phi);
      downR_tau.push_back(tau);
    }
  }
  const Line upR = fit(upR_phi, upR_tau), upL = fit(upL_phi, upL_tau), downR = fit(downR_phi, downR_tau);
  ASSERT_GT(upR.n, 20u);
  ASSERT_GT(upL.n, 20u);
  ASSERT_GT(downR.n, 20u);
  // Outer slopes: the stiffness.
  EXPECT_NEAR(upR.b, c, 0.02 * c);
  EXPECT_NEAR(upL.b, c, 0.02 * c);
  EXPECT_NEAR(downR.b, c, 0.02 * c);
  // Flat segment: the horizontal distance between the two contact lines of the rising branch at τ = F.
  const double span = (F - upR.a) / upR.b - (F - upL.a) / upL.b;
  EXPECT_NEAR(span, b, 0.05 * b);
  // Hysteresis: vertical distance between rising and falling branches in the same contact region.
  const double phi_mid = 0.5 * (upR_phi.front() + downR_phi.front());
  const double height = (upR.a + upR.b * phi_mid) - (downR.a + downR.b * phi_mid);
  EXPECT_NEAR(height, 2 * F, 0.05 * 2 * F);
}

TEST(RigConfigs, LuGreFrictionMapPlateausEqualStaticMap) {
  const Table t = runConfig("config/experiments/lugre_friction_map.yaml");
  // End of each plateau: torque = (α0 + α1 exp(−(v/v_S)²)) sgn v + α2 v ([Hauschild2003, eq. 4.21]), per direction.
  const double velocities[] = {0.01, 0.02, 0.05, 0.1, 0.2, -0.01, -0.02, -0.05, -0.1, -0.2};
  const double plateau_end[] = {30, 45, 51, 55, 58, 88, 103, 109, 113, 116};
  for (int k = 0; k < 10; ++k) {
    const double time = plateau_end[k] - 0.05;
    const size_t r = static_cast<size_t>(std::lround(time * 100));
    const double v = velocities[k];
    const bool pos = v > 0;
    const double a0 = pos ? 7.9707 : 7.7538, a1 = pos ? 1.4476 : 0.8626, a2 = pos ? 4.9349 : 4.3267,
                 vs = pos ? 0.0363 : 0.0221;
    const double expected = (a0 + a1 * std::exp(-(v / vs) * (v / vs))) * (pos ? 1 : -1) + a2 * v;
    EXPECT_NEAR(t.at(r, "output_velocity"), v, 1e-3 * std::abs(v)) << "plateau " << k;
    EXPECT_NEAR(t.at(r, "motor_torque"), expected, 1e-3 * std::abs(expected)) << "plateau " << k << ", v = " << v;
  }
}

TEST(RigConfigs, Ur5StrainWaveGearJointTracksVelocity) {
  const Table t = runConfig("config/experiments/ur5_swg_joint_velocity.yaml");
  const size_t r = 3900;  // t = 3.9 s, on the 101 rad/s plateau (log at 1 kHz)
  ASSERT_NEAR(t.at(r, "time"), 3.9, 1e-9);
  EXPECT_NEAR(t.at(r, "motor_velocity"), 101.0, 0.01 * 101.0);
  EXPECT_NEAR(t.at(r, "output_velocity"), t.at(r, "motor_velocity") / 101.0, 1e-4);
  // The output carries the friction torque at steady speed, the motor 1/101 of it (plus its own share).
  EXPECT_NEAR(t.at(r, "transmission_torque_out"), t.at(r, "friction_torque"),
              0.02 * std::abs(t.at(r, "friction_torque")) + 1e-3);
}
