// RobotR3 motor with op-amp current controller ([MSL, RobotR3.Utilities.Motor]): the derived constants table,
// the closed-loop second-order current response (CVODE vs closed form), the steady-state initial
// equations, a motor accelerating a pure inertia, the armature power balance and parameter validation.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/opamp_motor.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "test_util.hpp"

using namespace jointsim::drive;
using jointsim::sim::CvodeIntegrator;
using jointsim::sim::CvodeOptions;
using CRef = const Eigen::Ref<const Eigen::VectorXd>&;
using Ref = Eigen::Ref<Eigen::VectorXd>;

namespace {

constexpr double kPi = 3.14159265358979323846;

CvodeOptions tight() {
  CvodeOptions o;
  o.rtol = 1e-11;
  o.atol = 1e-12;
  o.component = "opamp motor test";
  return o;
}

double relErr(double a, double b) { return std::abs(a - b) / std::abs(b); }

/// Unit step response of w²/(s² + 2 D w s + w²) for 0 < D < 1, and its time derivative.
struct SecondOrderStep {
  double w, D;
  double y(double t) const {
    const double s = D * w, wd = w * std::sqrt(1.0 - D * D);
    return 1.0 - std::exp(-s * t) * (std::cos(wd * t) + s / wd * std::sin(wd * t));
  }
  double dy(double t) const {
    const double s = D * w, wd = w * std::sqrt(1.0 - D * D);
    return w * w / wd * std::exp(-s * t) * std::sin(wd * t);
  }
};

}  // namespace

TEST(OpAmpMotorParams, PresetsMatchAxisTable) {
  // Axis parameters of [MSL, RobotR3.FullRobot]: k, w, D, J per axis; w_max, i_max = 315, 9 (unused);
  // Ri, Ra, gain = 10, 250, 5.
  const double k[6] = {1.1616, 1.1616, 1.1616, 0.2365, 0.2608, 0.0842};
  const double w[6] = {4590, 5500, 5500, 6250, 6250, 7400};
  const double D[6] = {0.6, 0.6, 0.6, 0.55, 0.55, 0.27};
  const double J[6] = {0.0013, 0.0013, 0.0013, 1.6e-4, 1.8e-4, 4.3e-5};
  for (int a = 1; a <= 6; ++a) {
    SCOPED_TRACE("axis " + std::to_string(a));
    const auto p = OpAmpMotorParams::robotR3Axis(a);
    EXPECT_NO_THROW(p.validate());
    EXPECT_DOUBLE_EQ(p.k, k[a - 1]);
    EXPECT_DOUBLE_EQ(p.w, w[a - 1]);
    EXPECT_DOUBLE_EQ(p.D, D[a - 1]);
    EXPECT_DOUBLE_EQ(p.J, J[a - 1]);
    EXPECT_DOUBLE_EQ(p.Ri, 10.0);
    EXPECT_DOUBLE_EQ(p.Ra, 250.0);
    EXPECT_DOUBLE_EQ(p.amp_gain, 1.0 + 200.0 / 50.0);
    EXPECT_DOUBLE_EQ(p.w_max, 315.0);
    EXPECT_DOUBLE_EQ(p.i_max, 9.0);
  }
  // OneAxis ([MSL, RobotR3.OneAxis]): the axis-2 motor.
  const auto one = OpAmpMotorParams::oneAxis();
  EXPECT_DOUBLE_EQ(one.k, 1.1616);
  EXPECT_DOUBLE_EQ(one.w, 5500.0);
  EXPECT_DOUBLE_EQ(one.D, 0.6);
  EXPECT_DOUBLE_EQ(one.J, 0.0013);
  EXPECT_NEAR(one.C(), 4.363636e-7, 1e-6 * 4.363636e-7);
  EXPECT_NEAR(one.La(), 0.03787879, 1e-6 * 0.03787879);
  // Defaults of the MSL axis model: k = 1.1616, w = 4590, D = 0.6, J = 0.0013.
  const OpAmpMotorParams def;
  EXPECT_DOUBLE_EQ(def.k, 1.1616);
  EXPECT_DOUBLE_EQ(def.w, 4590.0);
  EXPECT_DOUBLE_EQ(def.D, 0.6);
  EXPECT_DOUBLE_EQ(def.J, 0.0013);
}

