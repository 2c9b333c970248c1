// Tests of the friction models (include/jointsim/drive/friction_models.hpp) against closed forms of
// [Hauschild2003, eqs. 4.2, 4.6, 4.9, 4.21], [Raviola2023, eq. 7] and [Olsson2017, eq. 3.1] and against
// simulations of an inertia J q̈ = τ − τ_f integrated with CVODE, and of the YAML front end.

#include "jointsim/drive/friction_models.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

// Internal header (src/ is not on the test include path, hence the relative path).
#include "jointsim/common/error.hpp"
#include "jointsim/drive/drive_yaml.hpp"
#include "jointsim/sim/cvode_integrator.hpp"

namespace {

using jointsim::InputError;
using jointsim::drive::CoulombViscousFriction;
using jointsim::drive::CoulombViscousParams;
using jointsim::drive::DahlFriction;
using jointsim::drive::DahlParams;
using jointsim::drive::Friction;
using jointsim::drive::LuGreFriction;
using jointsim::drive::LuGreParams;
using jointsim::drive::LuGreUr5Friction;
using jointsim::drive::LuGreUr5Params;
using jointsim::drive::StribeckFriction;
using jointsim::drive::StribeckParams;
using jointsim::drive::TableFriction;
using jointsim::drive::TableFrictionParams;
using jointsim::sim::CvodeIntegrator;
using jointsim::sim::CvodeOptions;

double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// [Hauschild2003, Table 4.3], shoulder actuator (δ = 2), typed in again here so that the tests do not depend on the
// library's defaults: {α0 [N·m], α1 [N·m], α2 [N·m·s/rad], v_S [rad/s]}.
struct Table43 {
  double a0, a1, a2, vs;
};
constexpr Table43 kPos{7.9707, 1.4476, 4.9349, 0.0363};
constexpr Table43 kNeg{7.7538, 0.8626, 4.3267, 0.0221};

// [Hauschild2003, eq. 4.21] / eq. 4.6 with δ = 2, written out independently of the library.
double eq421(double v) {
  const Table43& p = v >= 0.0 ? kPos : kNeg;
  return (p.a0 + p.a1 * std::exp(-(v / p.vs) * (v / p.vs))) * sgn(v) + p.a2 * v;
}

LuGreParams shoulderLuGre() {
  LuGreParams p;
  p.sigma0 = 259.0;  // [Hauschild2003, §4.5.6]
  p.sigma1 = 10.0;
  p.positive = {kPos.a0, kPos.a1, kPos.a2, kPos.vs};
  p.negative = {kNeg.a0, kNeg.a1, kNeg.a2, kNeg.vs};
  return p;
}

// ----------------------------------------------------------------------------- simulation helpers

// z-state alone driven at a constant velocity v: ż from the model, integrated to t_end; returns z.
std::vector<double> integrateStateAtVelocity(const Friction& f, double v, double t_end, double atol) {
  const int n = f.stateSize();
  CvodeOptions opt;
  opt.rtol = 1e-11;
  opt.atol = atol;
  CvodeIntegrator cv(
      n,
      [&f, v](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        f.evaluate({v, 0.0}, y.data(), yd.data());
      },
      opt);
  Eigen::VectorXd z(n);
  f.initialState(z.data());
  cv.initialize(0.0, z);
  cv.advance(t_end, z);
  return {z.data(), z.data() + n};
}

// Inertia J on a shaft with friction f and applied torque tau(t): y = [q, v, z...].
struct InertiaSim {
  const Friction& f;
  double J;
  std::function<double(double)> tau;
  CvodeIntegrator cv;
  Eigen::VectorXd y;

