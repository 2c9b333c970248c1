#include "jointsim/drive/opamp_motor.hpp"

#include <cmath>
#include <string>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::drive {

void OpAmpMotorParams::validate() const {
  auto positive = [](double v, const char* name, const char* unit) { check::positive("op-amp motor", name, v, unit); };
  positive(J, "J", "kg·m²");
  positive(k, "k", "N·m/A");
  positive(w, "w", "rad/s");
  positive(D, "D", "(dimensionless)");
  positive(Ri, "Ri", "Ω");
  positive(Ra, "Ra", "Ω");
  positive(amp_gain, "amp_gain", "(dimensionless)");
  positive(w_max, "w_max", "rad/s");
  positive(i_max, "i_max", "A");
}

OpAmpMotorParams OpAmpMotorParams::robotR3Axis(int axis) {
  // Axis parameters of [MSL, RobotR3.FullRobot].
  static const double k[6] = {1.1616, 1.1616, 1.1616, 0.2365, 0.2608, 0.0842};
  static const double w[6] = {4590, 5500, 5500, 6250, 6250, 7400};
  static const double D[6] = {0.6, 0.6, 0.6, 0.55, 0.55, 0.27};
  static const double J[6] = {0.0013, 0.0013, 0.0013, 1.6e-4, 1.8e-4, 4.3e-5};
  if (axis < 1 || axis > 6) throw InputError("RobotR3 motor: axis must be 1..6, got " + std::to_string(axis));
  OpAmpMotorParams p;
  p.k = k[axis - 1];
  p.w = w[axis - 1];
  p.D = D[axis - 1];
  p.J = J[axis - 1];
  return p;
}

OpAmpMotorParams OpAmpMotorParams::oneAxis() { return robotR3Axis(2); }

OpAmpMotor::OpAmpMotor(const OpAmpMotorParams& params) : p_(params) {
  p_.validate();
  inv_RiC_ = 1.0 / (p_.Ri * p_.C());
  inv_La_ = 1.0 / p_.La();
}

void OpAmpMotor::derivatives(double i_ref, double omega_m, const Eigen::Ref<const Eigen::VectorXd>& x,
                             Eigen::Ref<Eigen::VectorXd> xdot) const {
  if (x.size() != kNumStates || xdot.size() != kNumStates)
    throw InputError("OpAmpMotor::derivatives: x and xdot must have size 2, got " + std::to_string(x.size()) + " and " +
                     std::to_string(xdot.size()));
  const double v_C = x[kVC];
  const double i = x[kI];
  const double dv = (i - i_ref) * inv_RiC_;
  const double di = (-p_.amp_gain * v_C - p_.Ra * i - p_.k * omega_m) * inv_La_;
  xdot[kVC] = dv;
  xdot[kI] = di;
}

Eigen::Matrix2d OpAmpMotor::stateJacobian() const {
  Eigen::Matrix2d A;
  A(kVC, kVC) = 0.0;
  A(kVC, kI) = inv_RiC_;
  A(kI, kVC) = -p_.amp_gain * inv_La_;
  A(kI, kI) = -p_.Ra * inv_La_;
  return A;
}

Eigen::Vector2d OpAmpMotor::inputJacobianIref() const { return Eigen::Vector2d(-inv_RiC_, 0.0); }

Eigen::Vector2d OpAmpMotor::inputJacobianOmega() const { return Eigen::Vector2d(0.0, -p_.k * inv_La_); }

Eigen::Vector2d OpAmpMotor::steadyState(double i, double omega_m) const {
  Eigen::Vector2d x;
  x[kVC] = -(p_.Ra * i + p_.k * omega_m) / p_.amp_gain;
  x[kI] = i;
  return x;
}

}  // namespace jointsim::drive