TEST(OpAmpMotorParams, DerivedConstantsTable) {
  // Per-axis electrical constants derived from [MSL, RobotR3.Utilities.Motor]: C, La, 1/(Ri C), 5/(Ri C).
  struct Row {
    int axis;
    double C, La, invRiC, fiveRiC;
  };
  const std::vector<Row> table = {
      {1, 5.228758e-7, 0.04538853, 191250.0, 956250.0},   {2, 4.363636e-7, 0.03787879, 229166.67, 1145833.3},
      {3, 4.363636e-7, 0.03787879, 229166.67, 1145833.3}, {4, 3.52e-7, 0.03636364, 284090.91, 1420454.5},
      {5, 3.52e-7, 0.03636364, 284090.91, 1420454.5},     {6, 1.459459e-7, 0.06256256, 685185.19, 3425925.9},
  };
  for (const auto& r : table) {
    SCOPED_TRACE("axis " + std::to_string(r.axis));
    const auto p = OpAmpMotorParams::robotR3Axis(r.axis);
    EXPECT_LE(relErr(p.C(), r.C), 1e-6) << p.C();
    EXPECT_LE(relErr(p.La(), r.La), 1e-6) << p.La();
    EXPECT_LE(relErr(1.0 / (p.Ri * p.C()), r.invRiC), 1e-6);
    EXPECT_LE(relErr(p.amp_gain / (p.Ri * p.C()), r.fiveRiC), 1e-6);
    // Node-analysis consequences: Ra/La = 2 D w and 5/(Ri C La) = w² (exact for the MSL constants).
    EXPECT_LE(relErr(p.Ra / p.La(), 2.0 * p.D * p.w), 1e-14);
    EXPECT_LE(relErr(p.amp_gain / (p.Ri * p.C() * p.La()), p.w * p.w), 1e-14);
    // ... which is the characteristic polynomial s² + 2 D w s + w² of the state matrix.
    const OpAmpMotor m(p);
    const Eigen::Matrix2d A = m.stateJacobian();
    EXPECT_LE(relErr(-A.trace(), 2.0 * p.D * p.w), 1e-14);
    EXPECT_LE(relErr(A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0), p.w * p.w), 1e-14);
  }
}

TEST(OpAmpMotor, DerivativesAreTheNodeEquations) {
  const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(4));
  const auto& p = m.params();
  const double i_ref = 1.7, omega = -23.0, v_C = 12.5, i = -0.4;
  Eigen::Vector2d x(v_C, i), xd;
  m.derivatives(i_ref, omega, x, xd);
  // Node voltages ([MSL, RobotR3.Utilities.Motor]): v(N_d) = i − i_ref, capacitor current v(N_d)/Ri, v(N_o) = −5 v_C.
  const double vNd = i - i_ref;
  EXPECT_NEAR(xd[OpAmpMotor::kVC], vNd / p.Ri / p.C(), 1e-12 * std::abs(xd[0]));
  EXPECT_NEAR(m.armatureVoltage(v_C), -5.0 * v_C, 1e-15);
  EXPECT_NEAR(xd[OpAmpMotor::kI], (m.armatureVoltage(v_C) - p.Ra * i - m.emfVoltage(omega)) / p.La(),
              1e-12 * std::abs(xd[1]));
  EXPECT_DOUBLE_EQ(m.torque(i), p.k * i);
  // Linear: xdot = A x + b_iref i_ref + b_omega omega.
  const Eigen::Vector2d lin = m.stateJacobian() * x + m.inputJacobianIref() * i_ref + m.inputJacobianOmega() * omega;
  EXPECT_TRUE(jointsim::test::MatricesNear(xd / xd.norm(), lin / xd.norm(), 1e-14));
  // In-place evaluation (x and xdot alias).
  Eigen::Vector2d y = x;
  m.derivatives(i_ref, omega, y, y);
  EXPECT_TRUE(jointsim::test::MatricesNear(y / xd.norm(), xd / xd.norm(), 1e-15));
}