  InertiaSim(const Friction& friction, double inertia, std::function<double(double)> torque, double v0,
             CvodeOptions opt)
      : f(friction),
        J(inertia),
        tau(std::move(torque)),
        cv(
            2 + friction.stateSize(),
            [this](double t, const Eigen::Ref<const Eigen::VectorXd>& s, Eigen::Ref<Eigen::VectorXd> sd) {
              double* zdot = sd.data() + 2;
              const double td = tau(t);
              const double tf = f.evaluate({s[1], td}, s.data() + 2, zdot);
              sd[0] = s[1];
              sd[1] = (td - tf) / J;
            },
            opt),
        y(Eigen::VectorXd::Zero(2 + friction.stateSize())) {
    y[1] = v0;
    f.initialState(y.data() + 2);
    cv.initialize(0.0, y);
  }
  InertiaSim(const InertiaSim&) = delete;  // the right-hand side captures `this`
  InertiaSim& operator=(const InertiaSim&) = delete;
  void advance(double t) { cv.advance(t, y); }
  double q() const { return y[0]; }
  double v() const { return y[1]; }
  double z() const { return y[2]; }
  // Friction torque in the current state.
  double frictionTorque(double t) const {
    double zd[1] = {0.0};
    return f.evaluate({y[1], tau(t)}, y.data() + 2, zd);
  }
};

CvodeOptions tightOptions(double atol) {
  CvodeOptions opt;
  opt.rtol = 1e-9;
  opt.atol = atol;
  return opt;
}

::testing::AssertionResult contains(const std::string& haystack, const std::string& needle) {
  if (haystack.find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << needle << "' not found in: " << haystack;
}

// ============================================================================ LuGre ([Hauschild2003, §4.4–4.5])

TEST(FrictionLuGre, ConstantVelocityConvergesToStaticMapEq421) {
  // At constant v, z relaxes to g(v)/σ0 sgn(v) with rate σ0|v|/g(v); after 30 time constants the
  // friction σ0 z + σ1 ż + α2 v must equal eq. 4.21 to 1e-6 relative.
  const LuGreFriction f(shoulderLuGre());
  for (double v : {0.002, 0.01, 0.03, 0.1, 0.6, 2.0, -0.002, -0.01, -0.03, -0.1, -0.6, -2.0}) {
    const Table43& p = v >= 0.0 ? kPos : kNeg;
    const double g = p.a0 + p.a1 * std::exp(-(v / p.vs) * (v / p.vs));
    const double t_end = 30.0 * g / (259.0 * std::abs(v));
    const auto z = integrateStateAtVelocity(f, v, t_end, 1e-14);
    double zd = 0.0;
    const double F = f.evaluate({v, 0.0}, z.data(), &zd);
    const double ref = eq421(v);
    EXPECT_NEAR(F, ref, 1e-6 * std::abs(ref)) << "v = " << v;
    EXPECT_NEAR(z[0], sgn(v) * g / 259.0, 1e-6 * g / 259.0) << "bristle deflection g(v)/σ0, v = " << v;
    EXPECT_NEAR(f.steadyState(v), ref, 1e-12 * std::abs(ref)) << "v = " << v;
  }
  // The static map is asymmetric (Table 4.3): stiction levels α0 + α1 per direction.
  EXPECT_NEAR(f.steadyState(1e-9), kPos.a0 + kPos.a1, 1e-6);
  EXPECT_NEAR(f.steadyState(-1e-9), -(kNeg.a0 + kNeg.a1), 1e-6);
}

TEST(FrictionLuGre, PreslidingStiffnessIsSigma0) {
  // A torque of 1 % of the stiction level, ramped in slowly and held, deflects the shaft elastically.
  // Quasi-static LuGre (v > 0, ż = v(1 − σ0 z/g0), τ = σ0 z) gives q = −(g0/σ0) ln(1 − τ/g0), a secant
  // stiffness σ0 (τ/g0)/(−ln(1 − τ/g0)) = σ0 (1 − 0.5 %): the initial stiffness is σ0.
  const LuGreFriction f(shoulderLuGre());
  const double g0 = kPos.a0 + kPos.a1;
  const double tau1 = 0.01 * g0;
  const double T = 20.0;
  auto tau = [=](double t) {
    const double s = std::min(t / T, 1.0);
    return tau1 * s * s * (3.0 - 2.0 * s);  // smoothstep, no impulse to excite the bristle mode
  };
  InertiaSim sim(f, 3.41, tau, 0.0, tightOptions(1e-12));
  sim.advance(40.0);
  const double stiffness = tau1 / sim.q();
  EXPECT_NEAR(stiffness, 259.0, 0.01 * 259.0);
  EXPECT_NEAR(sim.q(), -(g0 / 259.0) * std::log(1.0 - tau1 / g0), 2e-3 * sim.q());
  EXPECT_NEAR(sim.v(), 0.0, 1e-6);
}

TEST(FrictionLuGre, PreslidingOscillationHasBristleStiffnessAndDamping) {
  // Small free motion about rest: σ0|v|z/g is second order, so ż ≈ q̇, z ≈ q and
  // J q̈ = −σ0 q − (σ1 + α2) q̇ (our linearised bristle mode, derived from [Hauschild2003, eqs. 4.15–4.16]):
  // a damped oscillator with ω_n = √(σ0/J), ζ = (σ1 + α2)/(2√(σ0 J)). α2 switches with the direction of v
  // (Table 4.3); over each cycle the motion spends equal time in both, so the mean α2 is used. From q = 0, q̇ = v0:
  // q(t) = (v0/ω_d) e^{−ζω_n t} sin(ω_d t).
  const LuGreFriction f(shoulderLuGre());
  const double J = 3.41, v0 = 1e-4;
  const double wn = std::sqrt(259.0 / J);
  const double zeta = (10.0 + 0.5 * (kPos.a2 + kNeg.a2)) / (2.0 * std::sqrt(259.0 * J));
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  InertiaSim sim(
      f, J, [](double) { return 0.0; }, v0, tightOptions(1e-14));
  for (double t : {0.1, 0.2, 0.3, 0.5, 0.8, 1.2}) {
    sim.advance(t);
    const double ref = v0 / wd * std::exp(-zeta * wn * t) * std::sin(wd * t);
    EXPECT_NEAR(sim.q(), ref, 0.01 * v0 / wd) << "t = " << t;
  }
}

TEST(FrictionLuGre, SlowTorqueRampBreaksAwayNearAlpha0PlusAlpha1) {
  // Criterion: the break-away torque is the largest friction torque the contact carries before the shaft
  // slides (|v| reaches 3 v_S, where the Stribeck term has decayed to e^-9). In the quasi-static limit
  // this is the maximum of the static map, α0 + α1 + α2² v_S²/(4 α1) (+0.06 % / +0.03 % above α0 + α1
  // for Table 4.3); at a finite force rate LuGre breaks away lower (its rate-dependent break-away force),
  // by 0.2–0.5 % at 0.01 N·m/s. Tolerance 1 % at 0.01 N·m/s, and the error must shrink as the rate does.
  const LuGreFriction f(shoulderLuGre());
  for (double dir : {1.0, -1.0}) {
    const double stiction = dir > 0 ? kPos.a0 + kPos.a1 : kNeg.a0 + kNeg.a1;
    const double vs = dir > 0 ? kPos.vs : kNeg.vs;
    double previous_error = std::numeric_limits<double>::infinity();
    for (double rate : {0.1, 0.03, 0.01}) {  // N·m/s
      InertiaSim sim(
          f, 3.41, [=](double t) { return dir * rate * t; }, 0.0, tightOptions(1e-12));
      double breakaway = 0.0;
      const double dt = 0.002 / rate;  // torque steps of 2 mN·m between samples
      double t = 0.0;
      while (dir * sim.v() < 3.0 * vs && t < 2.0 * stiction / rate) {
        t += dt;
        sim.advance(t);
        breakaway = std::max(breakaway, dir * sim.frictionTorque(t));
      }
      ASSERT_GE(dir * sim.v(), 3.0 * vs) << "no break-away up to twice the stiction torque, rate " << rate;
      const double error = std::abs(breakaway - stiction) / stiction;
      EXPECT_LT(error, previous_error) << "break-away must approach α0 + α1 as the rate decreases, rate " << rate;
      previous_error = error;
      if (rate == 0.01) {
        EXPECT_NEAR(breakaway, stiction, 0.01 * stiction) << "direction " << dir;
      }
    }
  }
}

TEST(FrictionLuGre, FreeDecelerationIsDissipative) {
  // E = J v²/2 + σ0 z²/2 with no driving torque: dE/dt = −α2 v² − [σ0²|v|/g z² + σ1σ0|v|/g z ż + σ1 ż²]
  // ≤ 0 while σ1 |v| ≤ 4 g(v) (the bracket is then a non-negative quadratic form). Here σ1 v0 = 10 N·m
  // < 4 α0⁻ = 31 N·m and |v| ≤ v0 as long as E does not grow, so E must never increase.
  const LuGreFriction f(shoulderLuGre());
  const double J = 3.41, v0 = 1.0;
  ASSERT_LT(10.0 * v0, 4.0 * std::min(kPos.a0, kNeg.a0));
  InertiaSim sim(
      f, J, [](double) { return 0.0; }, v0, tightOptions(1e-12));
  auto energy = [&] { return 0.5 * J * sim.v() * sim.v() + 0.5 * 259.0 * sim.z() * sim.z(); };
  const double E0 = energy();
  double E_prev = E0;
  double max_rate = -std::numeric_limits<double>::infinity();
  for (int k = 1; k <= 5000; ++k) {
    sim.advance(1e-3 * k);
    const double E = energy();
    ASSERT_LE(E, E_prev + 1e-9 * E0) << "energy increased at t = " << 1e-3 * k;
    E_prev = E;
    double zd = 0.0;
    const double F = f.evaluate({sim.v(), 0.0}, &sim.y[2], &zd);
    max_rate = std::max(max_rate, -sim.v() * F + 259.0 * sim.z() * zd);
  }
  EXPECT_LE(max_rate, 1e-12) << "pointwise dE/dt";
  // The shaft stops (Coulomb deceleration ≈ 8 N·m / 3.41 kg·m² from 1 rad/s: ~0.4 s) and the bristle
  // oscillation decays: nearly all energy is dissipated after 5 s.
  EXPECT_LT(E_prev, 1e-3 * E0);
  EXPECT_LT(std::abs(sim.v()), 1e-3);
}

// ============================================================================ UR5 LuGre ([Raviola2023, eq. 7])

LuGreUr5Params ur5Params() {
  LuGreUr5Params p;  // σ0, σ1, q̇_s, K_static, exponent: the values of [Raviola2023] (defaults)
  p.f_c = 10.0;      // not given by [Raviola2023]: test values
  p.f_v = 5.0;
  p.k_q = 1.0;
  return p;
}

TEST(FrictionLuGreUr5, ConstantVelocityConvergesToStaticMap) {
  const LuGreUr5Friction f(ur5Params());
  EXPECT_EQ(f.params().sigma0, 5e6);
  EXPECT_EQ(f.params().sigma1, 100.0);
  for (double v : {0.001, 0.05, 0.5, 3.0, -0.001, -0.05, -0.5, -3.0}) {
    // [Raviola2023, eq. 7] written out: g = f_c (1 + K_static e^{−k_q |q̇| / q̇_s}) + f_v |q̇|^{2/3}.
    const double g = 10.0 * (1.0 + 0.3 * std::exp(-std::abs(v) / 0.5)) + 5.0 * std::cbrt(v * v);
    const double t_end = 30.0 * g / (5e6 * std::abs(v));
    const auto z = integrateStateAtVelocity(f, v, t_end, 1e-18);
    double zd = 0.0;
    const double F = f.evaluate({v, 0.0}, z.data(), &zd);
    EXPECT_NEAR(F, sgn(v) * g, 1e-6 * g) << "v = " << v;
    EXPECT_NEAR(f.steadyState(v), sgn(v) * g, 1e-12 * g) << "v = " << v;
  }
  EXPECT_NEAR(f.steadyState(1e-12), 1.3 * 10.0, 1e-6);  // break-away (1 + K_static) f_c
}

TEST(FrictionLuGreUr5, UnsetCoefficientsAreRejected) {
  LuGreUr5Params p;  // f_c, f_v, k_q not given by [Raviola2023] → NaN
  try {
    LuGreUr5Friction f(p);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "lugre_ur5: f_c: expected a finite value > 0")) << e.what();
    EXPECT_EQ(e.keyPath(), "f_c");
  }
  p = ur5Params();
  p.k_q = -1.0;
  EXPECT_THROW(LuGreUr5Friction{p}, InputError);
}

