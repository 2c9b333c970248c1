// A robot log replayed as a trajectory (LoggedTrajectory, `trajectory: {type: log}`): the Hermite interpolation of
// the logged derivatives against polynomials it must reproduce exactly, its derivatives against finite differences,
// the rest hold and the re-anchoring on the logged positions, the measured start, and the errors on bad logs.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/control/trajectory_yaml.hpp"
#include "jointsim/io/yaml.hpp"
#include "test_util.hpp"

using jointsim::InputError;
using jointsim::control::LogColumns;
using jointsim::control::LoggedTrajectory;
using jointsim::test::TempDir;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

// q(t) = 0.3 + 0.2 t − 0.5 t² + 0.4 t³ − 0.15 t⁴ (a quartic: its velocity is a cubic, which the Hermite-corrected
// trapezoid integrates exactly, so the replay must reproduce it to rounding).
double p(double t) { return 0.3 + t * (0.2 + t * (-0.5 + t * (0.4 - 0.15 * t))); }
double pd(double t) { return 0.2 + t * (-1.0 + t * (1.2 - 0.6 * t)); }
double pdd(double t) { return -1.0 + t * (2.4 - 1.8 * t); }

struct Samples {
  std::vector<double> t;
  Eigen::MatrixXd q, qd, qdd;
};

Samples quartic(double t0, double h, int K) {
  Samples s;
  s.q.resize(1, K);
  s.qd.resize(1, K);
  s.qdd.resize(1, K);
  for (int k = 0; k < K; ++k) {
    const double t = t0 + h * k;
    s.t.push_back(t);
    s.q(0, k) = p(t);
    s.qd(0, k) = pd(t);
    s.qdd(0, k) = pdd(t);
  }
  return s;
}

