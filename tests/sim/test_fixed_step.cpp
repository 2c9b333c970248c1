// Tests of the fixed-step integrator sim::FixedStepIntegrator (ROS2, [Verwer1999]) against closed forms: the order of
// convergence on a non-autonomous problem with an exact and a wrong Jacobian (a W-method), L-stability, the stability
// function on an undamped oscillator (amplitude and phase per step), roots located on the step, stop times, the
// errors; and through sim::Simulator on a sampled plant against the exact discrete-time recurrence.

#include "jointsim/sim/fixed_step_integrator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "jointsim/common/error.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulator.hpp"

namespace {

using jointsim::InputError;
using jointsim::SolverError;
using jointsim::sim::CvodeIntegrator;
using jointsim::sim::CvodeOptions;
using jointsim::sim::FixedStepIntegrator;
using jointsim::sim::Method;
namespace sim = jointsim::sim;

const double kGamma = 1.0 + 1.0 / std::sqrt(2.0);

CvodeOptions fixedStep(double h, int jacobian_every = 1) {
  CvodeOptions o;
  o.method = Method::Rosenbrock;
  o.fixed_step = h;
  o.jacobian_every = jacobian_every;
  return o;
}

::testing::AssertionResult contains(const std::string& haystack, const std::string& needle) {
  if (haystack.find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << needle << "' not found in: " << haystack;
}

// y' = λ (y − sin t) + cos t, y(0) = 1: y(t) = sin t + e^{λt}. `w_scale` scales the Jacobian handed to the method
// (1: exact; another value: a wrong W, which a W-method of order 2 must tolerate).
double errorAtOne(double lambda, double h, double w_scale) {
  FixedStepIntegrator integ(
      1, [lambda](double t, const auto& y, auto yd) { yd[0] = lambda * (y[0] - std::sin(t)) + std::cos(t); },
      fixedStep(h));
  integ.setDifferenceJacobian(
      [lambda, w_scale](double, const auto&, const auto&, const auto&, auto J) { J(0, 0) = w_scale * lambda; });
  integ.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
  Eigen::VectorXd y(1);
  EXPECT_EQ(integ.advance(1.0, y), 1.0);
  EXPECT_EQ(integ.steps(), std::lround(1.0 / h));
  return std::abs(y[0] - (std::sin(1.0) + std::exp(lambda)));
}

TEST(FixedStep, SecondOrderOnANonAutonomousProblemWithTheExactAndAWrongJacobian) {
  for (double w_scale : {1.0, 0.5, 0.0}) {
    const double e1 = errorAtOne(-2.0, 0.02, w_scale), e2 = errorAtOne(-2.0, 0.01, w_scale),
                 e3 = errorAtOne(-2.0, 0.005, w_scale);
    // Order 2: each halving of the step divides the error by 4 (not 2), whatever W is; and the error is small.
    EXPECT_NEAR(e1 / e2, 4.0, 0.4) << "W = " << w_scale << " J";
    EXPECT_NEAR(e2 / e3, 4.0, 0.3) << "W = " << w_scale << " J";
    EXPECT_LT(e3, 3e-5) << "W = " << w_scale << " J";
  }
}

TEST(FixedStep, LStableAStiffTransientIsGoneAfterOneStep) {
  // λ h = −1e5: the stability function R(z) = (1 + (1 − 2γ) z + (γ² − 2γ + ½) z²) / (1 − γz)² tends to 0 as z → −∞
  // (γ² − 2γ + ½ = 0 for γ = 1 + 1/√2), so the transient e^{λt} is damped to O(1/z) in one step, and the smooth
  // solution sin t is followed to second order. (An A-stable but not L-stable method, the trapezoidal rule, would
  // carry a transient of R(−∞) = −1 for ever.)
  const double lambda = -1e8, h = 1e-3;
  FixedStepIntegrator integ(
      1, [lambda](double t, const auto& y, auto yd) { yd[0] = lambda * (y[0] - std::sin(t)) + std::cos(t); },
      fixedStep(h));
  integ.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
  Eigen::VectorXd y(1);
  integ.advance(h, y);
  EXPECT_LT(std::abs(y[0] - std::sin(h)), 1e-4);
  integ.advance(2 * h, y);
  EXPECT_LT(std::abs(y[0] - std::sin(2 * h)), 1e-8);
  integ.advance(1.0, y);
  // (The difference quotient of ∂f/∂t loses ε|λy|/δ ≈ 1 to rounding here, which the step divides by λ.)
  EXPECT_LT(std::abs(y[0] - std::sin(1.0)), 1e-6);
}

TEST(FixedStep, ATimeInvariantRightHandSideSkipsTheDifferenceInTimeWithTheSameResult) {
  // y'' = −ω² y − 2ζω y' (autonomous): fₜ's difference quotient is exactly 0, so declaring the right-hand side time
  // invariant saves one right-hand side per Jacobian and leaves every bit of the run as it was. Declared for an f that
  // does depend on t (a forcing cos t), the step loses the fₜ terms of [Verwer1999, eq. 2.2]: the run differs, which
  // shows the declaration is what is used (and why a plant may only make it when true).
  auto run = [](bool forced, int invariance) {  // invariance: 0 not set, 1 false, 2 true
    FixedStepIntegrator integ(
        2,
        [forced](double t, const auto& y, auto yd) {
          yd[0] = y[1];
          yd[1] = -400.0 * y[0] - 4.0 * y[1] + (forced ? 50.0 * std::cos(30.0 * t) : 0.0);
        },
        fixedStep(1e-3));
    if (invariance > 0) integ.setTimeInvariance([invariance] { return invariance == 2; });
    integ.initialize(0.0, Eigen::Vector2d(1.0, 0.0), false);
    Eigen::VectorXd y(2);
    integ.advance(0.5, y);
    return std::make_pair(Eigen::Vector2d(y), integ.stats());
  };
  const auto [y0, s0] = run(false, 0);
  const auto [y1, s1] = run(false, 1);
  const auto [y2, s2] = run(false, 2);
  EXPECT_EQ(y0[0], y2[0]);
  EXPECT_EQ(y0[1], y2[1]);
  EXPECT_EQ(y0[0], y1[0]);
  EXPECT_EQ(y0[1], y1[1]);
  EXPECT_EQ(s0.jac_evals, s2.jac_evals);
  EXPECT_GT(s0.jac_evals, 400);
  // Without a plant Jacobian each one costs n = 2 right-hand sides for ∂f/∂y, plus one for ∂f/∂t unless invariant.
  EXPECT_EQ(s0.rhs_evals_jacobian, 3 * s0.jac_evals);
  EXPECT_EQ(s1.rhs_evals_jacobian, 3 * s1.jac_evals);
  EXPECT_EQ(s2.rhs_evals_jacobian, 2 * s2.jac_evals);
  const auto [f0, fs0] = run(true, 0);
  const auto [f2, fs2] = run(true, 2);
  EXPECT_GT(std::abs(f0[0] - f2[0]), 1e-7);
}

TEST(FixedStep, AnUnresolvedOscillatorRingsDownAsTheStabilityFunctionPredicts) {
  // A lightly damped gear mode at 4.6 kHz stepped at 20 kHz (ωh = 1.45, above the step's Nyquist frequency's
  // resolution): per step the linear system is multiplied by R(hJ), so the amplitude shrinks by |R(iωh)| and the phase
  // turns by arg R(iωh), exactly, where the true mode would keep its amplitude and turn by ωh.
  const double w = 2.0 * std::acos(-1.0) * 4600.0, h = 5e-5;
  FixedStepIntegrator integ(
      2,
      [w](double, const auto& y, auto yd) {
        yd[0] = w * y[1];
        yd[1] = -w * y[0];
      },
      fixedStep(h));
  integ.initialize(0.0, Eigen::Vector2d(1.0, 0.0), false);
  const std::complex<double> z(0.0, w * h);
  const std::complex<double> R = (1.0 + (1.0 - 2.0 * kGamma) * z + (kGamma * kGamma - 2.0 * kGamma + 0.5) * z * z) /
                                 ((1.0 - kGamma * z) * (1.0 - kGamma * z));
  Eigen::VectorXd y(2);
  const int steps = 10;
  integ.advance(steps * h, y);
  // y = x + i·v rotates as e^{−iωt}: its numerical image is multiplied by conj(R)... compare modulus and angle.
  const std::complex<double> got(y[0], y[1]), want = std::pow(std::conj(R), steps);
  EXPECT_NEAR(std::abs(got) / std::abs(want), 1.0, 1e-8);
  EXPECT_NEAR(std::arg(got), std::arg(want), 1e-8);
  EXPECT_LT(std::abs(R), 0.75);  // measured damping per step: the mode is damped, not resolved
  EXPECT_GT(std::abs(R), 0.5);
}

// resolve_oscillations: the oscillatory states' rows are taken with ROS2's other L-stable γ, 1 − 1/√2. A lightly damped
// motor–gear mode (5.3 kHz at h = 50 µs, ωh = 1.66) in those rows then turns with R_low(iωh) per step, |R| = 0.98
// instead of 0.46, exactly; a stiff lag in a row that is not declared is still damped as by γ = 1 + 1/√2 (R(hλ) for
// hλ = −5: 0.144, not R_low's −0.176); the method keeps order 2, also with only one of the oscillator's rows declared
// (a mode shared by scaled and unscaled rows, as the twin's joint angle and rate); a kept Jacobian of a linear f is
// still kept (its defect is measured against the Jacobian, not the scaled W) with the same result to rounding; and
// the options a resolved row cannot stand are refused.
TEST(FixedStep, ResolvedOscillationsTurnWithTheOtherGammaAndStayOfOrderTwo) {
  const double w = 2.0 * std::acos(-1.0) * 5287.0, h = 5e-5, lambda = -5.0 / h;
  const double g_low = 1.0 - 1.0 / std::sqrt(2.0);
  auto stability = [](double g, std::complex<double> z) {
    return (1.0 + (1.0 - 2.0 * g) * z + (g * g - 2.0 * g + 0.5) * z * z) / ((1.0 - g * z) * (1.0 - g * z));
  };
  // States: an undamped oscillator (0, 1) and a stiff lag (2) towards 0.
  auto run = [&](bool resolve, bool adaptive, int steps, double step, std::vector<int> declared = {1, 0}) {
    CvodeOptions o = fixedStep(step);
    o.resolve_oscillations = resolve;
    if (adaptive) sim::setAdaptiveJacobian(o);
    FixedStepIntegrator integ(
        3,
        [&](double, const auto& y, auto yd) {
          yd[0] = w * y[1];
          yd[1] = -w * y[0];
          yd[2] = lambda * y[2];
        },
        o);
    integ.setDifferenceJacobian([&](double, const auto&, const auto&, const auto&, auto J) {
      J(0, 1) = w;
      J(1, 0) = -w;
      J(2, 2) = lambda;
    });
    integ.setOscillatoryStates(declared);
    integ.setTimeInvariance([] { return true; });
    integ.initialize(0.0, Eigen::Vector3d(1.0, 0.0, 1.0), false);
    Eigen::VectorXd y(3);
    integ.advance(steps * step, y);
    return std::make_pair(Eigen::Vector3d(y), integ.stats());
  };
  const std::complex<double> z(0.0, w * h);
  for (const bool resolve : {false, true}) {
    const auto [y, st] = run(resolve, false, 10, h);
    const std::complex<double> r = stability(resolve ? g_low : kGamma, z);
    const std::complex<double> got(y[0], y[1]), want = std::pow(std::conj(r), 10);
    EXPECT_NEAR(std::abs(got) / std::abs(want), 1.0, 1e-8) << resolve;
    EXPECT_NEAR(std::arg(got), std::arg(want), 1e-8) << resolve;
    const double lag = std::pow(stability(kGamma, lambda * h).real(), 10);  // undeclared: γ high
    EXPECT_NEAR(y[2], lag, 1e-12 * lag) << resolve;
    EXPECT_EQ(st.lin_setups, resolve ? 20 : 10);  // per Jacobian the unscaled I − γhW as well (its determinant)
  }
  EXPECT_NEAR(std::abs(stability(g_low, z)), 0.982, 1e-3);
  EXPECT_NEAR(std::abs(stability(kGamma, z)), 0.457, 1e-3);
  EXPECT_LT(stability(g_low, lambda * h).real(), -0.1);  // why the friction rows are not declared on the twin
  // A kept Jacobian: the same result as one per step (f is linear; to the rounding of the kept factorisation's explicit
  // inverses), one Jacobian.
  const auto [ya, sa] = run(true, true, 10, h);
  const auto [y1, s1] = run(true, false, 10, h);
  EXPECT_EQ(sa.jac_evals, 1);
  EXPECT_LT((ya - y1).cwiseAbs().maxCoeff(), 1e-13);
  // Order 2 over 2 ms: the error against cos/sin of the resolved oscillator falls 4× per halving of the step, with
  // both of its rows declared or one; and with one, a kept Jacobian is still kept.
  for (const std::vector<int>& declared : {std::vector<int>{0, 1}, std::vector<int>{0}}) {
    auto error = [&](double step) {
      const int steps = static_cast<int>(std::lround(2e-3 / step));
      const auto [y, st] = run(true, false, steps, step, declared);
      return std::hypot(y[0] - std::cos(w * 2e-3), y[1] + std::sin(w * 2e-3));
    };
    const double e1 = error(h / 8), e2 = error(h / 16), e3 = error(h / 32);
    std::printf("[ measured ] %zu declared row(s): error at h/8, h/16, h/32: %.3g %.3g %.3g\n", declared.size(), e1, e2,
                e3);
    EXPECT_NEAR(e1 / e2, 4.0, 0.5) << declared.size();
    EXPECT_NEAR(e2 / e3, 4.0, 0.3) << declared.size();
    EXPECT_EQ(run(true, true, 10, h, declared).second.jac_evals, 1) << declared.size();
  }
  // Refused: a defect test too lax for γ = 1 − 1/√2's 17 % tolerance, a Jacobian kept without it, a bad index.
  auto make = [](double defect, int every) {
    CvodeOptions o = fixedStep(1e-3, every);
    o.resolve_oscillations = true;
    o.jacobian_defect = defect;
    FixedStepIntegrator integ(
        1, [](double, const auto& y, auto yd) { yd[0] = -y[0]; }, o);
  };
  EXPECT_NO_THROW(make(sim::kResolveMaxJacobianDefect, sim::kAdaptiveJacobianEvery));
  try {
    make(0.2, sim::kAdaptiveJacobianEvery);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "jacobian_defect must be at most 0.05"));
  }
  try {
    make(0.0, 4);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "jacobian_every 1 or adaptive"));
  }
  CvodeOptions o = fixedStep(1e-3);
  o.resolve_oscillations = true;
  FixedStepIntegrator integ(
      2, [](double, const auto& y, auto yd) { yd = -y; }, o);
  EXPECT_THROW(integ.setOscillatoryStates({0, 2}), InputError);
  EXPECT_THROW(integ.setOscillatoryStates({1, 1}), InputError);
  try {
    integ.setOscillatoryStates({});  // a model without oscillatory states: the option would do nothing
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "declares no oscillatory states"));
  }
}