// ============================================================================ Stribeck ([Hauschild2003, eq. 4.6])

TEST(FrictionStribeck, MatchesEq46WithTable43PerDirection) {
  const StribeckFriction f(StribeckParams{});  // defaults: Table 4.3, δ = 2, k_S = 300 s/rad
  // Away from 0 the slope limiter 1 − e^{−300|v|} is 1 to < 2e-8 (|v| >= 0.06 rad/s).
  for (double v : {0.06, 0.1, 0.5, 2.0, -0.06, -0.1, -0.5, -2.0}) {
    const double ref = eq421(v);
    EXPECT_NEAR(f.evaluate({v, 123.0}, nullptr, nullptr), ref, 1e-7 * std::abs(ref)) << "v = " << v;
    EXPECT_NEAR(f.steadyState(v), ref, 1e-7 * std::abs(ref)) << "v = " << v;
  }
  // Asymmetric by direction (Table 4.3), eq. 4.6 typed out at ±0.07 rad/s (limiter factor 1 − 8e-10).
  EXPECT_NEAR(f.steadyState(0.07), 7.9707 + 1.4476 * std::exp(-std::pow(0.07 / 0.0363, 2)) + 4.9349 * 0.07, 1e-7);
  EXPECT_NEAR(f.steadyState(-0.07), -(7.7538 + 0.8626 * std::exp(-std::pow(0.07 / 0.0221, 2)) + 4.3267 * 0.07), 1e-7);
  EXPECT_GT(std::abs(f.steadyState(0.07) + f.steadyState(-0.07)), 0.2);
  // Near 0: slope limiter of [Hauschild2003, eq. 4.24], continuous through zero with slope k_S (α0 + α1).
  const double v = 1e-3;
  EXPECT_NEAR(f.steadyState(v), eq421(v) * (1.0 - std::exp(-0.3)), 1e-12);
  EXPECT_NEAR(f.steadyState(-v), eq421(-v) * (1.0 - std::exp(-0.3)), 1e-12);
  EXPECT_EQ(f.steadyState(0.0), 0.0);
  EXPECT_NEAR(f.steadyState(1e-9) / 1e-9, 300.0 * (kPos.a0 + kPos.a1), 1e-3 * 300.0 * (kPos.a0 + kPos.a1));
}

