// Joint-space trajectories: point-to-point moves, Fourier excitation, CSV set-points (spline), limit checks
// and YAML parsing with its errors.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/control/trajectory_yaml.hpp"
#include "test_util.hpp"

using jointsim::InputError;
using jointsim::control::FourierParams;
using jointsim::control::FourierTrajectory;
using jointsim::control::JointTrajectory;
using jointsim::control::PointToPointTrajectory;
using jointsim::control::PtpSegment;
using jointsim::control::SampledTrajectory;
using jointsim::test::MatricesNear;
using jointsim::test::TempDir;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out[i++] = x;
  return out;
}

bool exactlyEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && (a.array() == b.array()).all();
}

/// Central differences of q (against qd) and qd (against qdd) at `times`, skipping points within 3h of
/// a breakpoint.
void expectDerivativesMatch(const JointTrajectory& traj, const std::vector<double>& times, double tol) {
  const double h = 1e-6;
  const auto bps = traj.breakpoints();
  for (double t : times) {
    bool near = false;
    for (double b : bps) near = near || std::abs(t - b) < 3 * h;
    if (near) continue;
    const auto p = traj.setpoint(t + h), m = traj.setpoint(t - h), c = traj.setpoint(t);
    EXPECT_TRUE(MatricesNear(c.qd, (p.q - m.q) / (2 * h), tol)) << "qd at t = " << t;
    EXPECT_TRUE(MatricesNear(c.qdd, (p.qd - m.qd) / (2 * h), tol)) << "qdd at t = " << t;
  }
}

std::vector<double> grid(double t0, double t1, int n) {
  std::vector<double> out;
  for (int k = 0; k < n; ++k) out.push_back(t0 + (t1 - t0) * (k + 0.5) / n);
  return out;
}

// Three UR5-like moves: a long (trapezoidal) one, a short (triangular) one, one given by duration.
PointToPointTrajectory ur5Moves() {
  const Eigen::VectorXd start = vec({0.0, -1.57, 1.57, -1.57, -1.57, 0.0});
  std::vector<PtpSegment> segs(3);
  segs[0].target = start + vec({1.0, 0.5, -0.3, 0.2, 0.0, -0.1});
  segs[0].velocity = 1.05;
  segs[0].acceleration = 1.4;
  segs[0].dwell = 0.2;
  segs[1].target = segs[0].target + vec({0.05, -0.2, 0.1, 0.0, 0.02, 0.0});
  segs[1].velocity = 1.05;
  segs[1].acceleration = 1.4;
  segs[2].target = segs[1].target + vec({-0.3, 0.5, 0.1, 0.0, 0.0, 0.2});
  segs[2].duration = 1.5;
  segs[2].acceleration = 2.0;
  segs[2].dwell = 0.3;
  return PointToPointTrajectory(start, segs);
}