// y' = λy with λ > 0 and a step far beyond 1/λ. Unchecked, ROS2 would damp the growth: R(λh) = R(3) = −0.37 per step,
// so y(0.05) = (−0.37)⁵ = −0.007 instead of e¹⁵ = 3.3e6 — the failure that held a UR5 wrist joint at an unstable
// equilibrium. The step is halved while det(I − γhW) = 1 − γhλ < 0, then quartered, and that length is kept up to
// the grid point: the states follow the exact recurrence of that rule, and the growth e^{λt} to the accuracy of ROS2
// at hλ ≈ 0.09.
TEST(FixedStep, AGrowingModeFasterThanTheStepIsFollowedByShorterStepsNotDamped) {
  const double h = 0.01, t_end = 0.05;
  for (double lambda : {300.0, 1000.0}) {
    FixedStepIntegrator integ(
        1, [lambda](double, const auto& y, auto yd) { yd[0] = lambda * y[0]; }, fixedStep(h));
    integ.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
    Eigen::VectorXd y(1);
    EXPECT_EQ(integ.advance(t_end, y), t_end);
    // The rule, step by step: from t towards the next grid point; a step with γhλ > 1 is halved until γhλ ≤ 1, then
    // quartered, and the next steps keep that length up to that grid point.
    auto R = [](double z) { return (1.0 + (1.0 - 2.0 * kGamma) * z) / ((1.0 - kGamma * z) * (1.0 - kGamma * z)); };
    double t = 0.0, yr = 1.0, sub = 0.0, until = 0.0;
    long steps = 0, splits = 0;
    while (t < t_end - 1e-12) {
      const double grid = (std::floor(t / h + 1e-9) + 1.0) * h, merge = 1e-6 * h;
      if (sub > 0.0 && t >= until - merge) sub = 0.0;
      double end = grid;
      if (sub > 0.0) {
        if (until - t > sub + merge && 8.0 * kGamma * sub * lambda < 1.0) sub *= 2.0;  // (never, for a constant λ)
        end = until - t > sub + merge ? t + sub : until;
      }
      double r = end - t;
      if (kGamma * r * lambda > 1.0) {
        until = end;
        while (kGamma * r * lambda > 1.0) r *= 0.5;
        r *= 0.25;
        sub = r;
        end = t + r;
        ++splits;
      }
      yr *= R(lambda * r);
      t = end;
      ++steps;
    }
    EXPECT_EQ(integ.stats().split_steps, splits) << lambda;
    EXPECT_EQ(integ.steps(), steps) << lambda;
    EXPECT_NEAR(y[0] / yr, 1.0, 1e-9) << lambda;
    // Against the exact growth: 0.78 (λ = 300) and 0.58 (λ = 1000) of e^{λt} after e¹⁵ and e⁵⁰ (a rate error of 1.7 %
    // and 1.1 %).
    const double ratio = y[0] / std::exp(lambda * t_end);
    EXPECT_GT(ratio, 0.5) << lambda;
    EXPECT_LT(ratio, 1.0) << lambda;
  }
  // A mode no allowed halving resolves (γλh = 1.7e6 needs 21 of at most 13): an error naming the time and the state,
  // not a damped result.
  FixedStepIntegrator fast(
      1, [](double, const auto& y, auto yd) { yd[0] = 1e9 * y[0]; }, fixedStep(1e-3));
  fast.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
  Eigen::VectorXd y(1);
  try {
    fast.advance(0.01, y);
    FAIL() << "no error";
  } catch (const SolverError& e) {
    EXPECT_TRUE(contains(e.what(), "the step is too large for the dynamics at t = 0 s"));
    EXPECT_TRUE(contains(e.what(), "on y[0]"));
    EXPECT_EQ(e.flag(), "STEP_UNSTABLE");
    EXPECT_EQ(e.time(), 0.0);
  }
  // The limit: a full step is halved at most 13 times before its quarter is taken (the shortest step 2⁻¹⁵ of the
  // fixed step). γλh = 0.9·2¹⁴ needs 14 halvings: an error; 0.9·2¹³ needs 13: followed.
  for (double scale : {0.9 * 8192.0, 0.9 * 16384.0}) {
    FixedStepIntegrator edge(
        1, [scale](double, const auto& y, auto yd) { yd[0] = scale / kGamma * y[0]; }, fixedStep(1.0));
    edge.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
    if (scale < 10000.0) {
      EXPECT_NO_THROW(edge.advance(1e-3, y)) << scale;
      EXPECT_EQ(edge.stats().last_step, std::ldexp(1.0, -15)) << scale;  // 2⁻¹³ · ¼
    } else {
      EXPECT_THROW(edge.advance(1e-3, y), SolverError) << scale;
    }
  }
  // A decaying mode, however fast, is never split (det > 0 for λ < 0).
  FixedStepIntegrator decay(
      1, [](double, const auto& y, auto yd) { yd[0] = -1e9 * y[0]; }, fixedStep(1e-3));
  decay.initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
  decay.advance(0.01, y);
  EXPECT_EQ(decay.stats().split_steps, 0);
  EXPECT_EQ(decay.steps(), 10);
}

