// KinematicPtpTrajectory ([MSL, Blocks.Sources.KinematicPTP2]): the FullRobot and OneAxis profiles (derived
// timings, docs/validation.md), derivatives, continuity, limits, degenerate and zero-distance axes, start time
// offset, YAML.
#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/kinematic_ptp.hpp"
#include "jointsim/control/trajectory_yaml.hpp"
#include "test_util.hpp"

using jointsim::InputError;
using jointsim::control::JointTrajectory;
using jointsim::control::KinematicPtpTrajectory;
using jointsim::test::MatricesNear;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out[i++] = x;
  return out;
}

/// [MSL, RobotR3.FullRobot]: FullRobot reference motion.
KinematicPtpTrajectory fullRobot(double start_time = 0.0) {
  return KinematicPtpTrajectory(vec({-60 * kDeg, 20 * kDeg, 90 * kDeg, 0, -110 * kDeg, 0}),
                                vec({60 * kDeg, -70 * kDeg, -35 * kDeg, 45 * kDeg, 110 * kDeg, 45 * kDeg}),
                                vec({3, 1.5, 5, 3.1, 3.1, 4.1}), vec({15, 15, 15, 60, 60, 60}), start_time);
}

/// [MSL, RobotR3.OneAxis]: OneAxis, 0° → 120°, 3 rad/s, 10 rad/s².
KinematicPtpTrajectory oneAxis() { return KinematicPtpTrajectory(vec({0}), vec({120 * kDeg}), vec({3}), vec({10})); }

/// A triangular (no constant-velocity phase) 3-axis move with a start offset and one zero-distance axis.
KinematicPtpTrajectory triangular() {
  return KinematicPtpTrajectory(vec({0.2, -0.5, 1.0}), vec({0.5, 0.3, 1.0}), vec({10, 10, 1}), vec({2, 4, 1}), 0.25);
}

/// Central differences of q (against qd) and qd (against qdd), skipping points near breakpoints.
void expectDerivativesMatch(const JointTrajectory& traj, double tol) {
  const double h = 1e-6;
  const auto bps = traj.breakpoints();
  const double T = traj.duration() + 0.2;
  for (int k = 0; k < 997; ++k) {
    const double t = -0.1 + (T + 0.1) * (k + 0.5) / 997;
    bool near = std::abs(t) < 3 * h;
    for (double b : bps) near = near || std::abs(t - b) < 3 * h;
    if (near) continue;
    const auto p = traj.setpoint(t + h), m = traj.setpoint(t - h), c = traj.setpoint(t);
    EXPECT_TRUE(MatricesNear(c.qd, (p.q - m.q) / (2 * h), tol)) << "qd at t = " << t;
    EXPECT_TRUE(MatricesNear(c.qdd, (p.qd - m.qd) / (2 * h), tol)) << "qdd at t = " << t;
  }
}

/// q and qd continuous across every breakpoint (left limit vs value at the breakpoint).
void expectContinuous(const JointTrajectory& traj) {
  for (double b : traj.breakpoints()) {
    const auto l = traj.setpoint(std::nextafter(b, -1.0)), r = traj.setpoint(b);
    EXPECT_TRUE(MatricesNear(l.q, r.q, 1e-12)) << "q at breakpoint " << b;
    EXPECT_TRUE(MatricesNear(l.qd, r.qd, 1e-12)) << "qd at breakpoint " << b;
  }
}

/// |qd_i| <= qd_max_i, |qdd_i| <= qdd_max_i on a dense grid and at the breakpoints.
void expectLimitsRespected(const KinematicPtpTrajectory& traj) {
  std::vector<double> times = traj.breakpoints();
  for (int k = 0; k <= 5000; ++k) times.push_back(traj.duration() * k / 5000.0);
  for (double t : times) {
    const auto sp = traj.setpoint(t);
    for (int i = 0; i < traj.dof(); ++i) {
      EXPECT_LE(std::abs(sp.qd[i]), traj.qdMax()[i] * (1 + 1e-14)) << "axis " << i << " t = " << t;
      EXPECT_LE(std::abs(sp.qdd[i]), traj.qddMax()[i] * (1 + 1e-14)) << "axis " << i << " t = " << t;
    }
  }
}

}  // namespace

// ------------------------------------------------------------------------- derived timings (docs/validation.md)

