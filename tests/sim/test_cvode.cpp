// CvodeIntegrator against problems with known answers: exponential decay, the harmonic oscillator, the
// stiff Robertson kinetics (SUNDIALS' cvRoberts_dns published answers), restarts, stop times, and error
// reporting (component name, simulated time, CVODE flag).
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/sim/cvode_integrator.hpp"

using namespace jointsim::sim;
using ::testing::HasSubstr;
using Vec = Eigen::VectorXd;
using CRef = const Eigen::Ref<const Eigen::VectorXd>&;
using Ref = Eigen::Ref<Eigen::VectorXd>;

namespace {
constexpr double kPi = 3.14159265358979323846;

CvodeOptions options(Method method, double rtol, double atol) {
  CvodeOptions o;
  o.method = method;
  o.rtol = rtol;
  o.atol = atol;
  return o;
}

// Robertson: y1' = −0.04 y1 + 1e4 y2 y3, y2' = 0.04 y1 − 1e4 y2 y3 − 3e7 y2², y3' = 3e7 y2².
void robertson(double, CRef y, Ref yd) {
  yd[0] = -0.04 * y[0] + 1.0e4 * y[1] * y[2];
  yd[2] = 3.0e7 * y[1] * y[1];
  yd[1] = -yd[0] - yd[2];
}
void robertsonJacobian(double, CRef y, CRef, Eigen::Ref<Eigen::MatrixXd> J) {
  J << -0.04, 1.0e4 * y[2], 1.0e4 * y[1],  //
      0.04, -1.0e4 * y[2] - 6.0e7 * y[1], -1.0e4 * y[1],  //
      0.0, 6.0e7 * y[1], 0.0;
}
}  // namespace

class ExponentialDecay : public ::testing::TestWithParam<Method> {};

TEST_P(ExponentialDecay, MatchesClosedForm) {
  const double k = 2.5;
  CvodeIntegrator integ(1, [k](double, CRef y, Ref yd) { yd[0] = -k * y[0]; }, options(GetParam(), 1e-10, 1e-14));
  Vec y0(1), y(1);
  y0 << 3.0;
  integ.initialize(0.0, y0);
  for (double t : {0.1, 0.5, 1.0, 2.0, 4.0}) {
    EXPECT_DOUBLE_EQ(integ.advance(t, y), t);
    // Global error is bounded by ~100 rtol relative to the largest magnitude seen (y0 = 3).
    EXPECT_NEAR(y[0], 3.0 * std::exp(-k * t), 1e-8 * 3.0) << "t = " << t;
  }
  const SolverStats s = integ.stats();
  EXPECT_GT(s.steps, 10);
  EXPECT_GE(s.rhs_evals, s.steps);
}

INSTANTIATE_TEST_SUITE_P(Methods, ExponentialDecay, ::testing::Values(Method::BDF, Method::Adams));

TEST(HarmonicOscillator, TenPeriodsPhaseAndEnergy) {
  const double w = 2 * kPi * 3.0;  // 3 Hz
  for (Method m : {Method::Adams, Method::BDF}) {
    CvodeIntegrator integ(2, [w](double, CRef y, Ref yd) { yd << y[1], -w * w * y[0]; }, options(m, 1e-11, 1e-13));
    Vec y0(2), y(2);
    y0 << 1.0, 0.0;
    integ.initialize(0.0, y0);
    const double T = 10.0 / 3.0;  // ten periods
    integ.advance(T, y);
    EXPECT_NEAR(y[0], std::cos(w * T), 1e-7);
    EXPECT_NEAR(y[1], -w * std::sin(w * T), 1e-7 * w);
    EXPECT_NEAR(0.5 * (y[1] * y[1] / (w * w) + y[0] * y[0]), 0.5, 1e-7);
  }
}