TEST(OpAmpMotor, CurrentStepIsSecondOrderResponse) {
  // ω_m = 0 (locked rotor): i/i_ref = w²/(s² + 2 D w s + w²). From rest, a step of I amperes gives
  // i(t) = I·y(t) and v_C = −u = −(La di/dt + Ra i)/5.
  const double I = 2.0;
  for (int a = 1; a <= 6; ++a) {
    SCOPED_TRACE("axis " + std::to_string(a));
    const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(a));
    const auto& p = m.params();
    const SecondOrderStep step{p.w, p.D};
    CvodeIntegrator integ(
        2, [&](double, CRef y, Ref yd) { m.derivatives(I, 0.0, y, yd); }, tight());
    integ.initialize(0.0, m.steadyState(0.0, 0.0));
    Eigen::VectorXd y(2);
    const double v_scale = p.Ra * I / p.amp_gain;  // |v_C| at the final steady state
    const double T = 12.0 / (p.D * p.w);
    double worst_i = 0.0, worst_v = 0.0;
    for (int n = 1; n <= 400; ++n) {
      const double t = T * n / 400.0;
      integ.advance(t, y);
      const double i_ex = I * step.y(t);
      const double vC_ex = -(p.La() * I * step.dy(t) + p.Ra * i_ex) / p.amp_gain;
      worst_i = std::max(worst_i, std::abs(y[1] - i_ex) / I);
      worst_v = std::max(worst_v, std::abs(y[0] - vC_ex) / v_scale);
    }
    EXPECT_LE(worst_i, 1e-6);
    EXPECT_LE(worst_v, 1e-6);
    // Overshoot of the step (underdamped loop): exp(−π D/√(1−D²)).
    const double t_peak = kPi / (p.w * std::sqrt(1.0 - p.D * p.D));
    integ.initialize(0.0, m.steadyState(0.0, 0.0));
    integ.advance(t_peak, y);
    EXPECT_LE(std::abs(y[1] / I - 1.0 - std::exp(-kPi * p.D / std::sqrt(1.0 - p.D * p.D))), 1e-6);
  }
}

TEST(OpAmpMotor, ConstantSpeedBackEmfIsRejected) {
  // The loop is linear: starting from the steady state at a constant rotor speed, the current step
  // response is the locked-rotor one; v_C is shifted by −k ω/5.
  const OpAmpMotor m(OpAmpMotorParams::oneAxis());
  const auto& p = m.params();
  const double I = -1.25, omega = 150.0;
  const SecondOrderStep step{p.w, p.D};
  CvodeIntegrator integ(
      2, [&](double, CRef y, Ref yd) { m.derivatives(I, omega, y, yd); }, tight());
  integ.initialize(0.0, m.steadyState(0.0, omega));
  Eigen::VectorXd y(2);
  const double v_scale = std::abs(m.steadyState(I, omega)[0]);
  for (double t : {1e-4, 3e-4, 7e-4, 2e-3, 5e-3}) {
    integ.advance(t, y);
    const double i_ex = I * step.y(t);
    const double vC_ex = -(p.La() * I * step.dy(t) + p.Ra * i_ex + p.k * omega) / p.amp_gain;
    EXPECT_NEAR(y[1], i_ex, 1e-6 * std::abs(I)) << "t = " << t;
    EXPECT_NEAR(y[0], vC_ex, 1e-6 * v_scale) << "t = " << t;
  }
}

TEST(OpAmpMotor, SteadyStateInitialEquations) {
  // The Motor's steady-state initial equations ([MSL, RobotR3.Utilities.Motor]): dv_C/dt = 0 ⇒ i = i_ref;
  // di/dt = 0 ⇒ v_C = −(Ra i + k ω_m)/5 (= −50 i at rest).
  // FullRobot t = 0 rows (sa(0) = 0; docs/validation.md): i(0) → v_C(0).
  struct Row {
    int axis;
    double i0, vC0;
  };
  for (const Row& r : {Row{2, -1.888091, 94.40457}, Row{3, -3.678835, 183.9417}, Row{4, -0.6004244, 30.02122},
                       Row{5, -0.7242793, 36.21397}}) {
    const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(r.axis));
    const Eigen::Vector2d x = m.steadyState(r.i0, 0.0);
    EXPECT_DOUBLE_EQ(x[OpAmpMotor::kI], r.i0);
    EXPECT_LE(relErr(x[OpAmpMotor::kVC], r.vC0), 1e-6) << "axis " << r.axis << ": " << x[0];
  }
  // At any speed the derivatives vanish with i_ref = i, and a simulation stays put.
  const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(6));
  const auto& p = m.params();
  for (double i : {-3.0, 0.0, 0.8}) {
    for (double omega : {-200.0, 0.0, 31.4}) {
      const Eigen::Vector2d x = m.steadyState(i, omega);
      EXPECT_NEAR(x[0], -(p.Ra * i + p.k * omega) / 5.0, 1e-12 * (1.0 + std::abs(x[0])));
      Eigen::Vector2d xd;
      m.derivatives(i, omega, x, xd);
      EXPECT_EQ(xd[0], 0.0);
      EXPECT_NEAR(xd[1], 0.0, 1e-9 * p.Ra * (1.0 + std::abs(i)) / p.La());
    }
  }
  const double i0 = 0.8, om = 31.4;
  CvodeIntegrator integ(
      2, [&](double, CRef y, Ref yd) { m.derivatives(i0, om, y, yd); }, tight());
  const Eigen::Vector2d x0 = m.steadyState(i0, om);
  integ.initialize(0.0, x0);
  Eigen::VectorXd y(2);
  integ.advance(0.01, y);
  EXPECT_TRUE(jointsim::test::MatricesNear(y, x0, 1e-9));
}