std::filesystem::path writeFile(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

// ------------------------------------------------------------------------------------------ point to point

TEST(TrajectoryPointToPoint, EachSegmentEndsExactlyAtItsTargetAtRest) {
  const auto traj = ur5Moves();
  ASSERT_EQ(traj.segmentCount(), 3);
  EXPECT_EQ(traj.dof(), 6);
  for (int k = 0; k < 3; ++k) {
    const auto& target = traj.segments()[static_cast<size_t>(k)].target;
    const auto end = traj.setpoint(traj.segmentEnd(k));
    EXPECT_TRUE(exactlyEqual(end.q, target)) << "segment " << k;
    EXPECT_TRUE(end.qd.isZero(0.0));
    // qdd is right-continuous: 0 during a dwell; segment 1 has none, so segment 2 starts accelerating there.
    if (traj.segments()[static_cast<size_t>(k)].dwell > 0) {
      EXPECT_TRUE(end.qdd.isZero(0.0));
    }
    const auto before = traj.setpoint(traj.segmentEnd(k) - 1e-9);  // velocity goes continuously to 0
    EXPECT_LT(before.qd.cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT((before.q - target).cwiseAbs().maxCoeff(), 1e-15);
  }
  // Dwell after segment 0, then segment 1 starts; the final point is held.
  EXPECT_NEAR(traj.segmentStart(1) - traj.segmentEnd(0), 0.2, 1e-15);
  EXPECT_NEAR(traj.duration() - traj.segmentEnd(2), 0.3, 1e-15);
  EXPECT_TRUE(exactlyEqual(traj.setpoint(traj.duration() + 5.0).q, traj.segments()[2].target));
  EXPECT_TRUE(exactlyEqual(traj.setpoint(-1.0).q, traj.start()));
  EXPECT_TRUE(exactlyEqual(traj.setpoint(0.0).q, traj.start()));
  EXPECT_TRUE(traj.setpoint(0.0).qd.isZero(0.0));
  EXPECT_THAT(traj.describe(), HasSubstr("point_to_point(6 joints, 3 segments"));
}

TEST(TrajectoryPointToPoint, TrapezoidSynchronisedAndWithinLimits) {
  const auto traj = ur5Moves();
  const double v = 1.05, a = 1.4, D = 1.0;  // joint 0 has the largest distance in segment 0
  EXPECT_NEAR(traj.accelTime(0), v / a, 1e-15);
  EXPECT_NEAR(traj.cruiseTime(0), D / v - v / a, 1e-15);
  const Eigen::VectorXd delta = traj.segments()[0].target - traj.start();
  double vmax = 0, amax = 0;
  for (double t = 0.0; t <= traj.segmentEnd(0); t += 1e-3) {
    const auto s = traj.setpoint(t);
    vmax = std::max(vmax, s.qd.cwiseAbs().maxCoeff());
    amax = std::max(amax, s.qdd.cwiseAbs().maxCoeff());
    // Same normalised profile for every joint: qd_i / Δ_i equal across joints (synchronised phases).
    for (int i = 1; i < 6; ++i)
      if (delta[i] != 0.0) {
        EXPECT_NEAR(s.qd[i] / delta[i], s.qd[0] / delta[0], 1e-12);
      }
  }
  EXPECT_LE(vmax, v + 1e-12);
  EXPECT_NEAR(vmax, v, 1e-12);  // the slowest joint reaches the velocity limit
  EXPECT_LE(amax, a + 1e-12);
  EXPECT_NEAR(amax, a, 1e-12);
  // Every moving joint is still moving just before the common end, and all are at rest after it.
  const auto late = traj.setpoint(traj.segmentEnd(0) - 1e-3);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(late.qd[i] != 0.0, delta[i] != 0.0) << "joint " << i;
  // Other joints have proportionally lower peaks.
  const auto cruise = traj.setpoint(traj.accelTime(0) + 0.5 * traj.cruiseTime(0));
  EXPECT_NEAR(cruise.qd[1], v * 0.5, 1e-12);
  EXPECT_NEAR(cruise.qd[2], -v * 0.3, 1e-12);
}

TEST(TrajectoryPointToPoint, ShortMoveIsTriangular) {
  const auto traj = ur5Moves();
  const double a = 1.4, D = 0.2;  // segment 1: D < v²/a = 1.05²/1.4
  EXPECT_EQ(traj.cruiseTime(1), 0.0);
  EXPECT_NEAR(traj.accelTime(1), std::sqrt(D / a), 1e-15);
  double vmax = 0, amax = 0;
  for (double t = traj.segmentStart(1); t <= traj.segmentEnd(1); t += 1e-4) {
    const auto s = traj.setpoint(t);
    vmax = std::max(vmax, s.qd.cwiseAbs().maxCoeff());
    amax = std::max(amax, s.qdd.cwiseAbs().maxCoeff());
  }
  EXPECT_NEAR(amax, a, 1e-12);  // reaches the acceleration limit
  EXPECT_LT(vmax, 1.05);        // never the velocity limit
  EXPECT_NEAR(vmax, std::sqrt(D * a), 1e-3);
  const auto peak = traj.setpoint(traj.segmentStart(1) + traj.accelTime(1));
  EXPECT_NEAR(peak.qd.cwiseAbs().maxCoeff(), std::sqrt(D * a), 1e-12);
}

TEST(TrajectoryPointToPoint, DurationSegmentTakesItsTimeWithTheGivenAcceleration) {
  const auto traj = ur5Moves();
  EXPECT_NEAR(traj.segmentEnd(2) - traj.segmentStart(2), 1.5, 1e-12);
  double amax = 0;
  for (double t = traj.segmentStart(2); t <= traj.segmentEnd(2); t += 1e-3)
    amax = std::max(amax, traj.setpoint(t).qdd.cwiseAbs().maxCoeff());
  EXPECT_NEAR(amax, 2.0, 1e-12);
  // Without acceleration: triangular, peak acceleration 4 D / T².
  std::vector<PtpSegment> segs(1);
  segs[0].target = vec({0.5, -0.25});
  segs[0].duration = 2.0;
  const PointToPointTrajectory tri(vec({0.0, 0.0}), segs);
  EXPECT_NEAR(tri.accelTime(0), 1.0, 1e-15);
  EXPECT_NEAR(tri.setpoint(0.5).qdd[0], 4 * 0.5 / 4.0, 1e-15);
  EXPECT_NEAR(tri.setpoint(1.0).qd[0], 2 * 0.5 / 2.0, 1e-15);
}

TEST(TrajectoryPointToPoint, DerivativesMatchFiniteDifferencesAndBreakpoints) {
  const auto traj = ur5Moves();
  expectDerivativesMatch(traj, grid(0.0, traj.duration(), 97), 1e-6);
  const auto bps = traj.breakpoints();
  ASSERT_FALSE(bps.empty());
  EXPECT_TRUE(std::is_sorted(bps.begin(), bps.end()));
  EXPECT_GT(bps.front(), 0.0);
  const auto has = [&](double t) {
    return std::any_of(bps.begin(), bps.end(), [&](double b) { return std::abs(b - t) < 1e-12; });
  };
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(has(traj.segmentStart(k) + traj.accelTime(k))) << k;
    EXPECT_TRUE(has(traj.segmentEnd(k))) << k;
  }
  EXPECT_TRUE(has(traj.segmentStart(1)));
  EXPECT_TRUE(has(traj.segmentEnd(0) - traj.accelTime(0)));  // end of cruise
}

TEST(TrajectoryPointToPoint, InvalidSegmentsAreRejected) {
  std::vector<PtpSegment> segs(1);
  segs[0].target = vec({1.0, 0.0});
  segs[0].velocity = 1.0;
  EXPECT_THAT(
      [&] {
        PointToPointTrajectory(vec({0, 0}), segs);
      },
      ThrowsMessage<InputError>(HasSubstr("segment 0: acceleration must be > 0")));
  segs[0].duration = 1.0;
  segs[0].acceleration = 1.0;
  EXPECT_THAT(
      [&] {
        PointToPointTrajectory(vec({0, 0}), segs);
      },
      ThrowsMessage<InputError>(HasSubstr("either velocity (with acceleration) or duration")));
  segs[0].velocity = 0.0;  // 1 rad in 1 s needs a >= 4 rad/s²
  EXPECT_THAT(
      [&] {
        PointToPointTrajectory(vec({0, 0}), segs);
      },
      ThrowsMessage<InputError>(HasSubstr("too low to move 1 rad in 1 s")));
  segs[0].target = vec({1.0});
  EXPECT_THAT(
      [&] {
        PointToPointTrajectory(vec({0, 0}), segs);
      },
      ThrowsMessage<InputError>(HasSubstr("target has 1 joint positions, expected 2")));
}

// ------------------------------------------------------------------------------------------ Fourier

namespace {
FourierParams fourierParams() {
  std::mt19937 rng(7);
  FourierParams p;
  p.base_frequency = 0.2;
  p.offset = vec({0.1, -0.5, 1.2});
  p.a = Eigen::MatrixXd(3, 4);
  p.b = Eigen::MatrixXd(3, 4);
  for (int i = 0; i < 3; ++i) {
    p.a.row(i) = jointsim::test::randomVector(rng, 4, -0.3, 0.3).transpose();
    p.b.row(i) = jointsim::test::randomVector(rng, 4, -0.3, 0.3).transpose();
  }
  p.fade_in = 1.5;
  return p;
}
}  // namespace

TEST(TrajectoryFourier, SeriesMatchesTheClosedForm) {
  const FourierTrajectory traj(fourierParams());
  EXPECT_EQ(traj.harmonics(), 4);
  EXPECT_DOUBLE_EQ(traj.duration(), 1.5 + 5.0);  // default: fade-in + one period
  const auto& p = traj.params();
  const double wf = 2 * 3.141592653589793 * 0.2, tau = 0.73;
  double q = p.offset[1], qd = 0;
  for (int k = 1; k <= 4; ++k) {
    q += p.a(1, k - 1) / (wf * k) * std::sin(wf * k * tau) - p.b(1, k - 1) / (wf * k) * std::cos(wf * k * tau);
    qd += p.a(1, k - 1) * std::cos(wf * k * tau) + p.b(1, k - 1) * std::sin(wf * k * tau);
  }
  Eigen::VectorXd sq(3), sqd(3), sqdd(3);
  traj.evaluateSeries(tau, sq, sqd, sqdd);
  EXPECT_NEAR(sq[1], q, 1e-14);
  EXPECT_NEAR(sqd[1], qd, 1e-14);
  // Periodic: one period later the same.
  Eigen::VectorXd pq(3), pqd(3), pqdd(3);
  traj.evaluateSeries(tau + traj.period(), pq, pqd, pqdd);
  EXPECT_TRUE(MatricesNear(pq, sq, 1e-12));
}

TEST(TrajectoryFourier, FadeInStartsAtRestAtTheOffsetAndMatchesTheSeriesAfter) {
  const FourierTrajectory traj(fourierParams());
  const auto s0 = traj.setpoint(0.0);
  EXPECT_TRUE(exactlyEqual(s0.q, traj.params().offset));
  EXPECT_TRUE(s0.qd.isZero(0.0));
  EXPECT_TRUE(s0.qdd.isZero(0.0));
  const auto early = traj.setpoint(1e-4);  // smooth start: |qd| = O(t²), |qdd| = O(t)
  EXPECT_LT(early.qd.cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT(early.qdd.cwiseAbs().maxCoeff(), 1e-2);
  Eigen::VectorXd q(3), qd(3), qdd(3);
  for (double t : {1.5, 2.0, 4.321, 6.5, 9.0}) {
    const auto s = traj.setpoint(t);
    traj.evaluateSeries(t - 1.5, q, qd, qdd);
    EXPECT_TRUE(exactlyEqual(s.q, q)) << t;
    EXPECT_TRUE(exactlyEqual(s.qd, qd)) << t;
    EXPECT_TRUE(exactlyEqual(s.qdd, qdd)) << t;
  }
  // Continuous through the end of the fade, including the acceleration.
  const auto a = traj.setpoint(1.5 - 1e-9), b = traj.setpoint(1.5 + 1e-9);
  EXPECT_TRUE(MatricesNear(a.q, b.q, 1e-8));
  EXPECT_TRUE(MatricesNear(a.qd, b.qd, 1e-7));
  EXPECT_TRUE(MatricesNear(a.qdd, b.qdd, 1e-6));
  EXPECT_TRUE(traj.breakpoints().empty());
  EXPECT_THAT(traj.describe(), HasSubstr("4 harmonics"));
}

TEST(TrajectoryFourier, DerivativesMatchFiniteDifferences) {
  const FourierTrajectory traj(fourierParams());
  expectDerivativesMatch(traj, grid(0.0, 8.0, 53), 1e-6);
  auto p = fourierParams();
  p.fade_in = 0.0;
  p.duration = 10.0;
  const FourierTrajectory pure(p);
  expectDerivativesMatch(pure, grid(0.0, 10.0, 23), 1e-6);
  EXPECT_DOUBLE_EQ(pure.duration(), 10.0);
}

TEST(TrajectoryFourier, InvalidParametersAreRejected) {
  auto p = fourierParams();
  p.b = Eigen::MatrixXd::Zero(3, 2);
  EXPECT_THAT([&] { FourierTrajectory{p}; }, ThrowsMessage<InputError>(HasSubstr("a and b must both be 3 x N")));
  p = fourierParams();
  p.base_frequency = 0.0;
  EXPECT_THAT([&] { FourierTrajectory{p}; }, ThrowsMessage<InputError>(HasSubstr("base_frequency must be > 0 Hz")));
  p = fourierParams();
  p.duration = 1.0;
  EXPECT_THAT([&] { FourierTrajectory{p}; }, ThrowsMessage<InputError>(HasSubstr(">= fade_in")));
}

// ------------------------------------------------------------------------------------------ sampled / CSV

namespace {
SampledTrajectory sampled() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001);
  std::vector<double> t;
  const int K = 60;
  Eigen::MatrixXd y(2, K);
  for (int k = 0; k < K; ++k) {
    t.push_back(5.0 + 0.008 * k + jitter(rng));
    y(0, k) = 0.3 * std::sin(2.0 * t.back());
    y(1, k) = -1.0 + 0.2 * std::cos(3.0 * t.back()) + 0.05 * t.back();
  }
  return SampledTrajectory(t, y, "test samples");
}
}  // namespace