// y' = λ(t) y, y(0) = 1 (exact: y = exp ∫₀ᵗ λ) with its exact Jacobian, stepped at h, initialised.
template <class Lambda>
std::unique_ptr<FixedStepIntegrator> growth(Lambda lambda, double h) {
  auto integ = std::make_unique<FixedStepIntegrator>(
      1, [lambda](double t, const auto& y, auto yd) { yd[0] = lambda(t) * y[0]; }, fixedStep(h));
  integ->setDifferenceJacobian(
      [lambda](double t, const auto&, const auto&, const auto&, auto J) { J(0, 0) = lambda(t); });
  integ->initialize(0.0, Eigen::VectorXd::Constant(1, 1.0), false);
  return integ;
}

// y' = λ(t) y with a growth rate that rises from 3.7e3 1/s to 1e4 1/s and falls to −10 1/s within about a millisecond
// (a Gaussian bump of width 0.5 ms at t = 0.5 ms, like a break-away's negative damping), stepped at 10 ms: y(t) =
// exp(∫λ) grows by e^{8.2} = 3500 over the bump. The first step is shortened, later ones are shortened again as λ
// keeps rising (the run keeps its end: the grid point), and once the bump has passed the step length grows back by
// doubling instead of crawling to the grid point at the shortest length. (A bump inside a long step, unseen by the
// W of its start, is stepped over: the limit of a linearisation at the start of the step.)
TEST(FixedStep, AGrowthRateThatRisesAndFallsIsFollowedAndTheStepGrowsBackAfterIt) {
  const double h = 0.01, t_end = 0.02, a = 1e4, tc = 5e-4, w = 5e-4, b = 10.0;
  const double pi = std::acos(-1.0);
  auto lambda = [=](double t) { return a * std::exp(-((t - tc) / w) * ((t - tc) / w)) - b; };
  auto integral = [=](double t) {
    return a * w * std::sqrt(pi) / 2.0 * (std::erf((t - tc) / w) + std::erf(tc / w)) - b * t;
  };
  auto integ_ptr = growth(lambda, h);
  FixedStepIntegrator& integ = *integ_ptr;
  Eigen::VectorXd y(1);
  // Over the growth: the exponent ∫λ (8.2) to 3 % (ROS2 at hλ ≤ 0.15 where λ peaks: ~2 % in the rate).
  EXPECT_EQ(integ.advance(1e-3, y), 1e-3);
  EXPECT_NEAR(std::log(y[0]) / integral(1e-3), 1.0, 0.03);
  EXPECT_GE(integ.stats().split_steps, 2);  // shortened at the first step, and again as λ rose
  integ.advance(t_end, y);
  EXPECT_NEAR(std::log(y[0]) / integral(t_end), 1.0, 0.03);
  EXPECT_GT(integral(t_end), 7.9);  // (the growth is real: a damped result would be near 0)
  // Far fewer steps than 10 ms at the shortest length (γλh ≤ 1/4 at λ = 1e4: ≤ 15 µs, over 600 steps).
  EXPECT_LT(integ.steps(), 250);
  EXPECT_EQ(integ.stats().last_step, h);  // the second grid step is not shortened
}