TEST(Robertson, MatchesPublishedAnswersAndConservesMass) {
  // cvRoberts_dns.out (SUNDIALS examples, rtol 1e-4, atol (1e-8, 1e-14, 1e-6)).
  const double times[] = {0.4, 4.0, 40.0, 4.0e2, 4.0e4, 4.0e6, 4.0e8, 4.0e10};
  const double published[][3] = {{9.851641e-01, 3.386242e-05, 1.480205e-02}, {9.055097e-01, 2.240338e-05, 9.446793e-02},
                                 {7.158017e-01, 9.185037e-06, 2.841892e-01}, {4.505360e-01, 3.223271e-06, 5.494608e-01},
                                 {3.898824e-02, 1.621985e-07, 9.610116e-01}, {5.169987e-04, 2.069052e-09, 9.994830e-01},
                                 {5.204550e-06, 2.081831e-11, 9.999948e-01}, {3.630684e-08, 1.452274e-13, 1.000000e+00}};
  CvodeOptions loose = options(Method::BDF, 1e-4, 0);
  loose.atol_vector = Eigen::Vector3d(1e-8, 1e-14, 1e-6);
  CvodeOptions tight = options(Method::BDF, 1e-10, 0);
  tight.atol_vector = Eigen::Vector3d(1e-16, 1e-22, 1e-14);
  CvodeIntegrator analytic(3, robertson, loose, robertsonJacobian);
  CvodeIntegrator dq(3, robertson, loose);
  CvodeIntegrator ref(3, robertson, tight, robertsonJacobian);
  const Vec y0 = Eigen::Vector3d(1, 0, 0);
  analytic.initialize(0, y0);
  dq.initialize(0, y0);
  ref.initialize(0, y0);
  Vec ya(3), yq(3), yr(3);
  for (int k = 0; k < 8; ++k) {
    analytic.advance(times[k], ya);
    dq.advance(times[k], yq);
    ref.advance(times[k], yr);
    const Eigen::Vector3d pub(published[k][0], published[k][1], published[k][2]);
    for (int i = 0; i < 3; ++i) {
      // The tight run is the accurate answer. The published (rtol 1e-4) values, and our rtol-1e-4 runs,
      // must lie within a bound set by those tolerances: 50 rtol relative plus 10 atol absolute.
      const double bound = 5e-3 * std::abs(yr[i]) + 10 * loose.atol_vector[i];
      EXPECT_NEAR(pub[i], yr[i], bound) << "published vs reference, t = " << times[k] << ", y" << i + 1;
      EXPECT_NEAR(ya[i], yr[i], bound) << "analytic Jacobian, t = " << times[k] << ", y" << i + 1;
      EXPECT_NEAR(yq[i], yr[i], bound) << "DQ Jacobian, t = " << times[k] << ", y" << i + 1;
    }
    EXPECT_NEAR(ya.sum(), 1.0, 1e-6);
    EXPECT_NEAR(yr.sum(), 1.0, 1e-9);
  }
  EXPECT_GT(analytic.stats().jac_evals, 0);
  EXPECT_EQ(analytic.stats().rhs_evals_jacobian, 0) << "analytic Jacobian needs no difference quotients";
  EXPECT_GT(dq.stats().rhs_evals_jacobian, 0);
  EXPECT_LT(analytic.stats().steps, 2000) << "a stiff solver crosses 1e10 s in few steps";
}

TEST(Restart, PiecewiseConstantInputAfterReInit) {
  double u = 2.0;
  CvodeIntegrator integ(1, [&u](double, CRef, Ref yd) { yd[0] = u; }, options(Method::BDF, 1e-10, 1e-12));
  Vec y(1);
  integ.initialize(0.0, Vec::Zero(1));
  integ.advance(1.0, y);
  EXPECT_NEAR(y[0], 2.0, 1e-9);
  u = -3.0;  // discontinuity: restart the integrator at t = 1
  integ.initialize(1.0, y);
  integ.advance(2.5, y);
  EXPECT_NEAR(y[0], 2.0 - 3.0 * 1.5, 1e-9);
  EXPECT_DOUBLE_EQ(integ.time(), 2.5);
  EXPECT_GT(integ.stats().steps, 0);
}