TEST(TrajectorySampled, SplinePassesThroughTheSamplesAndIsC2) {
  const auto traj = sampled();
  EXPECT_NEAR(traj.startTime(), 5.0, 0.0011);
  const auto& t = traj.times();
  EXPECT_EQ(t.front(), 0.0);
  for (size_t k = 0; k < t.size(); ++k)
    EXPECT_TRUE(MatricesNear(traj.setpoint(t[k]).q, traj.positions().col(static_cast<Eigen::Index>(k)), 1e-13)) << k;
  for (size_t k = 1; k + 1 < t.size(); ++k) {
    const auto a = traj.setpoint(t[k] - 1e-9), b = traj.setpoint(t[k] + 1e-9);
    EXPECT_TRUE(MatricesNear(a.q, b.q, 1e-9)) << k;
    EXPECT_TRUE(MatricesNear(a.qd, b.qd, 1e-7)) << k;
    EXPECT_TRUE(MatricesNear(a.qdd, b.qdd, 1e-5)) << k;
  }
  // Natural spline: zero curvature at both ends; close to the underlying smooth signal inside.
  EXPECT_TRUE(traj.setpoint(1e-12).qdd.isZero(1e-6));
  EXPECT_TRUE(traj.setpoint(traj.duration() - 1e-12).qdd.isZero(1e-6));
  const double tm = 0.2;
  EXPECT_NEAR(traj.setpoint(tm).qd[0], 0.6 * std::cos(2.0 * (tm + traj.startTime())), 1e-4);
  // Holds outside the samples.
  EXPECT_TRUE(exactlyEqual(traj.setpoint(traj.duration() + 1.0).q, traj.positions().col(59)));
  EXPECT_TRUE(traj.setpoint(traj.duration() + 1.0).qd.isZero(0.0));
  EXPECT_EQ(traj.breakpoints(), std::vector<double>({traj.duration()}));
}