// y' = λ(t) y with λ rising from −10 1/s to 2000 1/s at 15 ms and falling back at 21 ms (∫λ = 12), stepped at 10 ms:
// the step from 10 ms starts where λ < 0 and ends inside the growth, which the linearisation at its start cannot
// show; the step from 20 ms sees it and is shortened, and the step before it is retaken from 10 ms with that length
// (nothing of it was returned yet). Without the retake (an output at 20 ms prevents it) most of the growth between 15
// and 20 ms is lost.
TEST(FixedStep, AStepThatRanIntoAGrowingModeUnseenAtItsStartIsRetaken) {
  const double h = 0.01, a = 2000.0, b = 10.0, w = 2e-4, ta = 0.015, tb = 0.021;
  auto lambda = [=](double t) { return 0.5 * a * (std::tanh((t - ta) / w) - std::tanh((t - tb) / w)) - b; };
  // ∫₀ᵗ λ: (a w / 2) [ln cosh((t − ta)/w) − ln cosh((t − tb)/w)] from 0 to t, minus b t (ln cosh by its stable form).
  auto lncosh = [](double x) { return std::abs(x) + std::log1p(std::exp(-2.0 * std::abs(x))) - std::log(2.0); };
  auto F = [=](double t) { return 0.5 * a * w * (lncosh((t - ta) / w) - lncosh((t - tb) / w)); };
  auto integral = [=](double t) { return F(t) - F(0.0) - b * t; };
  auto integ_ptr = growth(lambda, h);
  FixedStepIntegrator& integ = *integ_ptr;
  Eigen::VectorXd y(1);
  EXPECT_EQ(integ.advance(0.03, y), 0.03);
  EXPECT_GT(integral(0.03), 11.5);
  EXPECT_NEAR(std::log(y[0]) / integral(0.03), 1.0, 0.05);
  EXPECT_EQ(integ.stats().retaken_steps, 1);
  // Nothing is retaken across an output: the same run returning at 20 ms first keeps the step to 20 ms as it was.
  auto split_ptr = growth(lambda, h);
  FixedStepIntegrator& split = *split_ptr;
  split.advance(0.02, y);
  const double at20 = y[0];
  split.advance(0.03, y);
  EXPECT_EQ(split.stats().retaken_steps, 0);
  // The growth the step to 20 ms missed, as returned (measured: 21 % of the exponent at 20 ms, 35 % at 30 ms).
  EXPECT_LT(std::log(at20), 0.3 * integral(0.02));
  EXPECT_LT(std::log(y[0]), 0.5 * integral(0.03));
}