TEST(OpAmpMotor, AcceleratesInertiaAfterCurrentTransient) {
  // Rotor inertia J driven by k i only: J dω/dt = k i. Laplace: (La s² + Ra s + K + k²/J) I = K I_ref,
  // K = 5/(Ri C). The back-EMF ramp leaves a small constant current error: i_∞ = I_ref K / K'
  // (K' = K + k²/J), and i(t) is a second-order step with w'² = K'/La, 2 D' w' = Ra/La. After the
  // transient ω(t) = k i_∞ (t − Ra/K') / J, i.e. ω = k i t / J up to the lag Ra/K' of the current.
  const double I_ref = 1.0;
  for (int a : {1, 4, 6}) {
    SCOPED_TRACE("axis " + std::to_string(a));
    const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(a));
    const auto& p = m.params();
    const double K = p.amp_gain / (p.Ri * p.C());
    const double Kp = K + p.k * p.k / p.J;
    const double i_inf = I_ref * K / Kp;
    const double wp = std::sqrt(Kp / p.La());
    const SecondOrderStep step{wp, p.Ra / p.La() / (2.0 * wp)};
    const double lag = p.Ra / Kp;

    CvodeIntegrator integ(
        3,
        [&](double, CRef y, Ref yd) {
          m.derivatives(I_ref, y[2], y.head<2>(), yd.head<2>());
          yd[2] = m.torque(y[1]) / p.J;
        },
        tight());
    Eigen::VectorXd y0 = Eigen::VectorXd::Zero(3);
    y0.head<2>() = m.steadyState(0.0, 0.0);
    integ.initialize(0.0, y0);
    Eigen::VectorXd y(3);
    const double t_settle = 25.0 / (p.D * p.w);
    std::vector<double> times = {0.2 * t_settle, t_settle, 2 * t_settle, 0.03, 0.05, 0.1};
    std::sort(times.begin(), times.end());
    for (double t : times) {
      integ.advance(t, y);
      EXPECT_NEAR(y[1], i_inf * step.y(t), 1e-6 * I_ref) << "t = " << t;
      if (t >= t_settle) {
        EXPECT_LE(relErr(y[2], p.k * i_inf * (t - lag) / p.J), 1e-6) << "t = " << t << ", ω = " << y[2];
        // The naive k i t / J with the present current: off by the lag only.
        EXPECT_LE(relErr(y[2], p.k * y[1] * t / p.J), 1.01 * lag / t);
      }
    }
    EXPECT_LT(1.0 - i_inf / I_ref, 2e-3);  // back-EMF offset of the current is small
  }
}

