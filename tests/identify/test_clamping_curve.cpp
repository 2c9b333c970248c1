// [KR300Thesis, Algorithm II] pieces (jointsim::identify, clamping_curve.hpp) on hand-made data: an exact
// piecewise-linear hysteresis loop (dead-zone spring ± Coulomb friction, angle-driven, with dwell at the
// turning points), where the fold must give half the backlash and the friction is half the branch distance.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/identify/clamping_curve.hpp"
#include "jointsim/identify/clamping_fit.hpp"
#include "test_util.hpp"

using namespace jointsim;
using namespace jointsim::identify;
using ::testing::HasSubstr;

namespace {

constexpr double kC = 25.7, kB = 0.0102, kF = 1.91, kPhi0 = 0.3;

/// Angle-driven exact loop: x sweeps phi0 ± amplitude; on a branch τ = EB(x − φ0) + s·F; at each turning
/// point `dwell` samples at constant angle while the torque crosses over to the other branch.
ClampingData exactLoop(int half_cycles, int samples_per_half_cycle = 500, int dwell = 20, double amplitude = 0.1) {
  std::vector<double> x, tau;
  double s = 1.0;
  double pos = kPhi0 - amplitude;
  for (int h = 0; h < half_cycles; ++h) {
    for (int k = 0; k < dwell; ++k) {  // turning: stuck, torque moves from −s F to +s F
      x.push_back(pos);
      tau.push_back(elastoBacklashStatic(pos - kPhi0, kC, kB) + s * kF * (2.0 * (k + 1) / dwell - 1.0));
    }
    for (int k = 1; k <= samples_per_half_cycle; ++k) {
      pos += s * 2.0 * amplitude / samples_per_half_cycle;
      x.push_back(pos);
      tau.push_back(elastoBacklashStatic(pos - kPhi0, kC, kB) + s * kF);
    }
    s = -s;
  }
  ClampingData d;
  const auto n = static_cast<Eigen::Index>(x.size());
  d.time = Eigen::VectorXd::LinSpaced(n, 0.0, 0.02 * static_cast<double>(n - 1));
  d.angle = Eigen::Map<Eigen::VectorXd>(x.data(), n);
  d.torque = Eigen::Map<Eigen::VectorXd>(tau.data(), n);
  return d;
}

}  // namespace

TEST(ClampingCurve, SegmentationFindsHalfCyclesDespiteTurningFlicker) {
  ClampingData d = exactLoop(6);
  // flicker in the turning regions: alternating ±1e-6 rad steps while the angle dwells
  for (Eigen::Index k = 0; k < d.angle.size(); ++k)
    if (k > 0 && d.angle[k] == d.angle[k - 1]) d.angle[k] += (k % 2 ? 1e-6 : -1e-6);
  const auto hcs = segmentHalfCycles(d.angle, ClampingCurveOptions{});
  ASSERT_EQ(hcs.size(), 6u);
  for (size_t i = 0; i < hcs.size(); ++i) {
    EXPECT_EQ(hcs[i].direction, i % 2 == 0 ? 1 : -1);
    EXPECT_GE(hcs[i].last - hcs[i].first, 490);
  }
}

TEST(ClampingCurve, MergeAveragesOverTheCoveredInterval) {
  Eigen::VectorXd x1 = Eigen::VectorXd::LinSpaced(11, 0.0, 1.0), x2 = Eigen::VectorXd::LinSpaced(11, 0.5, 1.5);
  const Eigen::VectorXd y1 = 2.0 * x1, y2 = 2.0 * x2.array() + 1.0;
  const GridCurve both = mergeCurves({{x1, y1}, {x2, y2}}, 2, 21);
  ASSERT_EQ(both.x.size(), 21);
  EXPECT_NEAR(both.x[0], 0.5, 1e-12);
  EXPECT_NEAR(both.x[20], 1.0, 1e-12);
  for (Eigen::Index i = 0; i < 21; ++i) EXPECT_NEAR(both.tau[i], 2.0 * both.x[i] + 0.5, 1e-12);
  const GridCurve any = mergeCurves({{x1, y1}, {x2, y2}}, 1, 31);
  EXPECT_NEAR(any.x[0], 0.0, 1e-12);
  EXPECT_NEAR(any.x[30], 1.5, 1e-12);
  EXPECT_NEAR(any.at(0.25), 0.5, 1e-12);  // only curve 1
  EXPECT_NEAR(any.at(1.25), 3.5, 1e-12);  // only curve 2
  EXPECT_TRUE(mergeCurves({{x1, y1}, {x2, y2}}, 3, 21).empty());
}