TEST(FrictionStribeck, FormFactorDeltaEntersTheExponent) {
  StribeckParams p;
  p.delta = 1.0;
  const StribeckFriction f(p);
  const double v = 0.1;
  EXPECT_NEAR(f.steadyState(v), 7.9707 + 1.4476 * std::exp(-v / 0.0363) + 4.9349 * v, 1e-9);
  p.negative.v_s = 0.0;
  EXPECT_THROW(StribeckFriction{p}, InputError);
}

// ============================================================================ Dahl ([Hauschild2003, eqs. 4.7–4.9])

TEST(FrictionDahl, SteadyStateIsCoulombLevelAtAnySpeed) {
  const DahlFriction f(DahlParams{259.0, 7.9707, 1.0});
  for (double v : {0.01, 0.5, 5.0, -0.01, -0.5, -5.0}) {
    const double t_end = 30.0 * 7.9707 / (259.0 * std::abs(v));  // 30 "displacement constants" F_C/σ
    const auto z = integrateStateAtVelocity(f, v, t_end, 1e-14);
    double zd = 0.0;
    EXPECT_NEAR(f.evaluate({v, 0.0}, z.data(), &zd), sgn(v) * 7.9707, 1e-6 * 7.9707) << "v = " << v;
    EXPECT_NEAR(f.steadyState(v), sgn(v) * 7.9707, 1e-15);
  }
}