TEST(FixedStep, ARootIsLocatedOnTheStepAndTheEarliestOfTwoIsReported) {
  // A falling ball y'' = −g from 1 m: y is quadratic in t, which ROS2 and the cubic interpolant reproduce exactly, so
  // the root y = 0 (t = √(2/g)) is located to the root tolerance.
  const double g = 9.81, h = 0.01;
  FixedStepIntegrator integ(
      2,
      [g](double, const auto& y, auto yd) {
        yd[0] = y[1];
        yd[1] = -g;
      },
      fixedStep(h));
  integ.setRootFunction(2, [](double, const auto& y, auto r) {
    r[0] = y[0] - 0.5;  // half height: first
    r[1] = y[0];
  });
  integ.initialize(0.0, Eigen::Vector2d(1.0, 0.0), false);
  Eigen::VectorXd y(2);
  double t = integ.advance(1.0, y);
  ASSERT_TRUE(integ.rootFound());
  EXPECT_NEAR(t, std::sqrt(2.0 * 0.5 / g), 1e-12);
  EXPECT_EQ(integ.rootDirections(), (std::vector<int>{-1, 0}));
  EXPECT_NEAR(y[0], 0.5, 1e-12);
  integ.initialize(t, y, true);  // as sim::Simulator restarts after an event
  t = integ.advance(1.0, y);
  ASSERT_TRUE(integ.rootFound());
  EXPECT_NEAR(t, std::sqrt(2.0 / g), 1e-12);
  EXPECT_EQ(integ.rootDirections(), (std::vector<int>{0, -1}));
  EXPECT_NEAR(y[1], -std::sqrt(2.0 * g), 1e-10);
  // The steps after the root meet the grid again: the next one ends at the next multiple of h.
  integ.initialize(t, y, true);
  integ.advance(std::ceil(t / h) * h, y);
  EXPECT_FALSE(integ.rootFound());
  EXPECT_NEAR(integ.stats().last_step, std::ceil(t / h) * h - t, 1e-15);
}

