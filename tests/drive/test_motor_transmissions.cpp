// DC motor electrics, elastic and elasto-backlash gears and the coupling matrix against closed forms,
// the Modelica ElastoBacklash properties, and passivity of free two-inertia systems simulated with CVODE.
#include <cmath>
#include <functional>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "test_util.hpp"

using namespace jointsim::drive;
using jointsim::sim::CvodeIntegrator;
using jointsim::sim::CvodeOptions;
using CRef = const Eigen::Ref<const Eigen::VectorXd>&;
using Ref = Eigen::Ref<Eigen::VectorXd>;

namespace {
CvodeOptions tight() {
  CvodeOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  return o;
}
}  // namespace

TEST(DcMotor, LockedRotorCurrentStep) {
  const DcMotor motor(DcMotorParams::ur5(1));
  const auto& p = motor.params();
  const double V = 12.0;
  CvodeIntegrator integ(
      1, [&](double, CRef y, Ref yd) { yd[0] = motor.currentDerivative(y[0], V, 0.0); }, tight());
  integ.initialize(0.0, Eigen::VectorXd::Zero(1));
  Eigen::VectorXd y(1);
  for (double t : {0.5e-3, 1e-3, 2.77e-3, 1e-2}) {
    integ.advance(t, y);
    const double exact = V / p.R * (1.0 - std::exp(-t * p.R / p.L));
    EXPECT_NEAR(y[0], exact, 1e-7 * V / p.R) << "t = " << t;
  }
  EXPECT_DOUBLE_EQ(motor.torque(2.0), 2.0 * p.kt);
}

TEST(DcMotor, FreeRunningSteadySpeedByHand) {
  // Rotor J_M with viscous load b: steady state k_t i = b ω and V = R i + k_e ω
  // ⇒ ω = k_t V / (R b + k_t k_e). With k_e ≠ k_t to check that both constants enter where they should.
  DcMotorParams p = DcMotorParams::ur5(4);
  p.ke = 0.08;
  const DcMotor motor(p);
  const double V = 24.0, b = 1e-4;
  CvodeIntegrator integ(
      2,
      [&](double, CRef y, Ref yd) {
        yd[0] = motor.currentDerivative(y[0], V, y[1]);
        yd[1] = (motor.torque(y[0]) - b * y[1]) / p.J_M;
      },
      tight());
  integ.initialize(0.0, Eigen::VectorXd::Zero(2));
  Eigen::VectorXd y(2);
  integ.advance(5.0, y);  // mechanical time constant J R / (R b + kt ke) ≈ 5 ms
  EXPECT_NEAR(y[1], p.kt * V / (p.R * b + p.kt * p.ke), 1e-6 * y[1]);
  EXPECT_NEAR(motor.steadySpeed(V), V / p.ke, 1e-12);
}

TEST(DcMotor, SupplySaturatesAndValidates) {
  const DcMotor motor(DcMotorParams::ur5(2));
  EXPECT_DOUBLE_EQ(motor.supplyVoltage(100.0), 48.0);
  EXPECT_DOUBLE_EQ(motor.supplyVoltage(-100.0), -48.0);
  EXPECT_DOUBLE_EQ(motor.supplyVoltage(10.0), 10.0);
  DcMotorParams bad;
  bad.L = -1;
  EXPECT_THAT([&] { DcMotor m(bad); }, ::testing::ThrowsMessage<jointsim::InputError>(
                                           ::testing::HasSubstr("motor: L: expected a finite value > 0 H, got -1")));
}