TEST(TrajectorySampled, DerivativesMatchFiniteDifferences) {
  const auto traj = sampled();
  expectDerivativesMatch(traj, grid(0.0, traj.duration(), 61), 1e-5);
}

TEST(TrajectorySampled, CsvByOrderAndByColumnName) {
  const TempDir tmp;
  std::string text = "time [s],qd1,q1,q2\n";
  for (int k = 0; k < 20; ++k) {
    const double t = 100.0 + 0.008 * k;
    text += std::to_string(t) + ",9," + std::to_string(0.01 * k) + "," + std::to_string(-0.02 * k) + "\n";
  }
  const auto path = writeFile(tmp, "jointsim_traj_named.csv", text + "\n");
  const auto traj = SampledTrajectory::fromCsv(path.string(), 2, {"q1", "q2"});
  EXPECT_EQ(traj.dof(), 2);
  EXPECT_NEAR(traj.startTime(), 100.0, 1e-12);
  EXPECT_NEAR(traj.duration(), 19 * 0.008, 1e-9);
  EXPECT_NEAR(traj.setpoint(0.04).q[0], 0.05, 1e-9);  // linear data: the spline is exact
  EXPECT_NEAR(traj.setpoint(0.04).qd[1], -2.5, 1e-6);
  EXPECT_THAT(traj.describe(), HasSubstr("jointsim_traj_named.csv, 2 joints, 20 samples"));
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(path.string(), 2); },
              ThrowsMessage<InputError>(HasSubstr("jointsim_traj_named.csv:1: expected 1 + 2 = 3 columns (time, "
                                                  "then one per joint), got 4; name the joint columns")));
  EXPECT_THAT(
      [&] {
        SampledTrajectory::fromCsv(path.string(), 2, {"q1", "q3"});
      },
      ThrowsMessage<InputError>(
          HasSubstr("jointsim_traj_named.csv:1: no column named 'q3' (columns: time [s], qd1, q1, q2)")));
  const auto ordered = SampledTrajectory::fromCsv(path.string(), 3);
  EXPECT_DOUBLE_EQ(ordered.setpoint(0.0).q[0], 9.0);
}