TEST(FrictionDahl, VirginCurveMatchesClosedFormForAlpha1And2) {
  // From F = 0 at x = 0 moving forward, eq. 4.7 integrates to
  //   α = 1: F = F_C (1 − e^{−σx/F_C});   α = 2: F = F_C σx / (F_C + σx).
  const double sigma = 259.0, fc = 7.9707, v = 0.2;
  for (double alpha : {1.0, 2.0}) {
    const DahlFriction f(DahlParams{sigma, fc, alpha});
    for (double x : {0.005, 0.03, 0.1}) {
      const auto z = integrateStateAtVelocity(f, v, x / v, 1e-14);
      double zd = 0.0;
      const double F = f.evaluate({v, 0.0}, z.data(), &zd);
      const double ref = alpha == 1.0 ? fc * (1.0 - std::exp(-sigma * x / fc)) : fc * sigma * x / (fc + sigma * x);
      EXPECT_NEAR(F, ref, 1e-7 * fc) << "alpha = " << alpha << ", x = " << x;
    }
  }
}

TEST(FrictionDahl, HysteresisLoopDissipatesTheClosedFormEnergy) {
  // Displacement x = A sin(ωt). The periodic loop of eq. 4.8 (α = 1) has turning forces ±F_t,
  // F_t = F_C (1 − E)/(1 + E), E = e^{−2σA/F_C}; its upper branch is F = F_C − (F_C + F_t) e^{−σ(x+A)/F_C}
  // and its area ∮F dx = 2 [2 A F_C − (F_C + F_t)(F_C/σ)(1 − E)] > 0. Moving forward the friction is
  // above the backward branch (it lags the motion). Rate independence: same loop at two frequencies.
  const double sigma = 259.0, fc = 7.9707, A = 0.05;
  const double E = std::exp(-2.0 * sigma * A / fc);
  const double Ft = fc * (1.0 - E) / (1.0 + E);
  const double area = 2.0 * (2.0 * A * fc - (fc + Ft) * (fc / sigma) * (1.0 - E));
  const double F_up0 = fc - (fc + Ft) * std::exp(-sigma * A / fc);  // upper branch at x = 0
  const DahlFriction f(DahlParams{sigma, fc, 1.0});
  for (double omega : {1.0, 20.0}) {
    CvodeOptions opt;
    opt.rtol = 1e-10;
    opt.atol = 1e-13;
    // y = [z, W] with W = ∫ F v dt the work done against friction.
    CvodeIntegrator cv(
        2,
        [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
          const double v = A * omega * std::cos(omega * t);
          yd[1] = f.evaluate({v, 0.0}, y.data(), yd.data()) * v;
        },
        opt);
    cv.initialize(0.0, Eigen::Vector2d::Zero());
    const double T = 2.0 * std::acos(-1.0) / omega;
    Eigen::VectorXd y(2);
    cv.advance(4.0 * T, y);  // the loop converges by a factor E per half cycle
    const double W4 = y[1];
    double zd = 0.0;
    const double F_fwd = f.evaluate({A * omega, 0.0}, y.data(), &zd);  // x = 0 moving forward
    cv.advance(4.5 * T, y);
    const double F_bwd = f.evaluate({-A * omega, 0.0}, y.data(), &zd);  // x = 0 moving backward
    cv.advance(5.0 * T, y);
    EXPECT_NEAR(y[1] - W4, area, 1e-6 * area) << "omega = " << omega;
    EXPECT_GT(y[1] - W4, 0.0);
    EXPECT_NEAR(F_fwd, F_up0, 1e-6 * fc);
    EXPECT_NEAR(F_bwd, -F_up0, 1e-6 * fc);
    EXPECT_GT(F_fwd, F_bwd);
  }
}

// ======================================================================== Coulomb + viscous ([Hauschild2003, eq. 4.2])