TEST(ElastoBacklash, ZeroInGapSlopeOutsideNeverWrongSign) {
  ElastoBacklashParams p;
  p.stiffness = 25.7;
  p.damping = 3.0;
  p.backlash = 0.0102;
  const ElastoBacklash eb(p);
  // Inside the gap: exactly zero whatever the rate.
  for (double d : {-0.0050, -0.002, 0.0, 0.003, 0.0050})
    for (double v : {-5.0, 0.0, 5.0}) EXPECT_EQ(eb.contactTorque(d, v), 0.0);
  // Outside, with zero rate: slope c and offset b/2.
  for (double d : {0.006, 0.02, 0.3}) {
    EXPECT_NEAR(eb.contactTorque(d, 0.0), 25.7 * (d - 0.0051), 1e-12);
    EXPECT_NEAR(eb.contactTorque(-d, 0.0), -25.7 * (d - 0.0051), 1e-12);
    EXPECT_NEAR((eb.contactTorque(d + 1e-6, 0) - eb.contactTorque(d - 1e-6, 0)) / 2e-6, 25.7, 1e-6);
  }
  // Never of the wrong sign and the damper part never exceeds the spring part.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> D(-0.05, 0.05), V(-10.0, 10.0);
  for (int k = 0; k < 20000; ++k) {
    const double d = D(rng), v = V(rng), tau = eb.contactTorque(d, v);
    const double spring = std::abs(d) > 0.0051 ? 25.7 * (std::abs(d) - 0.0051) : 0.0;
    if (d > 0) {
      EXPECT_GE(tau, 0.0);
    } else {
      EXPECT_LE(tau, 0.0);
    }
    EXPECT_LE(std::abs(tau), 2.0 * spring + 1e-12);
  }
  // Continuous at contact onset even with a large closing speed.
  EXPECT_NEAR(eb.contactTorque(0.0051 + 1e-9, 100.0), 0.0, 1e-6);
}

TEST(ElastoBacklash, MotorAndOutputSideParametersAreEquivalent) {
  const double N = 101;
  ElastoBacklashParams m{N, 25.7, 0.4, 0.0102, ComplianceSide::Motor};
  ElastoBacklashParams o{N, 25.7 * N * N, 0.4 * N * N, 0.0102 / N, ComplianceSide::Output};
  const ElastoBacklash a(m), b(o);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int k = 0; k < 1000; ++k) {
    const ShaftPorts s{N * 0.01 * U(rng), U(rng), 0.01 * U(rng), U(rng) / N};
    const PortTorques ta = a.evaluate(s, nullptr, nullptr), tb = b.evaluate(s, nullptr, nullptr);
    EXPECT_NEAR(ta.tau_in, tb.tau_in, 1e-9 * (1 + std::abs(ta.tau_in)));
    EXPECT_NEAR(ta.tau_out, tb.tau_out, 1e-9 * (1 + std::abs(ta.tau_out)));
    EXPECT_NEAR(ta.tau_out, N * ta.tau_in, 1e-12 * (1 + std::abs(ta.tau_out)));
    EXPECT_NEAR(a.storedEnergy(s, nullptr), b.storedEnergy(s, nullptr), 1e-9);
  }
}

namespace {
// Two free inertias joined by a transmission, no input: returns the largest energy increase between
// consecutive samples and the initial energy.
struct PassivityResult {
  double max_increase, E0, E_end;
};
PassivityResult freeTwoInertias(const Transmission& tr, double Jm, double Jl, double qd_in0, double t_end,
                                jointsim::sim::Method method = jointsim::sim::Method::BDF) {
  CvodeOptions options = tight();
  options.method = method;
  auto energy = [&](const Eigen::VectorXd& y) {
    const ShaftPorts s{y[0], y[1], y[2], y[3]};
    return 0.5 * Jm * y[1] * y[1] + 0.5 * Jl * y[3] * y[3] + tr.storedEnergy(s, nullptr);
  };
  CvodeIntegrator integ(
      4,
      [&](double, CRef y, Ref yd) {
        const PortTorques t = tr.evaluate({y[0], y[1], y[2], y[3]}, nullptr, nullptr);
        yd << y[1], -t.tau_in / Jm, y[3], t.tau_out / Jl;
      },
      options);
  Eigen::VectorXd y(4);
  y << 0.0, qd_in0, 0.0, 0.0;
  integ.initialize(0.0, y);
  PassivityResult r{0.0, energy(y), 0.0};
  double prev = r.E0;
  for (int k = 1; k <= 2000; ++k) {
    integ.advance(t_end * k / 2000.0, y);
    const double E = energy(y);
    r.max_increase = std::max(r.max_increase, E - prev);
    prev = E;
  }
  r.E_end = prev;
  return r;
}
}  // namespace