TEST(FixedStep, StopTimesEndShortStepsAndOutputsBetweenStepsAreInterpolated) {
  // y' = 2t: ROS2 reduces to the trapezoidal rule (W plays no part where f does not depend on y), exact for a linear
  // f, and the cubic interpolant is exact for y = t², so every value below is exact to rounding.
  const double h = 0.1;
  FixedStepIntegrator integ(
      1, [](double t, const auto&, auto yd) { yd[0] = 2.0 * t; }, fixedStep(h));
  integ.initialize(0.0, Eigen::VectorXd::Zero(1), false);
  integ.setStopTime(0.25);
  Eigen::VectorXd y(1);
  EXPECT_EQ(integ.advance(1.0, y), 0.25);  // steps 0.1, 0.2, then 0.05 to the stop
  EXPECT_EQ(integ.steps(), 3);
  EXPECT_NEAR(y[0], 0.25 * 0.25, 1e-15);
  EXPECT_NEAR(integ.stats().last_step, 0.05, 1e-15);
  // The stop is one-shot; the next steps are back on the grid (0.3, 0.4), and 0.33 is interpolated.
  EXPECT_EQ(integ.advance(0.33, y), 0.33);
  EXPECT_EQ(integ.steps(), 5);
  EXPECT_NEAR(y[0], 0.33 * 0.33, 1e-15);
  EXPECT_EQ(integ.time(), 0.33);
  EXPECT_EQ(integ.stats().current_time, 0.4);
  EXPECT_EQ(integ.advance(0.4, y), 0.4);  // no step: already there
  EXPECT_EQ(integ.steps(), 5);
  EXPECT_NEAR(y[0], 0.16, 1e-15);
  // A stop a rounding error away from where the integrator stands (k·0.1 against a time summed another way) takes no
  // step of 1e-17 s: the state is already there.
  integ.setStopTime(0.4 + 1e-17 + 5e-17);
  EXPECT_GT(integ.advance(1.0, y), 0.4);
  EXPECT_EQ(integ.steps(), 5);
}