TEST(FrictionCoulombViscous, MatchesCoulombPlusViscousAwayFromZero) {
  const CoulombViscousFriction f(CoulombViscousParams{1.91, 0.2, 1e-3});  // F_C of [KR300Thesis, Table 6.1]
  for (double v : {0.02, 0.1, 1.0, 10.0, -0.02, -0.1, -1.0, -10.0}) {
    const double ref = 1.91 * sgn(v) + 0.2 * v;
    EXPECT_NEAR(f.evaluate({v, 5.0}, nullptr, nullptr), ref, 1e-12 * std::abs(ref)) << "v = " << v;
    EXPECT_NEAR(f.steadyState(v), ref, 1e-12 * std::abs(ref));
  }
  EXPECT_EQ(f.steadyState(0.0), 0.0);
  EXPECT_LE(std::abs(f.steadyState(5e-4)), 1.91 + 0.2 * 5e-4);  // regularised: never above F_C + F_v|v|
}

TEST(FrictionCoulombViscous, InertiaCoastsDownAsClosedForm) {
  // J v̇ = −F_C − b v from v0 > 0: v(t) = (v0 + F_C/b) e^{−bt/J} − F_C/b until the stop at
  // t* = (J/b) ln(1 + b v0/F_C); afterwards the regularised model holds v within v_reg of 0.
  const double J = 0.05, fc = 1.91, b = 0.2, v0 = 3.0;
  const CoulombViscousFriction f(CoulombViscousParams{fc, b, 1e-3});
  InertiaSim sim(
      f, J, [](double) { return 0.0; }, v0, tightOptions(1e-12));
  const double t_stop = (J / b) * std::log(1.0 + b * v0 / fc);
  for (double s : {0.25, 0.5, 0.9}) {
    const double t = s * t_stop;
    sim.advance(t);
    EXPECT_NEAR(sim.v(), (v0 + fc / b) * std::exp(-b * t / J) - fc / b, 1e-6 * v0) << "t = " << t;
  }
  sim.advance(2.0 * t_stop);
  EXPECT_LT(std::abs(sim.v()), 1e-3);
}

// ============================================================================ table friction ([Olsson2017, eq. 3.1])

TableFrictionParams joint1Table() {
  TableFrictionParams p;  // [Olsson2017, Table 4.1] joint 1: m = 0.1 N·m, k = 0.3 N·m·s/rad, peak 2
  p.tau_pos = {{{0.0, 0.1}}, {{1.0, 0.4}}};
  p.peak = 2.0;
  return p;
}

TEST(FrictionTable, StuckBelowPeakTimesM) {
  // Constant torques below peak·m (also between m and peak·m, where a sliding shaft would accelerate):
  // a shaft at rest stays at rest. One entering the band with v0 = v_stick/2 is caught: while
  // τ + d v > peak·m the clamp decelerates it at (peak·m − τ)/J down to v1 = (peak·m − τ)/d, then
  // J v̇ = −d v; total travel (v0² − v1²) J/(2(peak·m − τ)) + J v1/d (≤ 1.3e-7 rad here with the automatic
  // d_stick = 200 N·m·s/rad), where a free shaft would travel v0·1 s = 5e-4 rad.
  const TableFriction f(joint1Table());
  const double J = 1e-3, S = 0.2, d = 200.0;
  EXPECT_DOUBLE_EQ(f.stictionTorque(), S);
  EXPECT_DOUBLE_EQ(f.stickDamping(), d);
  for (double v0 : {0.0, 5e-4}) {
    for (double tau : {0.05, 0.15, 0.199, -0.15, -0.199}) {
      // atol 1e-12: in the band J v̇ = τ − τ_f is a cancellation with rounding noise ~ulp(τ), and a
      // tighter velocity tolerance makes CVODE's difference-quotient Jacobian meaningless.
      InertiaSim sim(
          f, J, [=](double) { return tau; }, v0, tightOptions(1e-12));
      sim.advance(1.0);
      double expected = 0.0;
      if (v0 > 0.0) {
        const double v1 = std::min(v0, (S - tau) / d);
        expected = (v0 * v0 - v1 * v1) * J / (2.0 * (S - tau)) + J * v1 / d;
      }
      EXPECT_NEAR(sim.q(), expected, 0.01 * expected + 1e-12) << "tau = " << tau << ", v0 = " << v0;
      EXPECT_LT(std::abs(sim.v()), 1e-10) << "tau = " << tau << ", v0 = " << v0;
    }
  }
}

TEST(FrictionTable, StickingBandRelaxesVelocityWithDStick) {
  // Inside the band with |τ + d v| < peak·m: J v̇ = −d v, so q(t) = (J v0/d)(1 − e^{−dt/J}).
  TableFrictionParams p = joint1Table();
  p.d_stick = 0.01;
  const TableFriction f(p);
  const double J = 1e-3, v0 = 5e-4;
  InertiaSim sim(
      f, J, [](double) { return 0.15; }, v0, tightOptions(1e-12));
  for (double t : {0.05, 0.2, 1.0}) {
    sim.advance(t);
    EXPECT_NEAR(sim.q(), (J * v0 / 0.01) * (1.0 - std::exp(-0.01 * t / J)), 1e-6 * J * v0 / 0.01) << "t = " << t;
  }
}