TEST(KinematicPtp, FullRobotTimingMatchesRobotR3Section45) {
  const auto p = fullRobot();
  EXPECT_EQ(p.dof(), 6);
  EXPECT_FALSE(p.degenerate());
  EXPECT_FALSE(p.triangular());                // trapezoidal
  EXPECT_EQ(p.speedLimitingAxis(), 4);         // axis 5
  EXPECT_EQ(p.accelerationLimitingAxis(), 2);  // axis 3
  EXPECT_NEAR(p.speedRatioMax(), 1.2386207595, 1e-9);
  EXPECT_NEAR(p.accelerationRatioMax(), 0.1454441043, 1e-9);
  EXPECT_NEAR(p.pathSpeed(), 0.8073496204, 1e-9);
  EXPECT_NEAR(p.pathAcceleration(), 6.8754935416, 1e-9);
  EXPECT_NEAR(p.Ta1(), 0.3813713470, 1e-9);
  EXPECT_NEAR(p.Ta2(), 31.0 / 264.0, 1e-15);
  EXPECT_NEAR(p.Ta2(), 0.1174242424, 1e-9);
  EXPECT_NEAR(p.Tv(), 1.2386207595, 1e-9);
  EXPECT_NEAR(p.Te(), 1.3560450019, 1e-9);
  EXPECT_NEAR(p.endTime(), 1.3560450019, 1e-9);
  EXPECT_DOUBLE_EQ(p.duration(), p.endTime());
  EXPECT_NEAR(p.terminationTime(0.5), 1.8560450019, 1e-9);
  EXPECT_LT(p.terminationTime(0.5), 2.0);  // stop time 2 s not reached
  EXPECT_EQ(p.describe(), "kinematic_ptp(6 joints, trapezoidal, start 0 s, end 1.35605 s)");
  // Breakpoints: end of acceleration, start of deceleration, end.
  const auto b = p.breakpoints();
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b[0], p.Ta2());
  EXPECT_DOUBLE_EQ(b[1], p.Tv());
  EXPECT_DOUBLE_EQ(b[2], p.Te());
}

TEST(KinematicPtp, FullRobotPeakSpeedsAndAccelerationsMatchRobotR3Section45) {
  const auto p = fullRobot();
  const double peak_speed[] = {1.690909, 1.268182, 1.761364, 0.634091, 3.1, 0.634091};
  const double peak_accel[] = {14.4, 10.8, 15.0, 5.4, 26.4, 5.4};
  const auto cruise = p.setpoint(0.5 * (p.Ta2() + p.Tv()));  // constant-velocity phase
  const auto start = p.setpoint(0.0);                        // accelerating already at t = 0
  const auto decel = p.setpoint(0.5 * (p.Tv() + p.Te()));
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(std::abs(cruise.qd[i]), peak_speed[i], 5e-7) << "axis " << i + 1;
    EXPECT_NEAR(std::abs(start.qdd[i]), peak_accel[i], 1e-12) << "axis " << i + 1;
    EXPECT_NEAR(std::abs(decel.qdd[i]), peak_accel[i], 1e-12) << "axis " << i + 1;
    EXPECT_EQ(start.qd[i], 0.0);
    EXPECT_EQ(start.q[i], p.qBegin()[i]);
    // Acceleration then deceleration: same sign as Δ, then opposite.
    EXPECT_GT(start.qdd[i] * p.delta()[i], 0.0);
    EXPECT_LT(decel.qdd[i] * p.delta()[i], 0.0);
    EXPECT_EQ(cruise.qdd[i], 0.0);
  }
  // Axis 5 is exactly at its speed limit, axis 3 exactly at its acceleration limit.
  EXPECT_NEAR(std::abs(cruise.qd[4]), 3.1, 1e-14);
  EXPECT_NEAR(std::abs(start.qdd[2]), 15.0, 1e-13);
  // All axes arrive together and hold.
  for (double t : {p.endTime(), p.endTime() + 0.1, p.terminationTime(0.5), 10.0}) {
    const auto e = p.setpoint(t);
    EXPECT_TRUE(MatricesNear(e.q, p.qEnd(), 1e-14)) << t;
    EXPECT_TRUE((e.qd.array() == 0.0).all()) << t;
    EXPECT_TRUE((e.qdd.array() == 0.0).all()) << t;
  }
  const auto before_end = p.setpoint(std::nextafter(p.endTime(), 0.0));
  EXPECT_TRUE(MatricesNear(before_end.q, p.qEnd(), 1e-14));
  EXPECT_TRUE(MatricesNear(before_end.qd, Eigen::VectorXd::Zero(6), 1e-13));
  EXPECT_TRUE(MatricesNear(before_end.qdd, -p.delta() * p.pathAcceleration(), 1e-14));
}