TEST(TrajectorySampled, CsvErrorsNameTheFileAndRow) {
  const TempDir tmp;
  // A gap: 125 Hz samples, then one 0.05 s step into row 57 (line 57 of the file, the header is row 1).
  std::string text = "t,q1,q2\n";
  double t = 0.0;
  for (int row = 2; row <= 70; ++row) {
    if (row > 2) t += (row == 57) ? 0.05 : 0.008;
    text += std::to_string(t) + ",0.1,0.2\n";
  }
  const auto gap = writeFile(tmp, "jointsim_traj_gap.csv", text);
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(gap.string(), 2); },
              ThrowsMessage<InputError>(
                  HasSubstr("jointsim_traj_gap.csv:57: time step 0.05 s is more than 3x the median 0.008 s (a gap)")));
  EXPECT_NO_THROW(SampledTrajectory::fromCsv(gap.string(), 2, {}, 10.0));
  EXPECT_NO_THROW(SampledTrajectory::fromCsv(gap.string(), 2, {}, 0.0));

  const auto backwards = writeFile(tmp, "jointsim_traj_backwards.csv", "t,q1\n0,1\n0.008,1\n0.008,2\n");
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(backwards.string(), 1); },
              ThrowsMessage<InputError>(HasSubstr("jointsim_traj_backwards.csv:4: time 0.008 s is not after")));
  const auto cell = writeFile(tmp, "jointsim_traj_cell.csv", "t,q1,q2\n0,1,2\n0.008,1,abc\n");
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(cell.string(), 2); },
              ThrowsMessage<InputError>(
                  HasSubstr("jointsim_traj_cell.csv:3:3: column 'q2': expected a number, got 'abc'")));
  const auto cols = writeFile(tmp, "jointsim_traj_cols.csv", "t,q1,q2\n0,1,2\n0.008,1\n");
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(cols.string(), 2); },
              ThrowsMessage<InputError>(
                  HasSubstr("jointsim_traj_cols.csv:3: expected 3 cells as in the header, got 2")));
  const auto trailing = writeFile(tmp, "jointsim_traj_trailing.csv", "t,q1,q2\n0,1,2,\n");
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(trailing.string(), 2); },
              ThrowsMessage<InputError>(
                  HasSubstr("jointsim_traj_trailing.csv:2: expected 3 cells as in the header, got 4")));
  const auto one = writeFile(tmp, "jointsim_traj_one.csv", "t,q1\n0,1\n");
  EXPECT_THAT([&] { SampledTrajectory::fromCsv(one.string(), 1); },
              ThrowsMessage<InputError>(HasSubstr("at least 2 data rows")));
  EXPECT_THAT([&] { SampledTrajectory::fromCsv((tmp / "jointsim_nope.csv").string(), 1); },
              ThrowsMessage<InputError>(HasSubstr("cannot open")));
}