TEST(FrictionTable, BreaksAwayAbovePeakAndSlidesAtKOmegaPlusM) {
  // τ > peak·m: break-away, the friction drops to the table value (MSL semantics), so from rest
  // J v̇ = τ − (m + k v): v(t) = ((τ − m)/k)(1 − e^{−kt/J}); at constant velocity τ_f = k ω + m.
  const TableFriction f(joint1Table());
  const double J = 1e-3, m = 0.1, k = 0.3;
  for (double tau : {0.21, 0.25, -0.25}) {
    InertiaSim sim(
        f, J, [=](double) { return tau; }, 0.0, tightOptions(1e-12));
    const double w_ss = sgn(tau) * (std::abs(tau) - m) / k;
    for (double t : {1e-3, 5e-3, 0.1}) {
      sim.advance(t);
      EXPECT_NEAR(sim.v(), w_ss * (1.0 - std::exp(-k * t / J)), 1e-6 * std::abs(w_ss)) << "tau " << tau << " t " << t;
    }
    EXPECT_NEAR(sim.v(), w_ss, 1e-6 * std::abs(w_ss));
    EXPECT_NEAR(sim.frictionTorque(0.1), sgn(w_ss) * (k * std::abs(sim.v()) + m), 1e-12);
    EXPECT_NEAR(sim.frictionTorque(0.1), tau, 1e-6);
  }
}

TEST(FrictionTable, InterpolatesAndExtrapolatesLikeBearingFriction) {
  TableFrictionParams p;
  p.tau_pos = {{{0.0, 1.0}}, {{1.0, 3.0}}, {{2.0, 4.0}}};
  const TableFriction f(p);
  EXPECT_DOUBLE_EQ(f.steadyState(0.5), 2.0);
  EXPECT_DOUBLE_EQ(f.steadyState(1.5), 3.5);
  EXPECT_DOUBLE_EQ(f.steadyState(3.0), 5.0);  // last slope
  EXPECT_DOUBLE_EQ(f.steadyState(-1.5), -3.5);
  // [Olsson2017, §3.8] example tau_pos = [1, 3; 2, 5]: τ = 2ω + 1 for ω >= 0, so m = 1 by extrapolation.
  p.tau_pos = {{{1.0, 3.0}}, {{2.0, 5.0}}};
  p.peak = 1.5;
  const TableFriction g(p);
  EXPECT_DOUBLE_EQ(g.tau0(), 1.0);
  EXPECT_DOUBLE_EQ(g.stictionTorque(), 1.5);
  EXPECT_DOUBLE_EQ(g.steadyState(0.5), 2.0);
  EXPECT_DOUBLE_EQ(g.steadyState(3.0), 7.0);
  // Bad tables are rejected with the row named.
  p.tau_pos = {{{0.0, 1.0}}, {{0.0, 2.0}}};
  try {
    TableFriction h(p);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "tau_pos[1]"));
  }
  p = joint1Table();
  p.peak = 0.5;
  EXPECT_THROW(TableFriction{p}, InputError);
}

// ============================================================================ YAML front end

std::unique_ptr<Friction> parse(const std::string& text) {
  const auto doc = jointsim::io::YamlValue::loadString(text, "f.yaml");
  return jointsim::drive::frictionFromYaml(doc["friction"]);
}