TEST(KinematicPtp, OneAxisTimingMatchesRobotR3Section45) {
  const auto p = oneAxis();
  EXPECT_FALSE(p.triangular());
  EXPECT_NEAR(p.delta()[0], 2.0943951024, 1e-10);
  EXPECT_NEAR(p.pathSpeed(), 1.4323944878, 1e-9);
  EXPECT_NEAR(p.pathAcceleration(), 4.7746482928, 1e-9);
  EXPECT_NEAR(p.Ta1(), 0.4576456164, 1e-9);
  EXPECT_NEAR(p.Ta2(), 0.3, 1e-15);
  EXPECT_NEAR(p.Tv(), 0.6981317008, 1e-9);
  EXPECT_NEAR(p.Te(), 0.9981317008, 1e-9);
  EXPECT_NEAR(p.endTime(), 0.9981317008, 1e-9);
  EXPECT_NEAR(p.terminationTime(0.5), 1.4981317008, 1e-9);
  EXPECT_LT(p.terminationTime(0.5), 1.6);
  // The single axis is at both of its limits.
  EXPECT_NEAR(p.setpoint(0.5).qd[0], 3.0, 1e-14);
  EXPECT_NEAR(p.setpoint(0.1).qdd[0], 10.0, 1e-14);
  EXPECT_NEAR(p.setpoint(0.9).qdd[0], -10.0, 1e-14);
  // Closed-form values: s(Ta2) = A·Ta2²/2 → q = 10·0.3²/2 = 0.45 rad.
  EXPECT_NEAR(p.setpoint(0.3).q[0], 0.45, 1e-14);
  EXPECT_NEAR(p.setpoint(2.0).q[0], 120 * kDeg, 1e-15);
  EXPECT_TRUE(p.moving(0, 0.0));
  EXPECT_TRUE(p.moving(0, std::nextafter(p.endTime(), 0.0)));
  EXPECT_FALSE(p.moving(0, p.endTime()));
}

// ------------------------------------------------------------------------------------------ semantics

TEST(KinematicPtp, PathFollowsTheMslBranchFormulas) {
  // Independent evaluation of the [MSL, Blocks.Sources.KinematicPTP2] equations at random times (τ-based, trapezoidal).
  const auto p = fullRobot(0.3);
  const double A = p.pathAcceleration(), V = p.pathSpeed(), Ta2 = p.Ta2(), Tv = p.Tv(), Te = p.Te();
  const double s1 = A * Ta2 * Ta2 / 2, s2 = s1 + V * (Tv - Ta2);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> dist(-0.5, 2.5);
  for (int k = 0; k < 500; ++k) {
    const double t = dist(rng), tau = t - 0.3;
    double s, sd, sdd, es, esd, esdd;
    p.evaluatePath(t, s, sd, sdd);
    if (tau < 0) {
      es = esd = esdd = 0;
    } else if (tau < Ta2) {
      es = A * tau * tau / 2, esd = A * tau, esdd = A;
    } else if (tau < Tv) {
      es = s1 + V * (tau - Ta2), esd = V, esdd = 0;
    } else if (tau < Te) {
      es = s2 + V * (tau - Tv) - A * (tau - Tv) * (tau - Tv) / 2, esd = V - A * (tau - Tv), esdd = -A;
    } else {
      es = 1, esd = 0, esdd = 0;
    }
    EXPECT_NEAR(s, es, 1e-14) << t;
    EXPECT_NEAR(sd, esd, 1e-13) << t;
    EXPECT_NEAR(sdd, esdd, 1e-13) << t;
  }
}