// ------------------------------------------------------------------------------------------ limits

TEST(TrajectoryLimits, ViolationNamesTheJointAndTime) {
  std::vector<PtpSegment> segs(1);
  segs[0].target = vec({0.1, 1.0});
  segs[0].velocity = 1.0;
  segs[0].acceleration = 1.0;  // joint 1: q = t²/2 for t < 1, peak speed 1 rad/s at t = 1
  const PointToPointTrajectory traj(vec({0.0, 0.0}), segs);
  std::vector<jointsim::multibody::JointLimits> lim(2);
  lim[0].lower = -1.0;
  lim[0].upper = 1.0;
  lim[1].lower = -3.0;
  lim[1].upper = 3.0;
  const std::vector<std::string> names{"shoulder_pan", "wrist_1"};
  EXPECT_NO_THROW(jointsim::control::checkLimits(traj, names, lim));
  lim[1].upper = 0.125;  // reached at t = 0.5 s, exceeded from the next millisecond
  EXPECT_THAT([&] { jointsim::control::checkLimits(traj, names, lim); },
              ThrowsMessage<InputError>(HasSubstr(
                  "trajectory leaves the limits of joint wrist_1 at t = 0.501 s: q = 0.1255 rad outside [-3, 0.125]")));
  lim[1].upper = 3.0;
  lim[1].velocity = 0.9;
  EXPECT_THAT([&] { jointsim::control::checkLimits(traj, names, lim); },
              ThrowsMessage<InputError>(
                  HasSubstr("velocity limit of joint wrist_1 at t = 0.901 s: |qd| = 0.901 rad/s > 0.9 rad/s")));
  lim[1].velocity = 1.0;  // exactly reached: allowed
  EXPECT_NO_THROW(jointsim::control::checkLimits(traj, names, lim));
  EXPECT_THAT([&] { jointsim::control::checkLimits(traj, {"a"}, lim); },
              ThrowsMessage<InputError>(HasSubstr("2 joints but 1 joint names")));
}