TEST(TransmissionPassivity, ElasticAndBacklashNeverGainEnergy) {
  const ElasticGear elastic({50.0, 30.0, 0.05, ComplianceSide::Motor});
  const ElastoBacklash backlash({50.0, 30.0, 0.05, 0.02, ComplianceSide::Motor});
  for (const Transmission* tr :
       {static_cast<const Transmission*>(&elastic), static_cast<const Transmission*>(&backlash)}) {
    const PassivityResult r = freeTwoInertias(*tr, 1e-3, 2.0, 20.0, 2.0);
    EXPECT_LT(r.max_increase, 1e-9 * r.E0) << tr->type();
    EXPECT_LT(r.E_end, r.E0) << tr->type() << ": damping must dissipate";
  }
  // Undamped elastic gear: energy conserved to integration accuracy. Adams: BDF at rtol 1e-10 loses
  // ~3e-6 of the energy of this 41 Hz mode over 2 s by numerical dissipation (measured).
  const ElasticGear lossless({50.0, 30.0, 0.0, ComplianceSide::Motor});
  const PassivityResult r = freeTwoInertias(lossless, 1e-3, 2.0, 20.0, 2.0, jointsim::sim::Method::Adams);
  EXPECT_NEAR(r.E_end, r.E0, 2e-6 * r.E0);  // global error of rtol 1e-10 over ~80 periods
}

TEST(ElasticGear, TwoMassFrequencyMatchesClosedForm) {
  // Output-side stiffness K between J_l and the reflected rotor N² J_m: ω² = K (1/J_l + 1/(N² J_m)).
  const double N = 10, K = 400, Jm = 0.01, Jl = 3.5;
  const ElasticGear gear({N, K, 0.0, ComplianceSide::Output});
  CvodeIntegrator integ(
      4,
      [&](double, CRef y, Ref yd) {
        const PortTorques t = gear.evaluate({y[0], y[1], y[2], y[3]}, nullptr, nullptr);
        yd << y[1], -t.tau_in / Jm, y[3], t.tau_out / Jl;
      },
      tight());
  Eigen::VectorXd y(4);
  y << 0.1 * N, 0, 0, 0;  // deflected, at rest
  integ.initialize(0, y);
  // Count the zero crossings of the deflection over 2 s.
  double prev = 0.1, t_prev = 0;
  std::vector<double> crossings;
  for (int k = 1; k <= 20000; ++k) {
    const double t = 2.0 * k / 20000;
    integ.advance(t, y);
    const double d = y[0] / N - y[2];
    if ((d > 0) != (prev > 0)) crossings.push_back(t_prev + (t - t_prev) * prev / (prev - d));
    prev = d;
    t_prev = t;
  }
  ASSERT_GE(crossings.size(), 4u);
  const double period = 2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  const double w = std::sqrt(K * (1.0 / Jl + 1.0 / (N * N * Jm)));
  EXPECT_NEAR(2 * M_PI / period, w, 1e-4 * w);
}

TEST(CouplingMatrix, Irb140WristInverseAndPower) {
  const CouplingMatrix G(CouplingMatrix::irb140Wrist());
  // Exact rational G derived from [Olsson2017, Listing 4.1]: G⁻¹ with G⁻¹₂₁ = −71/22 and G⁻¹₃₁ = −64/22 exactly.
  const Eigen::Vector3d motors = G.motorAngles(Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR(motors[0], 60.4454545455, 1e-9);
  EXPECT_NEAR(motors[1], -71.0 / 22.0, 1e-9);
  EXPECT_NEAR(motors[2], -64.0 / 22.0, 1e-9);
  const Eigen::Vector3d m2 = G.motorAngles(Eigen::Vector3d(0, 1, 0));
  EXPECT_NEAR(m2[1], 65.1018808777, 1e-9);
  EXPECT_NEAR(m2[2], -58.6833855799, 1e-9);
  EXPECT_NEAR(G.motorAngles(Eigen::Vector3d(0, 0, 1))[2], 61.0307210031, 1e-9);
  // Power: q̇_jointᵀ τ_joint = q̇_motorᵀ τ_motor.
  const Eigen::Vector3d qd_m(100, -50, 30), tau_j(4, -2, 1);
  EXPECT_NEAR(G.jointAngles(qd_m).dot(tau_j), qd_m.dot(G.motorTorques(tau_j)), 1e-12);
  EXPECT_TRUE(jointsim::test::MatricesNear(G.jointTorques(G.motorTorques(tau_j)), tau_j, 1e-12));
  EXPECT_THROW(CouplingMatrix{Eigen::Matrix2d::Zero()}, jointsim::InputError);
}