TEST(KinematicPtp, StartTimeShiftsTheProfile) {
  const auto a = fullRobot(0.0), b = fullRobot(0.7);
  EXPECT_NEAR(b.endTime(), a.endTime() + 0.7, 1e-15);
  EXPECT_DOUBLE_EQ(b.duration(), b.endTime());
  const auto bp = b.breakpoints();
  ASSERT_EQ(bp.size(), 4u);
  EXPECT_EQ(bp[0], 0.7);
  // Rests at q_begin before the start; at the start instant the acceleration phase has begun.
  for (double t : {-1.0, 0.0, 0.3, std::nextafter(0.7, 0.0)}) {
    const auto sp = b.setpoint(t);
    EXPECT_TRUE((sp.q.array() == b.qBegin().array()).all()) << t;
    EXPECT_TRUE((sp.qd.array() == 0.0).all()) << t;
    EXPECT_TRUE((sp.qdd.array() == 0.0).all()) << t;
  }
  EXPECT_TRUE(MatricesNear(b.setpoint(0.7).qdd, a.setpoint(0.0).qdd, 1e-15));
  for (double t : {0.05, 0.4, 1.0, 1.3, 1.5}) {
    const auto x = a.setpoint(t), y = b.setpoint(t + 0.7);
    EXPECT_TRUE(MatricesNear(y.q, x.q, 1e-12)) << t;
    EXPECT_TRUE(MatricesNear(y.qd, x.qd, 1e-12)) << t;
    EXPECT_TRUE(MatricesNear(y.qdd, x.qdd, 1e-12)) << t;
  }
  EXPECT_NEAR(b.terminationTime(0.5), a.endTime() + 1.2, 1e-14);
}

TEST(KinematicPtp, TriangularProfile) {
  const auto p = triangular();
  // Δ = (0.3, 0.8, 0): speed ratio max 0.08 (axis 2), accel ratio max 0.2 (axis 2)
  // → V = 12.5, A = 5, Ta1 = sqrt(0.2), Ta2 = 2.5 ≥ Ta1 → triangular, Te = 2 sqrt(0.2).
  EXPECT_TRUE(p.triangular());
  EXPECT_EQ(p.speedLimitingAxis(), 1);
  EXPECT_EQ(p.accelerationLimitingAxis(), 1);
  EXPECT_NEAR(p.pathAcceleration(), 5.0, 1e-15);
  EXPECT_NEAR(p.Ta1(), std::sqrt(0.2), 1e-15);
  EXPECT_NEAR(p.Tv(), p.Ta1(), 0.0);
  EXPECT_NEAR(p.Te(), 2 * std::sqrt(0.2), 1e-15);
  EXPECT_NEAR(p.endTime(), 0.25 + 2 * std::sqrt(0.2), 1e-15);
  EXPECT_NEAR(p.peakPathSpeed(), 5 * std::sqrt(0.2), 1e-14);
  const auto b = p.breakpoints();
  ASSERT_EQ(b.size(), 3u);  // start, switch, end (Tv = Ta1 not repeated)
  EXPECT_EQ(b[0], 0.25);
  EXPECT_NEAR(b[1], 0.25 + std::sqrt(0.2), 1e-15);
  EXPECT_EQ(b[2], p.endTime());
  const auto peak = p.setpoint(b[1]);
  EXPECT_NEAR(peak.qd[1], 0.8 * 5 * std::sqrt(0.2), 1e-14);  // below the 10 rad/s limit
  EXPECT_NEAR(peak.q[1], -0.5 + 0.4, 1e-14);                 // half way
  EXPECT_NEAR(peak.qdd[1], -4.0, 1e-14);                     // deceleration starts at the switch
  EXPECT_NEAR(p.setpoint(5.0).q[1], 0.3, 1e-15);
  EXPECT_EQ(p.describe(), "kinematic_ptp(3 joints, triangular, start 0.25 s, end 1.14443 s)");
}

TEST(KinematicPtp, DerivativesMatchFiniteDifferences) {
  expectDerivativesMatch(fullRobot(), 1e-6);
  expectDerivativesMatch(fullRobot(0.4), 1e-6);
  expectDerivativesMatch(oneAxis(), 1e-6);
  expectDerivativesMatch(triangular(), 1e-6);
}

TEST(KinematicPtp, PositionAndVelocityAreContinuous) {
  expectContinuous(fullRobot());
  expectContinuous(fullRobot(0.4));
  expectContinuous(oneAxis());
  expectContinuous(triangular());
  // Also at t = 0 for a motion that starts there (from rest).
  const auto p = fullRobot();
  EXPECT_TRUE(MatricesNear(p.setpoint(-1e-300).q, p.setpoint(0.0).q, 0.0));
  EXPECT_TRUE(MatricesNear(p.setpoint(-1e-300).qd, p.setpoint(0.0).qd, 0.0));
}