TEST(ClampingCurve, FlatRunMustBeInterior) {
  Eigen::VectorXd s(10);
  s << 0, 0, 5, 0, 0, 0, 5, 5, 0, 0;
  EXPECT_EQ(longestFlatRun(s, 1.0), std::make_pair(3, 5));
  Eigen::VectorXd edge(5);
  edge << 0, 0, 0, 5, 5;
  EXPECT_EQ(longestFlatRun(edge, 1.0).first, -1);
}

TEST(ClampingCurve, FoldOfDeadZoneGivesHalfTheBacklashAndTheStiffness) {
  GridCurve m;
  m.x = Eigen::VectorXd::LinSpaced(801, kPhi0 - 0.1, kPhi0 + 0.1);
  m.tau.resize(m.x.size());
  for (Eigen::Index i = 0; i < m.x.size(); ++i) m.tau[i] = elastoBacklashStatic(m.x[i] - kPhi0, kC, kB) + kF;
  ClampingCurveOptions o;
  o.slope_window_fraction = 0.01;
  double flat = 0, c = 0;
  const GridCurve f = foldCurve(m, kPhi0, o, flat, c);
  EXPECT_NEAR(c, kC, 1e-9);
  // flat part of the fold = half the total backlash (within the derivative window's smear)
  EXPECT_NEAR(flat, 0.5 * kB, 0.2 * 0.5 * kB);
  EXPECT_NEAR(f.tau[0], 0.0, 1e-12);
  EXPECT_NEAR(f.at(0.05), kC * (0.05 - 0.5 * kB), 1e-9);
}

TEST(ClampingCurve, ExactHysteresisLoopGivesTheParameters) {
  const ClampingData d = exactLoop(8);
  const ClampingCurves r = preprocessClampingCurve(d);
  EXPECT_EQ(r.half_cycles.size(), 8u);
  EXPECT_EQ(r.used_upper, 4);
  EXPECT_EQ(r.used_lower, 4);
  EXPECT_EQ(r.rejected, 0);
  EXPECT_TRUE(r.crosses_zero);
  EXPECT_NEAR(r.friction, kF, 1e-6);  // half the vertical distance of the branches
  EXPECT_NEAR(r.stiffness, kC, 1e-3 * kC);
  EXPECT_NEAR(r.backlash, kB, 0.02 * kB);
  EXPECT_NEAR(r.center, kPhi0, 0.1 * kB);
  EXPECT_NEAR(r.fold_flat, 0.5 * kB, 0.25 * 0.5 * kB);  // the fold's flat part is half the backlash
  EXPECT_NEAR(r.backlash_upper, kB, 0.5 * kB);
  // the Ceres fit recovers the exact values
  const ClampingFitResult fit = identifyClamping(d);
  EXPECT_NEAR(fit.stiffness.value, kC, 1e-6 * kC);
  EXPECT_NEAR(fit.backlash.value, kB, 1e-6 * kB);
  EXPECT_NEAR(fit.friction.value, kF, 1e-6 * kF);
  EXPECT_NEAR(fit.center.value, kPhi0, 1e-9);
  EXPECT_LT(fit.rms_residual, 1e-9);
}