TEST(StopTime, IntegrationDoesNotPassIt) {
  double max_t_seen = 0;
  CvodeIntegrator integ(1, [&](double t, CRef y, Ref yd) {
    max_t_seen = std::max(max_t_seen, t);
    yd[0] = -y[0];
  }, options(Method::Adams, 1e-8, 1e-10));
  Vec y(1);
  integ.initialize(0.0, Vec::Ones(1));
  integ.setStopTime(0.75);
  const double t = integ.advance(2.0, y);
  EXPECT_DOUBLE_EQ(t, 0.75);
  EXPECT_LE(max_t_seen, 0.75);
  EXPECT_NEAR(y[0], std::exp(-0.75), 1e-7);
  integ.clearStopTime();
  EXPECT_DOUBLE_EQ(integ.advance(2.0, y), 2.0);
  EXPECT_NEAR(y[0], std::exp(-2.0), 1e-7);
}

TEST(Errors, ComponentExceptionReportsComponentAndTime) {
  CvodeOptions o = options(Method::BDF, 1e-8, 1e-10);
  o.component = "joint rig";
  CvodeIntegrator integ(1, [](double t, CRef y, Ref yd) {
    if (t > 0.5) throw jointsim::ComponentError("lugre", "bristle state NaN");
    yd[0] = -y[0];
  }, o);
  Vec y(1);
  integ.initialize(0.0, Vec::Ones(1));
  try {
    integ.advance(2.0, y);
    FAIL() << "no exception";
  } catch (const jointsim::SolverError& e) {
    EXPECT_EQ(e.component(), "lugre");
    EXPECT_GT(e.time(), 0.5);
    EXPECT_LT(e.time(), 0.6);
    EXPECT_THAT(e.what(), HasSubstr("lugre"));
    EXPECT_THAT(e.what(), HasSubstr("bristle state NaN"));
    EXPECT_THAT(e.what(), HasSubstr("t = 0.5"));
  }
}

TEST(Errors, TooMuchWorkAndNonFiniteDerivative) {
  CvodeOptions o = options(Method::Adams, 1e-12, 1e-14);
  o.max_num_steps = 10;
  o.component = "oscillator";
  const double w = 1000;
  CvodeIntegrator busy(2, [w](double, CRef y, Ref yd) { yd << y[1], -w * w * y[0]; }, o);
  Vec y(2);
  busy.initialize(0.0, Eigen::Vector2d(1, 0));
  EXPECT_THAT([&] { busy.advance(1.0, y); },
              ::testing::ThrowsMessage<jointsim::SolverError>(
                  ::testing::AllOf(HasSubstr("CV_TOO_MUCH_WORK"), HasSubstr("oscillator"))));

  CvodeIntegrator nan(1, [](double t, CRef, Ref yd) { yd[0] = t > 0.3 ? std::nan("") : 1.0; },
                      options(Method::BDF, 1e-6, 1e-8));
  Vec z(1);
  nan.initialize(0.0, Vec::Zero(1));
  try {
    nan.advance(1.0, z);
    FAIL() << "no exception";
  } catch (const jointsim::SolverError& e) {
    EXPECT_THAT(e.what(), HasSubstr("non-finite"));
    EXPECT_NEAR(e.time(), 0.3, 0.05);
    EXPECT_FALSE(e.flag().empty());
  }
}

TEST(Errors, BadOptionsAreInputErrors) {
  auto rhs = [](double, CRef, Ref yd) { yd.setZero(); };
  using jointsim::InputError;
  EXPECT_THROW(CvodeIntegrator(0, rhs), InputError);
  EXPECT_THROW(CvodeIntegrator(2, rhs, options(Method::BDF, 0.0, 1e-8)), InputError);
  EXPECT_THROW(CvodeIntegrator(2, rhs, options(Method::BDF, 1e-6, -1.0)), InputError);
  CvodeOptions o = options(Method::BDF, 1e-6, 1e-8);
  o.atol_vector = Eigen::Vector3d(1, 1, 1);
  EXPECT_THAT([&] { CvodeIntegrator(2, rhs, o); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("atol_vector has 3 entries, expected 2")));
  CvodeIntegrator ok(2, rhs);
  EXPECT_THROW(ok.initialize(0.0, Vec::Zero(3)), InputError);
}