TEST(KinematicPtp, LimitsRespected) {
  expectLimitsRespected(fullRobot());
  expectLimitsRespected(oneAxis());
  expectLimitsRespected(triangular());
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> q(-3, 3), lim(0.2, 20);
  for (int k = 0; k < 30; ++k) {
    Eigen::VectorXd qb(4), qe(4), v(4), a(4);
    for (int i = 0; i < 4; ++i) qb[i] = q(rng), qe[i] = q(rng), v[i] = lim(rng), a[i] = lim(rng);
    const KinematicPtpTrajectory p(qb, qe, v, a, 0.1);
    expectLimitsRespected(p);
    // One axis is at its acceleration limit; in the trapezoidal case one axis is at its speed limit.
    const auto acc = p.setpoint(0.1);
    EXPECT_NEAR((acc.qdd.array().abs() / a.array()).maxCoeff(), 1.0, 1e-13);
    if (!p.triangular()) {
      const auto c = p.setpoint(0.1 + 0.5 * (p.Ta2() + p.Tv()));
      EXPECT_NEAR((c.qd.array().abs() / v.array()).maxCoeff(), 1.0, 1e-13);
    }
    EXPECT_TRUE(MatricesNear(p.setpoint(p.endTime()).q, qe, 1e-13));
  }
}

TEST(KinematicPtp, ZeroDistanceAxesStayAtRest) {
  const auto p = triangular();  // axis 3: q_begin = q_end = 1.0
  for (int k = -10; k <= 200; ++k) {
    const double t = 0.01 * k;
    const auto sp = p.setpoint(t);
    EXPECT_EQ(sp.q[2], 1.0);
    EXPECT_EQ(sp.qd[2], 0.0);
    EXPECT_EQ(sp.qdd[2], 0.0);
    EXPECT_FALSE(p.moving(2, t));
    EXPECT_EQ(p.moving(1, t), t < p.endTime());
  }
}

TEST(KinematicPtp, DegenerateMotionEndsAtTimeZero) {
  // All distances zero: s ≡ 0 and endTime = 0 even with a start time (MSL: Tes = 0).
  const KinematicPtpTrajectory p(vec({0.5, -1.0}), vec({0.5, -1.0}), vec({1, 1}), vec({1, 1}), 0.8);
  EXPECT_TRUE(p.degenerate());
  EXPECT_EQ(p.endTime(), 0.0);
  EXPECT_EQ(p.duration(), 0.0);
  EXPECT_EQ(p.terminationTime(0.5), 0.5);
  EXPECT_TRUE(p.breakpoints().empty());
  EXPECT_EQ(p.describe(), "kinematic_ptp(2 joints, no motion, start 0.8 s, end 0 s)");
  for (double t : {-1.0, 0.0, 0.8, 2.0}) {
    const auto sp = p.setpoint(t);
    EXPECT_TRUE((sp.q.array() == p.qBegin().array()).all());
    EXPECT_TRUE((sp.qd.array() == 0.0).all() && (sp.qdd.array() == 0.0).all());
    EXPECT_FALSE(p.moving(0, t));
  }
  // Below ε = 1e-14 the motion is suppressed entirely (q stays at q_begin) ...
  const KinematicPtpTrajectory tiny(vec({0.0}), vec({5e-15}), vec({0.5}), vec({1}));
  EXPECT_TRUE(tiny.degenerate());
  EXPECT_EQ(tiny.setpoint(1.0).q[0], 0.0);
  // ... above it the motion is planned normally.
  const KinematicPtpTrajectory small(vec({0.0}), vec({1e-13}), vec({1}), vec({1}));
  EXPECT_FALSE(small.degenerate());
  EXPECT_NEAR(small.setpoint(1.0).q[0], 1e-13, 1e-28);
}