TEST(ClampingCurve, OneSidedLoopIsUnobservableUnlessTheBacklashIsGiven) {
  ClampingData d = exactLoop(8);
  d.angle.array() += 0.15;  // the loop sits entirely in positive contact (x − φ0 ∈ [0.05, 0.25])
  for (Eigen::Index k = 0; k < d.angle.size(); ++k) {
    // recompute the torque for the shifted angle: same branch offsets
    const double branch = d.torque[k] - elastoBacklashStatic(d.angle[k] - 0.15 - kPhi0, kC, kB);
    d.torque[k] = elastoBacklashStatic(d.angle[k] - kPhi0, kC, kB) + branch;
  }
  const ClampingCurves r = preprocessClampingCurve(d);
  EXPECT_FALSE(r.crosses_zero);
  try {
    identifyClamping(d);
    FAIL() << "expected UnidentifiableError";
  } catch (const UnidentifiableError& e) {
    EXPECT_THAT(e.what(), HasSubstr("backlash"));
    EXPECT_THAT(e.what(), HasSubstr("never crosses zero torque"));
  }
  ClampingFitOptions o;
  o.fixed_backlash = kB;
  const ClampingFitResult fit = identifyClamping(d, o);
  EXPECT_NEAR(fit.stiffness.value, kC, 1e-6 * kC);
  EXPECT_NEAR(fit.friction.value, kF, 1e-6 * kF);
  EXPECT_NEAR(fit.center.value, kPhi0, 1e-8);
  EXPECT_FALSE(fit.backlash.fitted);
  EXPECT_EQ(fit.backlash.std_error, 0.0);
}

TEST(ClampingCurve, TooFewHalfCyclesIsBadInputTooManyRejectedIsUnidentifiable) {
  ClampingData ramp;
  ramp.time = Eigen::VectorXd::LinSpaced(200, 0.0, 4.0);
  ramp.angle = Eigen::VectorXd::LinSpaced(200, 0.0, 0.2);
  ramp.torque = kC * ramp.angle;
  EXPECT_THROW(preprocessClampingCurve(ramp), InputError);
  // half-cycles of 15 samples: found, but fewer than N_min = 20 points each after cleaning
  const ClampingData shortLoop = exactLoop(10, 15, 5);
  try {
    preprocessClampingCurve(shortLoop);
    FAIL() << "expected UnidentifiableError";
  } catch (const UnidentifiableError& e) {
    EXPECT_THAT(e.what(), HasSubstr("half-cycles rejected"));
  }
}

TEST(ClampingCurve, DataValidationNamesTheLine) {
  const jointsim::test::TempDir tmp;
  const auto path = tmp / "jointsim_clamping_curve_unsorted.csv";
  {
    std::ofstream f(path);
    f << "time[s],motor_angle[deg],motor_torque[N*m]\n";
    for (int k = 0; k < 30; ++k) f << (k == 20 ? 0.1 : 0.1 * k) << "," << k << "," << 2.0 * k << "\n";
  }
  try {
    readClampingCsv(path.string());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path.string() + ":22: time[s] must be strictly increasing"));
  }
  {
    std::ofstream f(path);
    f << "time[s],motor_angle[deg],motor_torque[N*m]\n";
    for (int k = 0; k < 30; ++k) f << 0.1 * k << "," << k << "," << 2.0 * k << "\n";
  }
  const ClampingData d = readClampingCsv(path.string(), 4.0);
  EXPECT_NEAR(d.angle[3], 3.0 * M_PI / 180.0, 1e-15);  // [deg] converted to rad
  EXPECT_NEAR(d.torque[3], 1.5, 1e-15);                // divided by the gear ratio
  EXPECT_THROW(readClampingCsv(path.string(), 0.0), InputError);
  std::filesystem::remove(path);
  ClampingCurveOptions bad;
  bad.step_filter_window = 4;
  EXPECT_THROW(bad.validate(), InputError);
}