std::filesystem::path writeFile(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(LoggedTrajectory, ReproducesAQuarticWithItsDerivativesBetweenTheSamples) {
  const Samples s = quartic(2.0, 0.008, 200);
  const LoggedTrajectory traj(s.t, s.q, s.qd, s.qdd, 2.0);
  EXPECT_NEAR(traj.duration(), 199 * 0.008, 1e-12);
  Eigen::VectorXd q(1), qd(1), qdd(1);
  for (double t : {0.0, 0.0031, 0.5, 0.777, 1.2345, 1.58}) {
    traj.evaluate(t, q, qd, qdd);
    EXPECT_NEAR(q[0], p(2.0 + t), 1e-12) << t;
    EXPECT_NEAR(qd[0], pd(2.0 + t), 1e-10) << t;
    EXPECT_NEAR(qdd[0], pdd(2.0 + t), 1e-7) << t;
  }
  // After the last sample: hold, at rest (a breakpoint there); before t = 0: rest at q(0).
  traj.evaluate(5.0, q, qd, qdd);
  EXPECT_DOUBLE_EQ(q[0], s.q(0, 199));
  EXPECT_EQ(qd[0], 0.0);
  EXPECT_EQ(traj.breakpoints(), std::vector<double>{traj.duration()});
  traj.evaluate(-1.0, q, qd, qdd);
  EXPECT_NEAR(q[0], p(2.0), 1e-15);
  EXPECT_EQ(qd[0], 0.0);
}

TEST(LoggedTrajectory, DerivativesMatchFiniteDifferencesOnQuantisedData) {
  // A sine logged with positions rounded to 1e-6 rad (as RTDE text logs are) and exact derivatives.
  const int K = 400;
  const double h = 0.008, w = 2.0;
  std::vector<double> t(K);
  Eigen::MatrixXd q(1, K), qd(1, K), qdd(1, K);
  for (int k = 0; k < K; ++k) {
    t[static_cast<size_t>(k)] = h * k;
    q(0, k) = std::round(1e6 * 0.7 * std::sin(w * h * k)) * 1e-6;
    qd(0, k) = 0.7 * w * std::cos(w * h * k);
    qdd(0, k) = -0.7 * w * w * std::sin(w * h * k);
  }
  const LoggedTrajectory traj(t, q, qd, qdd, 0.0);
  Eigen::VectorXd a(1), ad(1), add(1), b(1), bd(1), bdd(1), c(1), cd(1), cdd(1);
  const double e = 1e-6;
  double worst_q = 0.0, worst_qdd = 0.0;
  for (double s = 0.01; s < 3.1; s += 0.0137) {
    traj.evaluate(s, a, ad, add);
    traj.evaluate(s - e, b, bd, bdd);
    traj.evaluate(s + e, c, cd, cdd);
    EXPECT_NEAR(ad[0], (c[0] - b[0]) / (2 * e), 1e-7) << s;
    EXPECT_NEAR(add[0], (cd[0] - bd[0]) / (2 * e), 1e-5) << s;
    worst_q = std::max(worst_q, std::abs(a[0] - 0.7 * std::sin(w * s)));
    worst_qdd = std::max(worst_qdd, std::abs(add[0] + 0.7 * w * w * std::sin(w * s)));
  }
  // Positions from the derivatives: the quantisation does not reach the acceleration (a spline through the rounded
  // positions has errors of order 6 · 0.5e-6 / h² ≈ 0.05 rad/s² there).
  EXPECT_LT(worst_q, 1e-6);
  EXPECT_LT(worst_qdd, 1e-4);
}

TEST(LoggedTrajectory, HoldsOnePositionAtRestAndReanchorsOnTheLog) {
  // Rest with a jittering target (a controller whose target follows the measured position at rest), a move, rest.
  std::vector<double> t;
  std::vector<double> qv, vv, av;
  const double h = 0.01;
  for (int k = 0; k < 10; ++k) {  // rest, target jitter ±2e-5
    t.push_back(h * k);
    qv.push_back(1.0 + ((k % 2) != 0 ? 2e-5 : -2e-5));
    vv.push_back(0.0);
    av.push_back(0.0);
  }
  const double a = 2.0;  // then a constant acceleration from the last rest sample's position
  for (int k = 10; k < 30; ++k) {
    const double dt = h * (k - 9);
    t.push_back(h * k);
    qv.push_back(qv[9] + 0.5 * a * dt * dt);
    vv.push_back(a * dt);
    av.push_back(a);
  }
  Eigen::Map<Eigen::RowVectorXd> Q(qv.data(), static_cast<Eigen::Index>(qv.size()));
  Eigen::Map<Eigen::RowVectorXd> V(vv.data(), static_cast<Eigen::Index>(vv.size()));
  Eigen::Map<Eigen::RowVectorXd> A(av.data(), static_cast<Eigen::Index>(av.size()));
  const LoggedTrajectory hold(t, Q, V, A, 0.0);
  Eigen::VectorXd q(1), qd(1), qdd(1), q2(1);
  for (double s = h; s <= 9 * h; s += 0.0013) {  // after the first interval: the position the move starts from
    hold.evaluate(s, q, qd, qdd);
    EXPECT_DOUBLE_EQ(q[0], qv[9]) << s;
    EXPECT_EQ(qd[0], 0.0);
  }
  // Moving: positions integrated from the logged derivatives from the rest position on. The interval where q̈
  // switches on (0 at 0.09 s, 2 at 0.1 s) is integrated as a linear q̈: a h²/12 short of the log; every later
  // interval is exact.
  hold.evaluate(0.2, q, qd, qdd);
  hold.evaluate(0.15, q2, qd, qdd);
  const double exact = qv[9] + 0.5 * a * (0.2 - 9 * h) * (0.2 - 9 * h),
               exact2 = qv[9] + 0.5 * a * (0.15 - 9 * h) * (0.15 - 9 * h);
  EXPECT_NEAR(q[0] - q2[0], exact - exact2, 1e-12);
  EXPECT_NEAR(q[0], exact - a * h * h / 12.0, 1e-12);
  EXPECT_NEAR(qd[0], a * (0.15 - 9 * h), 1e-12);
  const LoggedTrajectory follow(t, Q, V, A, 0.0, "log", false);
  follow.evaluate(5 * h, q, qd, qdd);
  EXPECT_DOUBLE_EQ(q[0], qv[5]);  // the logged (jittering) target
}

TEST(LoggedTrajectory, CsvWithPatternsMeasuredStartAndUrRtdeNames) {
  const TempDir tmp;
  std::ostringstream text;
  text << "t_s,q_target_1,q_target_2,qd_target_1,qd_target_2,qdd_target_1,qdd_target_2,q_actual_1,q_actual_2\n";
  text.precision(17);
  for (int k = 0; k < 50; ++k) {
    const double t = 0.008 * k;
    text << t << "," << p(t) << "," << -p(t) << "," << pd(t) << "," << -pd(t) << "," << pdd(t) << "," << -pdd(t) << ","
         << p(t) + 1e-3 << "," << -p(t) - 2e-3 << "\n";
  }
  const auto path = writeFile(tmp, "log.csv", text.str());
  LogColumns c;
  c.time = "t_s";
  c.q = LogColumns::expand("q_target_{j}", 2, "q");
  c.qd = LogColumns::expand("qd_target_{j}", 2, "qd");
  c.qdd = LogColumns::expand("qdd_target_{j}", 2, "qdd");
  c.q_measured = LogColumns::expand("q_actual_{j}", 2, "q_measured");
  const auto traj = LoggedTrajectory::fromCsv(path.string(), 2, c, 0.1);
  EXPECT_DOUBLE_EQ(traj.startTime(), 0.1);
  Eigen::VectorXd q(2), qd(2), qdd(2), q0(2);
  traj.evaluate(0.05, q, qd, qdd);
  EXPECT_NEAR(q[0], p(0.15), 1e-12);
  EXPECT_NEAR(q[1], -p(0.15), 1e-12);
  EXPECT_NEAR(qdd[1], -pdd(0.15), 1e-8);
  ASSERT_TRUE(traj.startPositions(q0));
  EXPECT_NEAR(q0[0], p(0.1) + 1e-3, 1e-5);  // measured, linear between the samples around 0.1 s
  EXPECT_NEAR(q0[1], -p(0.1) - 2e-3, 1e-5);

  const LogColumns rtde = LogColumns::urRtde(6);
  EXPECT_EQ(rtde.time, "timestamp");
  EXPECT_EQ(rtde.q.front(), "target_q_0");
  EXPECT_EQ(rtde.qdd.back(), "target_qdd_5");
  EXPECT_EQ(rtde.q_measured[2], "actual_q_2");
  EXPECT_THAT([] { LogColumns::expand("q_target", 2, "columns.q"); },
              ThrowsMessage<InputError>(HasSubstr("columns.q: expected a column-name pattern with {j}")));
}

TEST(LoggedTrajectory, BadLogsGiveOneLineErrorsNamingFileRowAndColumn) {
  const TempDir tmp;
  LogColumns c;
  c.time = "t";
  c.q = {"q1"};
  c.qd = {"v1"};
  c.qdd = {"a1"};
  auto load = [&](const std::string& name, const std::string& text) {
    return [&tmp, &c, name, text] { LoggedTrajectory::fromCsv(writeFile(tmp, name, text).string(), 1, c); };
  };
  EXPECT_THAT(load("missing.csv", "t,q1,v1\n0,0,0\n0.008,0,0\n"),
              ThrowsMessage<InputError>(HasSubstr("missing.csv:1: missing column 'a1'")));
  EXPECT_THAT(load("nan.csv", "t,q1,v1,a1\n0,0,0,0\n0.008,0,nan,0\n"),
              ThrowsMessage<InputError>(HasSubstr("nan.csv:3:3: column 'v1'")));
  EXPECT_THAT(load("back.csv", "t,q1,v1,a1\n0,0,0,0\n0.008,0,0,0\n0.004,0,0,0\n"),
              ThrowsMessage<InputError>(HasSubstr("back.csv:4:1: column 't': time 0.004 s is not after")));
  std::string gap = "t,q1,v1,a1\n";
  for (int k = 0; k < 20; ++k) gap += std::to_string(k < 12 ? 0.008 * k : 0.008 * k + 0.1) + ",0,0,0\n";
  EXPECT_THAT(load("gap.csv", gap),
              ThrowsMessage<InputError>(HasSubstr("gap.csv:14:1: column 't': time step 0.108 s is more than 3x")));
  EXPECT_THAT([&] { LoggedTrajectory::fromCsv(writeFile(tmp, "ok.csv", gap).string(), 1, c, 99.0, 0.0); },
              ThrowsMessage<InputError>(HasSubstr("ok.csv: start time 99 s is outside the log's times")));
}

TEST(LoggedTrajectory, FromYamlWithErrorsAtTheirLine) {
  const TempDir tmp;
  std::ostringstream text;
  text << "timestamp";
  for (const char* w : {"target_q_", "target_qd_", "target_qdd_", "actual_q_"})
    for (int i = 0; i < 2; ++i) text << "," << w << i;
  text << "\n";
  for (int k = 0; k < 30; ++k) {
    const double t = 0.002 * k;
    text << t << "," << p(t) << "," << p(t) << "," << pd(t) << "," << pd(t) << "," << pdd(t) << "," << pdd(t) << ","
         << p(t) << "," << p(t) << "\n";
  }
  writeFile(tmp, "rtde.csv", text.str());
  auto yaml = [&](const std::string& body) {
    const auto doc = jointsim::io::YamlValue::loadString("trajectory:\n  type: log\n" + body, "t.yaml");
    return jointsim::control::trajectoryFromYaml(doc["trajectory"], 2, tmp.path().string());
  };
  const auto traj = yaml("  file: rtde.csv\n  format: ur_rtde\n");
  EXPECT_THAT(traj->describe(), HasSubstr("rtde.csv, 2 joints, 30 samples, quintic Hermite"));
  EXPECT_NEAR(traj->setpoint(0.0301).qd[1], pd(0.0301), 1e-6);
  // The columns override the preset: without accelerations, the cubic Hermite with a breakpoint per sample.
  const auto cubic = yaml("  file: rtde.csv\n  format: ur_rtde\n  columns:\n    qdd: []\n");
  EXPECT_EQ(cubic->breakpoints().size(), 29u);
  EXPECT_THAT([&] { yaml("  file: rtde.csv\n  format: urscript\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml:4: trajectory.format: expected a log format: ur_rtde")));
  EXPECT_THAT([&] { yaml("  file: rtde.csv\n  columns:\n    q: target_q\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml:5: trajectory.columns.q: expected a column-name pattern")));
  EXPECT_THAT([&] { yaml("  file: rtde.csv\n  format: ur_rtde\n  start_time: 5\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml:5: trajectory.start_time: ")));
  EXPECT_THAT([&] { yaml("  file: rtde.csv\n  columns:\n    q: target_q_{i}\n    qd: nope_{i}\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml:3: trajectory.file: ")));
  EXPECT_THAT([&] { yaml("  file: rtde.csv\n  format: ur_rtde\n  rest_speed: -1e-4\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml:5: trajectory.rest_speed: expected a speed >= 0 rad/s")));
}

TEST(LoggedTrajectory, SlowTailsBelowTheRestSpeedAreRests) {
  // An exact rest, a move v = V sin²(π u) over T = 0.2 s, then a controller's slow deceleration tail (3e-5 rad/s
  // held for 0.3 s: the target creeps by 9e-6 rad), then an exact rest. With the default rest speed (1e-4 rad/s)
  // the tail is part of the rest: held on the position the next move would start from (the last one), q̇ = 0; with
  // rest speed 0 the tail is replayed as a move.
  const double h = 0.01, t0 = 0.1, T = 0.2, V = 0.5, creep = 3e-5, pi = std::acos(-1.0);
  std::vector<double> t, qv, vv, av;
  double q = 0.4;
  for (int k = 0; k <= 80; ++k) {
    const double s = h * k;
    t.push_back(s);
    const double u = (s - t0) / T;
    const bool moving = u > 1e-12 && u < 1.0 - 1e-12;
    const bool tail = s > t0 + T + 1e-12 && s < 0.6 - 1e-12;
    if (k > 0) {
      const double prev = t[static_cast<size_t>(k - 1)], ua = std::clamp((prev - t0) / T, 0.0, 1.0),
                   ub = std::clamp(u, 0.0, 1.0);
      q += V * T * ((ub - ua) / 2 - (std::sin(2 * pi * ub) - std::sin(2 * pi * ua)) / (4 * pi));
      q += creep * std::max(0.0, std::min(s, 0.6) - std::max(prev, t0 + T));
    }
    qv.push_back(q);
    vv.push_back(moving ? V * std::sin(pi * u) * std::sin(pi * u) : tail ? creep : 0.0);
    av.push_back(moving ? V * pi / T * std::sin(2 * pi * u) : 0.0);
  }
  const auto K = static_cast<Eigen::Index>(t.size());
  const Eigen::Map<Eigen::RowVectorXd> Q(qv.data(), K), Vq(vv.data(), K), A(av.data(), K);
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::VectorXd x(1), xd(1), xdd(1);

  const LoggedTrajectory held(t, Q, Vq, A, 0.0);  // the default rest speed
  const auto rests = held.rests();
  ASSERT_EQ(rests.size(), 1u);
  ASSERT_EQ(rests[0].size(), 2u);
  EXPECT_EQ(rests[0][0].first, -inf);  // resting since before t = 0, until the move starts
  EXPECT_NEAR(rests[0][0].second, t0, 1e-12);
  EXPECT_NEAR(rests[0][1].first, t0 + T, 1e-12);  // the tail and the rest after it: one rest
  EXPECT_EQ(rests[0][1].second, inf);
  for (double s : {0.35, 0.45, 0.7}) {
    held.evaluate(s, x, xd, xdd);
    EXPECT_DOUBLE_EQ(x[0], qv.back()) << s;
    EXPECT_EQ(xd[0], 0.0) << s;
  }
  const LoggedTrajectory exact(t, Q, Vq, A, 0.0, "log", true, 0.0);  // only exact zeros rest
  const auto r0 = exact.rests();
  ASSERT_EQ(r0[0].size(), 3u);  // before the move, the one sample between the move and the tail, after the tail
  EXPECT_NEAR(r0[0][1].first, t0 + T, 1e-12);
  EXPECT_NEAR(r0[0][1].second, t0 + T, 1e-12);
  EXPECT_NEAR(r0[0][2].first, 0.6, 1e-12);
  exact.evaluate(0.45, x, xd, xdd);
  EXPECT_NEAR(xd[0], creep, 0.1 * creep);  // (plus the drift blending the tail's first half-interval in)
  // Starting the replay in the middle of the move (log time 0.25 s) or of the tail (0.35 s) shifts the rests.
  const auto r1 = LoggedTrajectory(t, Q, Vq, A, 0.25).rests();
  ASSERT_EQ(r1[0].size(), 1u);
  EXPECT_NEAR(r1[0][0].first, t0 + T - 0.25, 1e-12);
  const auto r2 = LoggedTrajectory(t, Q, Vq, A, 0.35).rests();
  ASSERT_EQ(r2[0].size(), 1u);
  EXPECT_EQ(r2[0][0].first, -inf);
  EXPECT_EQ(r2[0][0].second, inf);
  // Positions taken as logged: no held rests to report.
  EXPECT_TRUE(LoggedTrajectory(t, Q, Vq, A, 0.0, "log", false).rests().empty());
  EXPECT_THROW(LoggedTrajectory(t, Q, Vq, A, 0.0, "log", true, -1.0), InputError);
}

TEST(LoggedTrajectory, AMoveMeetsTheNextRestsPositionSmoothly) {
  // Rest, a move v(t) = V sin²(π (t − t0)/T) over T = 0.5 s, then a rest whose logged target is 3e-4 rad off the
  // move's end (the target set to the measured position at rest): the replay must reach that held position with
  // q, q̇, q̈ continuous (a C² blend of the mismatch over the move), not by a jump at rest.
  const double h = 0.01, t0 = 0.05, T = 0.5, V = 0.8, pi = std::acos(-1.0), offset = 3e-4;
  std::vector<double> t, qv, vv, av;
  for (int k = 0; k <= 100; ++k) {
    const double s = h * k;
    t.push_back(s);
    const double u = std::clamp((s - t0) / T, 0.0, 1.0);
    const bool moving = s > t0 + 1e-12 && s < t0 + T - 1e-12;
    const double q = 0.2 + V * (s < t0 ? 0.0 : (std::min(s, t0 + T) - t0) / 2 - T * std::sin(2 * pi * u) / (4 * pi));
    qv.push_back(s >= t0 + T - 1e-12 ? q + offset : q);
    vv.push_back(moving ? V * std::sin(pi * u) * std::sin(pi * u) : 0.0);
    av.push_back(moving ? V * pi / T * std::sin(2 * pi * u) : 0.0);
  }
  const auto K = static_cast<Eigen::Index>(t.size());
  const LoggedTrajectory traj(t, Eigen::Map<Eigen::RowVectorXd>(qv.data(), K),
                              Eigen::Map<Eigen::RowVectorXd>(vv.data(), K),
                              Eigen::Map<Eigen::RowVectorXd>(av.data(), K), 0.0);
  Eigen::VectorXd q(1), qd(1), qdd(1), a(1), ad(1), add(1), b(1), bd(1), bdd(1);
  traj.evaluate(0.8, q, qd, qdd);
  EXPECT_DOUBLE_EQ(q[0], qv.back());  // at rest on the logged position
  EXPECT_EQ(qd[0], 0.0);
  const double e = 1e-7;
  double worst_dqdd = 0.0;
  for (double s = 0.001; s < 0.99; s += 0.0037) {
    traj.evaluate(s, q, qd, qdd);
    traj.evaluate(s - e, a, ad, add);
    traj.evaluate(s + e, b, bd, bdd);
    EXPECT_NEAR(qd[0], (b[0] - a[0]) / (2 * e), 1e-6) << s;
    EXPECT_NEAR(qdd[0], (bd[0] - ad[0]) / (2 * e), 1e-4) << s;
    const double u = std::clamp((s - t0) / T, 0.0, 1.0);
    worst_dqdd = std::max(worst_dqdd, std::abs(qdd[0] - V * pi / T * std::sin(2 * pi * u)));
  }
  for (double s : {t0 + T - 1e-9, t0 + T + 1e-9}) {  // the move's end: q̇ and q̈ continuous into the rest
    traj.evaluate(s, q, qd, qdd);
    EXPECT_NEAR(qd[0], 0.0, 1e-6) << s;
    EXPECT_NEAR(qdd[0], 0.0, 1e-3) << s;
  }
  // The blend adds at most max|w''| E/T² = 5.77 · 3e-4 / 0.25 ≈ 7e-3 rad/s² (plus the interpolation error).
  EXPECT_LT(worst_dqdd, 5.78 * offset / (T * T) + 0.02);
}