std::string parseError(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FrictionYaml, EveryTypeParses) {
  auto cv = parse("friction: {type: coulomb_viscous, f_c: 1.91, f_v: 0.2}\n");
  EXPECT_EQ(cv->type(), "coulomb_viscous");
  EXPECT_NEAR(cv->steadyState(1.0), 2.11, 1e-12);

  auto table = parse("friction:\n  type: table\n  tau_pos: [[0, 0.1], [1, 0.4]]\n  peak: 2\n");
  EXPECT_EQ(table->type(), "table");
  EXPECT_NEAR(table->steadyState(0.5), 0.25, 1e-12);
  EXPECT_NEAR(dynamic_cast<const TableFriction&>(*table).stictionTorque(), 0.2, 1e-15);
  auto flat = parse("friction: {type: table, tau_pos: [0, 1.91]}\n");  // [KR300Thesis]: constant 1.91 N·m
  EXPECT_NEAR(flat->steadyState(-3.0), -1.91, 1e-15);

  auto stribeck = parse("friction:\n  type: stribeck\n"
                        "  positive: {alpha0: 7.9707, alpha1: 1.4476, alpha2: 4.9349, v_s: 0.0363}\n"
                        "  negative: {alpha0: 7.7538, alpha1: 0.8626, alpha2: 4.3267, v_s: 0.0221}\n");
  EXPECT_EQ(stribeck->type(), "stribeck");
  EXPECT_NEAR(stribeck->steadyState(-0.1), eq421(-0.1), 1e-9);
  EXPECT_NEAR(stribeck->steadyState(0.1), eq421(0.1), 1e-9);

  auto dahl = parse("friction: {type: dahl, sigma: 100, f_c: 2.5}\n");
  EXPECT_EQ(dahl->type(), "dahl");
  EXPECT_EQ(dahl->stateSize(), 1);
  EXPECT_EQ(dahl->steadyState(-1.0), -2.5);

  auto lugre = parse("friction: {type: lugre, sigma0: 259, sigma1: 10, alpha0: 5, alpha1: 1, alpha2: 2, v_s: 0.1}\n");
  EXPECT_EQ(lugre->type(), "lugre");
  EXPECT_EQ(lugre->stateNames(), std::vector<std::string>{"z[rad]"});
  EXPECT_NEAR(lugre->steadyState(-0.1), -(5.0 + std::exp(-1.0) + 0.2), 1e-12);  // symmetric set

  auto ur5 = parse("friction: {type: lugre_ur5, f_c: 10, f_v: 5, k_q: 1}\n");
  EXPECT_EQ(ur5->type(), "lugre_ur5");
  EXPECT_NEAR(ur5->steadyState(0.5), 10.0 * (1.0 + 0.3 * std::exp(-1.0)) + 5.0 * std::cbrt(0.25), 1e-12);
}

TEST(FrictionYaml, ErrorsNameFileLineAndKeyPath) {
  // Bad value (rule of validate(), relocated to the key).
  std::string e = parseError("friction:\n  type: lugre\n  sigma0: -5\n  sigma1: 10\n"
                             "  alpha0: 5\n  alpha1: 1\n  alpha2: 2\n  v_s: 0.1\n");
  EXPECT_TRUE(contains(e, "f.yaml:3: friction.sigma0: expected a finite value > 0 N·m/rad, got -5")) << e;
  EXPECT_TRUE(contains(e, "-5"));
  // Bad value in a per-direction mapping.
  e = parseError("friction:\n  type: stribeck\n"
                 "  positive: {alpha0: 1, alpha1: 1, alpha2: 0, v_s: 0.1}\n"
                 "  negative:\n    alpha0: 1\n    alpha1: 1\n    alpha2: 0\n    v_s: -0.1\n");
  EXPECT_TRUE(contains(e, "f.yaml:8: friction.negative.v_s: expected a finite value > 0 rad/s")) << e;
  // Symmetric set: the error points at the top-level key.
  e = parseError("friction:\n  type: lugre\n  sigma0: 1\n  sigma1: 1\n  alpha0: 0\n  alpha1: 1\n  alpha2: 2\n"
                 "  v_s: 0.1\n");
  EXPECT_TRUE(contains(e, "f.yaml:5: friction.alpha0:")) << e;
  // Bad table row.
  e = parseError("friction:\n  type: table\n  tau_pos:\n    - [0, 0.1]\n    - [0, 0.3]\n");
  EXPECT_TRUE(contains(e, "f.yaml:5: friction.tau_pos[1]: expected velocities strictly increasing")) << e;
  // Not a number.
  e = parseError("friction:\n  type: dahl\n  sigma: stiff\n  f_c: 1\n");
  EXPECT_TRUE(contains(e, "f.yaml:3: friction.sigma: expected rest stiffness sigma in N·m/rad")) << e;
  // Unknown key, with a suggestion.
  e = parseError("friction:\n  type: dahl\n  sigma: 1\n  f_c: 1\n  alpah: 1\n");
  EXPECT_TRUE(contains(e, "f.yaml:5: friction.alpah: unknown key 'alpah' (did you mean 'alpha'?)")) << e;
  // Missing key: reported at the mapping, with the unit.
  e = parseError("friction:\n  type: lugre_ur5\n  f_c: 10\n  f_v: 5\n");
  EXPECT_TRUE(contains(e, "f.yaml:2: friction: missing required key 'k_q'")) << e;
  e = parseError("friction:\n  type: coulomb_viscous\n  f_c: 1\n");
  EXPECT_TRUE(contains(e, "missing required key 'f_v' (viscous coefficient F_v in N·m·s/rad)")) << e;
  // Unknown type.
  e = parseError("friction:\n  type: lugre5\n");
  EXPECT_TRUE(contains(e, "f.yaml:2: friction.type: unknown friction type 'lugre5'")) << e;
  // Both forms of the static set.
  e = parseError("friction:\n  type: stribeck\n  alpha0: 1\n  positive: {alpha0: 1, alpha1: 1, alpha2: 0, v_s: 1}\n");
  EXPECT_TRUE(contains(e, "f.yaml:3: friction.alpha0: give the static parameters either")) << e;
}

}  // namespace