// ------------------------------------------------------------------------------------------ YAML

namespace {
std::unique_ptr<JointTrajectory> fromYaml(const std::string& text, int dof, const std::string& base_dir = ".") {
  const auto doc = jointsim::io::YamlValue::loadString(text, "t.yaml");
  return jointsim::control::trajectoryFromYaml(doc["trajectory"], dof, base_dir);
}
/// Expects the trajectory of `text`, its files relative to `base_dir`, to fail with `message`.
auto yamlErrorIn(const std::string& base_dir, const std::string& text, int dof, const std::string& message) {
  return [=] { EXPECT_THAT([&] { fromYaml(text, dof, base_dir); }, ThrowsMessage<InputError>(HasSubstr(message))); };
}
}  // namespace

TEST(TrajectoryYaml, PointToPoint) {
  const auto traj = fromYaml(R"(trajectory:
  type: point_to_point
  start: [0, -1.57]
  segments:
    - {target: [1, -1.57], velocity: 1.05, acceleration: 1.4, dwell: 0.2}
    - target: [1, 0]
      duration: 2
)",
                             2);
  const auto* ptp = dynamic_cast<const PointToPointTrajectory*>(traj.get());
  ASSERT_NE(ptp, nullptr);
  ASSERT_EQ(ptp->segmentCount(), 2);
  EXPECT_DOUBLE_EQ(ptp->segments()[0].dwell, 0.2);
  EXPECT_NEAR(ptp->duration(), (1.0 / 1.05 + 0.75) + 0.2 + 2.0, 1e-12);
  EXPECT_TRUE(exactlyEqual(ptp->setpoint(ptp->duration()).q, vec({1, 0})));
}

TEST(TrajectoryYaml, FourierAndCsv) {
  const auto f = fromYaml(R"(trajectory:
  type: fourier
  base_frequency: 0.1
  harmonics: 2
  offset: [0.5, -1]
  a: [[0.1, 0.2], [0.0, -0.1]]
  b: [[0, 0.05], [0.1, 0]]
  fade_in: 2
)",
                          2);
  const auto* fourier = dynamic_cast<const FourierTrajectory*>(f.get());
  ASSERT_NE(fourier, nullptr);
  EXPECT_DOUBLE_EQ(fourier->duration(), 12.0);
  EXPECT_DOUBLE_EQ(fourier->params().a(0, 1), 0.2);
  EXPECT_DOUBLE_EQ(fourier->params().b(1, 0), 0.1);
  EXPECT_TRUE(exactlyEqual(fourier->setpoint(0).q, vec({0.5, -1})));

  const TempDir tmp;
  const auto dir = tmp / "jointsim_traj_yaml";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "log.csv") << "t,a,b\n0,1,2\n0.008,1,2\n0.016,1,2\n";
  const auto c = fromYaml("trajectory: {type: csv, file: log.csv, columns: [b, a], gap_factor: 5}\n", 2, dir.string());
  ASSERT_NE(dynamic_cast<const SampledTrajectory*>(c.get()), nullptr);
  EXPECT_TRUE(exactlyEqual(c->setpoint(0.01).q, vec({2, 1})));
}