TEST(OpAmpMotor, ArmaturePowerBalance) {
  // Electrical power into the armature 5·u·i (u = −v_C) = Ra i² + k ω i + d/dt(½ La i²), along a
  // trajectory of the motor driving its rotor inertia (plus a viscous load) with a varying i_ref.
  // Quadratures: E_el = ∫5 u i, E_R = ∫Ra i², E_m = ∫k ω i; also E_m = ½ J ω² + ∫b ω².
  const OpAmpMotor m(OpAmpMotorParams::robotR3Axis(5));
  const auto& p = m.params();
  const double b = 2e-4;  // viscous load [N·m·s/rad]
  auto i_ref = [](double t) {
    return 0.5 + 1.5 * std::sin(2.0 * kPi * 50.0 * t) - 0.7 * std::cos(2.0 * kPi * 130.0 * t);
  };
  // States: v_C, i, ω, E_el, E_R, E_m, E_b.
  auto rhs = [&](double t, CRef y, Ref yd) {
    m.derivatives(i_ref(t), y[2], y.head<2>(), yd.head<2>());
    const double i = y[1], w = y[2];
    yd[2] = (m.torque(i) - b * w) / p.J;
    yd[3] = m.armatureVoltage(y[0]) * i;
    yd[4] = p.Ra * i * i;
    yd[5] = p.k * w * i;
    yd[6] = b * w * w;
  };
  CvodeIntegrator integ(7, rhs, tight());
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(7);
  y0.head<2>() = m.steadyState(i_ref(0.0), 0.0);
  integ.initialize(0.0, y0);
  Eigen::VectorXd y(7), yd(7);
  double E_scale = 0.0;
  for (int n = 1; n <= 60; ++n) {
    const double t = 1e-3 * n;
    integ.advance(t, y);
    const double i = y[1], w = y[2];
    // Pointwise: 5 u i − Ra i² − k ω i − La i di/dt = 0.
    rhs(t, y, yd);
    const double P_el = m.armatureVoltage(y[0]) * i;
    const double P_scale = std::abs(P_el) + p.Ra * i * i + std::abs(p.k * w * i);
    EXPECT_NEAR(P_el - p.Ra * i * i - p.k * w * i - p.La() * i * yd[1], 0.0, 1e-12 * P_scale) << "t = " << t;
    // Integrated: E_el = E_R + E_m + ½ La (i² − i0²);  E_m = ½ J ω² + E_b.
    E_scale = std::max(E_scale, std::abs(y[3]) + y[4]);
    const double mag = 0.5 * p.La() * (i * i - y0[1] * y0[1]);
    EXPECT_NEAR(y[3], y[4] + y[5] + mag, 1e-7 * E_scale) << "t = " << t;
    EXPECT_NEAR(y[5], 0.5 * p.J * w * w + y[6], 1e-7 * E_scale) << "t = " << t;
  }
  EXPECT_GT(E_scale, 1.0);  // a non-trivial amount of energy went through
}

TEST(OpAmpMotorParams, ValidationErrors) {
  using jointsim::InputError;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Field {
    const char* name;
    double OpAmpMotorParams::*ptr;
  };
  const Field fields[] = {{"J", &OpAmpMotorParams::J},
                          {"k", &OpAmpMotorParams::k},
                          {"w", &OpAmpMotorParams::w},
                          {"D", &OpAmpMotorParams::D},
                          {"Ri", &OpAmpMotorParams::Ri},
                          {"Ra", &OpAmpMotorParams::Ra},
                          {"amp_gain", &OpAmpMotorParams::amp_gain},
                          {"w_max", &OpAmpMotorParams::w_max},
                          {"i_max", &OpAmpMotorParams::i_max}};
  for (const Field& f : fields) {
    for (double bad : {0.0, -1.0, nan, inf}) {
      OpAmpMotorParams p = OpAmpMotorParams::oneAxis();
      p.*(f.ptr) = bad;
      try {
        p.validate();
        ADD_FAILURE() << f.name << " = " << bad << " accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(std::string("op-amp motor: ") + f.name + ": expected a finite value > 0"),
                  std::string::npos)
            << e.what();
      }
      EXPECT_THROW(OpAmpMotor{p}, InputError) << f.name;
    }
  }
  EXPECT_THROW(OpAmpMotorParams::robotR3Axis(0), InputError);
  EXPECT_THROW(OpAmpMotorParams::robotR3Axis(7), InputError);
  const OpAmpMotor m(OpAmpMotorParams::oneAxis());
  Eigen::VectorXd x3 = Eigen::VectorXd::Zero(3), xd2(2), xd3(3);
  EXPECT_THROW(m.derivatives(0.0, 0.0, x3, xd2), InputError);
  EXPECT_THROW(m.derivatives(0.0, 0.0, x3.head(2), xd3), InputError);
}