// jacobian_defect (the experiment files' jacobian_every: adaptive): W is kept while the linearisation defect along each
// step's first stage stays below θ relative to the change of f.
// (1) A linear f with its exact Jacobian has no defect: one Jacobian for the whole run, and every bit as with a
// Jacobian per step (the same W; the factorisation of the same length is kept).
// (2) A bristle-like state whose stiffness follows the velocity, z' = v − σ|v|z with v = sin(ωt) as a second state
// (σ = 1e5 1/rad: h·σ|v| up to 10 at h = 100 µs, where a W from v ≈ 0 is an explicit step that diverges): the
// adaptive run renews W where |v| moves and meets the accuracy of a Jacobian per step against CVODE at rtol 1e-10,
// with a fraction of the Jacobians; the same reuse without the defect test diverges.
TEST(FixedStep, AnAdaptiveJacobianIsKeptWhileItDescribesTheStepsAndRenewedWhereTheStiffnessMoves) {
  {
    auto run = [](bool adaptive) {
      // (h = 2⁻¹⁰ s: the grid's step lengths are exact, so a kept factorisation is of the very same matrix)
      CvodeOptions o = fixedStep(std::ldexp(1.0, -10));
      if (adaptive) sim::setAdaptiveJacobian(o);
      FixedStepIntegrator integ(
          2,
          [](double, const auto& y, auto yd) {
            yd[0] = y[1];
            yd[1] = -1e6 * y[0] - 50.0 * y[1];
          },
          o);
      integ.setDifferenceJacobian([](double, const auto&, const auto&, const auto&, auto J) {
        J(0, 1) = 1.0;
        J(1, 0) = -1e6;
        J(1, 1) = -50.0;
      });
      integ.initialize(0.0, Eigen::Vector2d(1.0, 0.0), false);
      Eigen::VectorXd y(2);
      integ.advance(0.5, y);
      return std::make_pair(Eigen::Vector2d(y), integ.stats());
    };
    const auto [y1, s1] = run(false);
    const auto [ya, sa] = run(true);
    EXPECT_EQ(s1.jac_evals, 512);
    EXPECT_EQ(sa.jac_evals, 1);
    EXPECT_EQ(sa.lin_setups, 1);
    EXPECT_EQ(y1[0], ya[0]);
    EXPECT_EQ(y1[1], ya[1]);
  }
  const double sigma = 1e5, omega = 2.0 * M_PI * 10.0, h = 1e-4, t_end = 0.25;
  // v' = ω u, u' = −ω v (v = sin ωt, u = cos ωt), z' = v − σ|v| z.
  auto rhs = [=](double, const auto& y, auto yd) {
    yd[0] = omega * y[1];
    yd[1] = -omega * y[0];
    yd[2] = y[0] - sigma * std::abs(y[0]) * y[2];
  };
  const Eigen::Vector3d y0(0.0, 1.0, 0.0);
  CvodeOptions ref_opts;
  ref_opts.rtol = 1e-10;
  ref_opts.atol = 1e-14;
  CvodeIntegrator ref(3, rhs, ref_opts);
  ref.initialize(0.0, y0, false);
  // restart: after every step initialize(t, y, true), as under input_jumps: restart at every sample (the kept
  // Jacobian keeps its verdict: a defect found in the step before still renews it).
  auto fixed = [&](int every, double defect, Eigen::VectorXd& zs, sim::SolverStats& st, bool restart = false) {
    CvodeOptions o = fixedStep(h, every);
    o.jacobian_defect = defect;
    o.atol = 1e-12;
    FixedStepIntegrator integ(3, rhs, o);
    integ.initialize(0.0, y0, false);
    Eigen::VectorXd y(3);
    zs.resize(50);
    const int per_output = static_cast<int>(std::lround(t_end / 50 / h));
    for (int k = 0; k < 50; ++k) {
      if (restart) {
        for (int i = 1; i <= per_output; ++i) {
          const double t = (k * per_output + i) * h;
          integ.advance(t, y);
          integ.initialize(t, y, true);
        }
      } else {
        integ.advance((k + 1) * t_end / 50, y);
      }
      zs[k] = y[2];
    }
    st = integ.stats();
  };
  Eigen::VectorXd z_ref(50), y(3);
  for (int k = 0; k < 50; ++k) {
    ref.advance((k + 1) * t_end / 50, y);
    z_ref[k] = y[2];
  }
  const double scale = 1.0 / sigma;  // z's steady state sign(v)/σ
  Eigen::VectorXd z1, za;
  sim::SolverStats s1, sa;
  fixed(1, 0.0, z1, s1);
  fixed(sim::kAdaptiveJacobianEvery, sim::kAdaptiveJacobianDefect, za, sa);
  const double e1 = (z1 - z_ref).cwiseAbs().maxCoeff() / scale, ea = (za - z_ref).cwiseAbs().maxCoeff() / scale;
  EXPECT_LT(e1, 0.02);
  EXPECT_LT(ea, 2.0 * e1);
  EXPECT_EQ(s1.jac_evals, s1.steps);
  EXPECT_LT(sa.jac_evals, sa.steps / 3);
  EXPECT_GT(sa.jac_evals, 10);  // renewed as |v| moves, not kept from the start
  Eigen::VectorXd zr;
  sim::SolverStats sr;
  fixed(sim::kAdaptiveJacobianEvery, sim::kAdaptiveJacobianDefect, zr, sr, true);
  EXPECT_EQ(sr.jac_evals, sa.jac_evals);  // restarts that keep the Jacobian change nothing
  EXPECT_EQ(zr, za);
  // Kept from the start without the test: the step at |v| = 1 is explicit with h·σ = 10.
  Eigen::VectorXd zk;
  sim::SolverStats sk;
  bool diverged = false;
  try {
    fixed(sim::kAdaptiveJacobianEvery, 0.0, zk, sk);
    diverged = !((zk - z_ref).cwiseAbs().maxCoeff() / scale < 1.0);
  } catch (const SolverError&) {
    diverged = true;
  }
  EXPECT_TRUE(diverged);
  std::printf(
      "[ measured ] z error / (1/sigma): Jacobian per step %.3g (%ld), adaptive %.3g (%ld Jacobians of %ld steps)\n",
      e1, s1.jac_evals, ea, sa.jac_evals, sa.steps);
}