TEST(TrajectoryYaml, ErrorsNameFileLineAndKeyPath) {
  const TempDir tmp;  // the base folder of the trajectory's files
  const auto yamlError = [&](const std::string& text, int dof, const std::string& message) {
    return yamlErrorIn(tmp.string(), text, dof, message);
  };
  const std::string head = "trajectory:\n  type: point_to_point\n  start: [0, 0]\n  segments:\n";
  yamlError(
      head + "    - {target: [1, 2, 3], velocity: 1, acceleration: 1}\n", 2,
      "t.yaml:5: trajectory.segments[0].target: expected a list of 2 joint positions in rad, got a list of 3 items")();
  yamlError(head + "    - {target: [1, 2], velocty: 1, acceleration: 1}\n", 2,
            "t.yaml:5: trajectory.segments[0].velocty: unknown key 'velocty' (did you mean 'velocity'?)")();
  yamlError(head + "    - {target: [1, 2], velocity: 1}\n", 2,
            "t.yaml:5: trajectory.segments[0]: missing required key 'acceleration'")();
  yamlError(head + "    - {target: [1, 2], velocity: -1, acceleration: 1}\n", 2,
            "t.yaml:5: trajectory.segments[0].velocity: expected a joint speed in rad/s > 0, got '-1'")();
  yamlError(head + "    - {target: [1, 2], velocity: 1, acceleration: 1}\n    - target: [0, 0]\n      duration: 1\n"
                   "      velocity: 2\n",
            2, "t.yaml:8: trajectory.segments[1].velocity: give either velocity (with acceleration) or duration")();
  yamlError(head + "    - {target: [1, 2], duration: 2, acceleration: 1}\n", 2,
            "t.yaml:5: trajectory.segments[0].acceleration: acceleration 1 rad/s^2 is too low to move 2 rad in 2 s")();
  yamlError(head + "    - {target: [1, 2], velocity: 1, acceleration: 1, dwell: -1}\n", 2,
            "trajectory.segments[0].dwell: expected a dwell time in s >= 0")();
  // SI only: no unit switch.
  yamlError("trajectory:\n  type: point_to_point\n  units: deg\n  start: [0, 0]\n", 2,
            "t.yaml:3: trajectory.units: unknown key 'units'")();
  yamlError(
      "trajectory:\n  type: spline\n", 2,
      "t.yaml:2: trajectory.type: expected a trajectory type (point_to_point, fourier, csv, log, kinematic_ptp), got 'spline'")();
  yamlError("trajectory: [1, 2]\n", 2, "t.yaml:1: trajectory: expected a trajectory mapping")();

  const std::string fh = "trajectory:\n  type: fourier\n  base_frequency: 0.1\n  offset: [0, 0]\n";
  yamlError(
      fh + "  a: [[0.1, 0.2], [0.3]]\n  b: [[0, 0], [0, 0]]\n", 2,
      "t.yaml:5: trajectory.a[1]: expected a list of 2 coefficients in rad/s (one per harmonic), got a list of 1 items")();
  yamlError(fh + "  a: [[0.1, 0.2]]\n  b: [[0, 0], [0, 0]]\n", 2,
            "t.yaml:5: trajectory.a: expected a list of 2 rows (one per joint) of coefficients in rad/s")();
  yamlError(fh + "  a: [[0.1, 0.2], [0.3, 0]]\n  b: [[0, 0, 1], [0, 0, 1]]\n", 2,
            "t.yaml:6: trajectory.b[0]: expected a list of 2 coefficients")();
  yamlError(fh + "  harmonics: 3\n  a: [[0.1, 0.2], [0.3, 0]]\n  b: [[0, 0], [0, 0]]\n", 2,
            "t.yaml:6: trajectory.a[0]: expected a list of 3 coefficients")();
  yamlError(fh + "  a: [[0.1], [0.3]]\n  b: [[0], [0]]\n  fade_in: 2\n  duration: 1\n", 2,
            "t.yaml:8: trajectory.duration: expected a duration >= fade_in (2 s), got '1'")();
  yamlError(fh + "  a: [[0.1], [0.3]]\n", 2, "t.yaml:2: trajectory: missing required key 'b'")();

  std::ofstream(tmp / "jointsim_traj_yaml_bad.csv") << "t,q1,q2\n0,1,2\n0.008,x,2\n";
  yamlError("trajectory:\n  type: csv\n  file: jointsim_traj_yaml_bad.csv\n", 2, "t.yaml:3: trajectory.file: ")();
  yamlError("trajectory:\n  type: csv\n  file: jointsim_traj_yaml_bad.csv\n", 2,
            "jointsim_traj_yaml_bad.csv:3:2: column 'q1': expected a number, got 'x'")();
  yamlError("trajectory:\n  type: csv\n  file: log.csv\n  columns: [a]\n", 2,
            "t.yaml:4: trajectory.columns: expected a list of 2 column names")();
  yamlError("trajectory:\n  type: csv\n  file: log.csv\n  gap_factor: 1\n", 2,
            "t.yaml:4: trajectory.gap_factor: expected a factor > 1 (0 disables the gap check), got '1'")();
}