TEST(KinematicPtp, ScalarParametersAreBroadcastAndBadInputRejected) {
  const KinematicPtpTrajectory p(vec({0.0}), vec({1, 2, -3}), vec({2}), vec({4}));
  EXPECT_EQ(p.dof(), 3);
  EXPECT_EQ(p.qBegin(), Eigen::VectorXd::Zero(3));
  EXPECT_EQ(p.qdMax(), Eigen::VectorXd::Constant(3, 2.0));
  EXPECT_EQ(p.accelerationLimitingAxis(), 2);
  EXPECT_THAT(
      [] {
        KinematicPtpTrajectory(vec({0, 0}), vec({1, 2, 3}), vec({1}), vec({1}));
      },
      ThrowsMessage<InputError>(HasSubstr("q_begin has 2 entries, expected 3 (or 1)")));
  EXPECT_THAT([] { KinematicPtpTrajectory(vec({0}), vec({1}), vec({0}), vec({1})); },
              ThrowsMessage<InputError>(HasSubstr("qd_max of axis 1 must be > 0 rad/s")));
  EXPECT_THAT([] { KinematicPtpTrajectory(vec({0}), vec({1}), vec({1}), vec({-2})); },
              ThrowsMessage<InputError>(HasSubstr("qdd_max of axis 1 must be > 0 rad/s^2")));
  EXPECT_THAT([] { KinematicPtpTrajectory(vec({0}), vec({NAN}), vec({1}), vec({1})); },
              ThrowsMessage<InputError>(HasSubstr("must be finite")));
  EXPECT_THAT([] { KinematicPtpTrajectory(vec({0}), vec({1}), vec({1}), vec({1}), -0.1); },
              ThrowsMessage<InputError>(HasSubstr("start_time must be >= 0 s")));
}

// ------------------------------------------------------------------------------------------ YAML

namespace {
std::unique_ptr<JointTrajectory> fromYaml(const std::string& text, int dof) {
  const auto doc = jointsim::io::YamlValue::loadString(text, "t.yaml");
  return jointsim::control::trajectoryFromYaml(doc["trajectory"], dof, ".");
}
}  // namespace

TEST(KinematicPtpYaml, OneAxisFromYaml) {
  const auto traj = fromYaml(R"(trajectory:
  type: kinematic_ptp
  q_begin: [0]
  q_end: [2.0943951023931953]
  qd_max: [3]
  qdd_max: [10]
)",
                             1);
  const auto* p = dynamic_cast<const KinematicPtpTrajectory*>(traj.get());
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->startTime(), 0.0);
  EXPECT_NEAR(p->endTime(), 0.9981317008, 1e-9);
  const auto ref = oneAxis();
  for (double t : {0.0, 0.2, 0.5, 0.8, 1.2}) EXPECT_TRUE(MatricesNear(p->setpoint(t).q, ref.setpoint(t).q, 1e-15));
}

TEST(KinematicPtpYaml, StartTimeAndErrors) {
  const auto traj = fromYaml(R"(trajectory:
  type: kinematic_ptp
  q_begin: [0, 1]
  q_end: [1, 1]
  qd_max: [1, 1]
  qdd_max: [1, 1]
  start_time: 0.5
)",
                             2);
  EXPECT_NEAR(dynamic_cast<const KinematicPtpTrajectory&>(*traj).endTime(), 2.5, 1e-15);
  auto err = [](const std::string& text, const std::string& msg) {
    EXPECT_THAT([&] { fromYaml(text, 2); }, ThrowsMessage<InputError>(HasSubstr(msg)));
  };
  err("trajectory:\n  type: kinematic_ptp\n  q_begin: [0, 1]\n  q_end: [1, 1]\n  qd_max: [1, 0]\n  qdd_max: [1, 1]\n",
      "t.yaml:5: trajectory.qd_max: expected a list of 2 max joint speeds in rad/s, each > 0");
  err("trajectory:\n  type: kinematic_ptp\n  q_begin: [0, 1]\n  q_end: [1, 1]\n  qd_max: [1, 1]\n  qdd_max: [1]\n",
      "trajectory.qdd_max");
  err("trajectory:\n  type: kinematic_ptp\n  q_begin: [0, 1]\n  q_end: [1, 1]\n  qd_max: [1, 1]\n", "qdd_max");
  err("trajectory:\n  type: kinematic_ptp\n  q_begin: [0, 1]\n  q_end: [1, 1]\n  qd_max: [1, 1]\n  qdd_max: [1, 1]\n"
      "  start_time: -1\n",
      "trajectory.start_time");
  err("trajectory:\n  type: kinematic_ptp\n  q_begin: [0, 1]\n  q_end: [1, 1]\n  qd_max: [1, 1]\n  qdd_max: [1, 1]\n"
      "  swing_time: 0.5\n",
      "swing_time");
}