TEST(FixedStep, FailuresNameTheTimeAndTheStateAndBadOptionsAreRefused) {
  CvodeOptions o = fixedStep(0.01);
  o.state_name = [](int i) { return i == 0 ? std::string("motor.current [A]") : std::string(); };
  o.component = "test drive";
  FixedStepIntegrator blowup(
      1, [](double t, const auto& y, auto yd) { yd[0] = t > 0.5 ? NAN : y[0]; }, o);
  blowup.initialize(0.0, Eigen::VectorXd::Ones(1), false);
  Eigen::VectorXd y(1);
  try {
    blowup.advance(1.0, y);
    FAIL() << "no error";
  } catch (const SolverError& e) {
    EXPECT_TRUE(contains(e.what(), "motor.current [A]"));
    EXPECT_TRUE(contains(e.what(), "test drive"));
    EXPECT_GE(e.time(), 0.5);
    EXPECT_LT(e.time(), 0.52);
    EXPECT_EQ(e.flag(), "RHS_NONFINITE");
  }
  FixedStepIntegrator thrower(
      1,
      [](double t, const auto&, auto yd) {
        if (t > 0.3) throw std::runtime_error("broken model");
        yd[0] = 0.0;
      },
      o);
  thrower.initialize(0.0, Eigen::VectorXd::Ones(1), false);
  try {
    thrower.advance(1.0, y);
    FAIL() << "no error";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "RHS_EXCEPTION");
    EXPECT_TRUE(contains(e.what(), "broken model"));
    bool nested = false;
    try {
      std::rethrow_if_nested(e);
    } catch (const std::runtime_error&) {
      nested = true;
    }
    EXPECT_TRUE(nested);
  }
  auto rhs = [](double, const auto&, auto yd) { yd[0] = 0.0; };
  EXPECT_THROW(FixedStepIntegrator(1, rhs, fixedStep(0.0)), InputError);
  EXPECT_THROW(FixedStepIntegrator(1, rhs, fixedStep(-1.0)), InputError);
  EXPECT_THROW(FixedStepIntegrator(1, rhs, fixedStep(0.1, 0)), InputError);
  for (double defect : {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    CvodeOptions o_bad = fixedStep(0.1);
    o_bad.jacobian_defect = defect;
    EXPECT_THROW(FixedStepIntegrator(1, rhs, o_bad), InputError) << defect;
  }
  EXPECT_THROW(FixedStepIntegrator(1, rhs, CvodeOptions{}), InputError);  // BDF is CVODE's
  EXPECT_THROW(CvodeIntegrator(1, rhs, fixedStep(0.1)), InputError);      // and Rosenbrock is not
  // A step budget ends the call; max_num_steps bounds one call.
  FixedStepIntegrator budget(1, rhs, fixedStep(0.01));
  budget.initialize(0.0, Eigen::VectorXd::Ones(1), false);
  budget.setStepLimit(10);
  try {
    budget.advance(1.0, y);
    FAIL() << "no error";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "STEP_BUDGET");
    EXPECT_NEAR(budget.lastStep(y), 0.1, 1e-12);
  }
}

// x' = (u − x)/τ with u = −K x held from each sample (period T): exactly x_{k+1} = (a − (1 − a) K) x_k, a = e^{−T/τ}.
class SampledLag : public sim::Plant {
 public:
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double u = 0.0;
  };
  static constexpr double tau = 2e-3, K = 0.5, T = 1e-3;
  std::string name() const override { return "sampled lag"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Ones(1); }
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  void start(sim::PlantState& s, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    sample(s, t, y);
  }
  double samplePeriod() const override { return T; }
  void sample(sim::PlantState& s, double, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    own<State>(s).u = -K * y[0];
  }
  void derivatives(const sim::PlantState& s, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    ++derivative_calls;
    yd[0] = (own<State>(s).u - y[0]) / tau;
  }
  mutable long derivative_calls = 0;  // (a test's counter: one simulator at a time)
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }

 private:
  std::vector<std::string> names_{"x[-]"};
};

TEST(FixedStep, SampledControlThroughTheSimulatorIsTheMethodsRecurrenceAndConvergesAtSecondOrder) {
  // Between samples the plant is linear with the fixed point u, which ROS2 keeps: with m steps per period each sample
  // maps x to u + R(−T/(mτ))^m (x − u), R the stability function, exactly. And R^m → e^{−T/τ} at second order.
  SampledLag plant;
  const double T = SampledLag::T, tau = SampledLag::tau, K = SampledLag::K;
  const double exact = std::pow(std::exp(-T / tau) - (1.0 - std::exp(-T / tau)) * K, 20);  // x after 20 samples
  std::vector<double> errors;
  for (int m : {1, 2, 4}) {
    CvodeOptions o;
    o.method = Method::Rosenbrock;
    o.fixed_step = m == 1 ? 0.0 : T / m;  // 0: the control period
    plant.derivative_calls = 0;
    sim::Simulator s(plant, o);
    for (int i = 0; i < 20; ++i) s.advance(T);
    EXPECT_EQ(s.stats().steps, 20L * m);  // locked to the clock: m steps per period, no more
    // Every right-hand side is the integrator's (the simulator evaluates none around a sample: a fixed step keeps no
    // history whose error an input jump would need estimating; with CVODE it takes two per sample).
    EXPECT_EQ(plant.derivative_calls, s.stats().rhs_evals + s.stats().rhs_evals_jacobian) << m;
    const double z = -T / (m * tau);
    const double R = (1.0 + (1.0 - 2.0 * kGamma) * z + (kGamma * kGamma - 2.0 * kGamma + 0.5) * z * z) /
                     ((1.0 - kGamma * z) * (1.0 - kGamma * z));
    const double Rm = std::pow(R, m);
    EXPECT_NEAR(s.state()[0], std::pow(Rm - (1.0 - Rm) * K, 20), 1e-15) << m << " steps per period";
    errors.push_back(std::abs(s.state()[0] - exact));
  }
  EXPECT_LT(errors[0], 2e-3);
  EXPECT_GT(errors[0] / errors[1], 3.5);  // z = −0.5 per period is not yet asymptotic; then 4
  EXPECT_NEAR(errors[1] / errors[2], 4.0, 0.4);
  // A step that is not an integer fraction of the control period is refused, naming the period.
  CvodeOptions bad;
  bad.method = Method::Rosenbrock;
  bad.fixed_step = 0.3e-3;
  try {
    sim::Simulator s(plant, bad);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "integer fraction"));
    EXPECT_TRUE(contains(e.what(), "0.001"));
  }
}

}  // namespace
