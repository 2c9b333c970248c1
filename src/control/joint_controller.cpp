#include "jointsim/control/joint_controller.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::control {

void JointControllerParams::validate(const std::string& where) const {
  auto nonneg = [&](double v, const char* name) { check::nonNegative(where, name, v, "(a gain)"); };
  if (type == ControllerType::VoltageCascade) {
    nonneg(P_pos, "P_pos");
    nonneg(P_vel, "P_vel");
    nonneg(I_vel, "I_vel");
    nonneg(P_cur, "P_cur");
    nonneg(I_cur, "I_cur");
  } else if (type == ControllerType::TorqueCascade) {
    nonneg(kp, "kp");
    nonneg(ks, "ks");
    check::positive(where, "Ts", Ts, "s");
  }
}

double velocityPi(double kp, double ki, double limit, double e, double x, double& xdot) {
  const double raw = kp * e + ki * x;
  const bool winding_up = (raw > limit && e > 0) || (raw < -limit && e < 0);
  xdot = winding_up ? 0.0 : e;
  return std::clamp(raw, -limit, limit);
}

JointController JointController::torqueCascade(double kp, double ks, double Ts) {
  JointControllerParams p;
  p.type = ControllerType::TorqueCascade;
  p.kp = kp;
  p.ks = ks;
  p.Ts = Ts;
  return JointController(p);
}

int JointController::stateSize() const {
  switch (p_.type) {
    case ControllerType::VoltageCascade: return 2;
    case ControllerType::TorqueCascade: return 1;
    default: return 0;
  }
}

void JointController::initialState(const ControllerInputs& in, double* x) const {
  if (p_.type == ControllerType::VoltageCascade) {
    x[0] = x[1] = 0.0;
  } else if (p_.type == ControllerType::TorqueCascade) {
    const double u = in.ratio * in.qd_set + p_.kp * (in.qm_offset + in.ratio * in.q_set - in.qm_fb) - in.qdm_fb;
    x[0] = -u;  // InitialOutput: y(0) = 0
  }
}

ControllerOutputs JointController::evaluate(const ControllerInputs& in, const double* x, double* xdot) const {
  ControllerOutputs out;
  switch (p_.type) {
    case ControllerType::VoltageCascade: {
      out.voltage = true;
      const bool velocity_loop = in.entry != ControlEntry::Current;
      double e_vel = 0.0;
      if (velocity_loop) {
        out.qdm_ref = in.entry == ControlEntry::MotorVelocity ? in.command
                                                              : p_.P_pos * (in.q_set - in.q_fb) + in.ratio * in.qd_set;
        e_vel = out.qdm_ref - in.qdm_fb;
        out.i_ref = p_.P_vel * e_vel + p_.I_vel * x[0];
      } else {
        out.i_ref = in.command;
      }
      const double e_cur = out.i_ref - in.i_fb;
      out.u = p_.P_cur * e_cur + p_.I_cur * x[1];
      xdot[0] = e_vel;  // frozen (0) when the velocity loop is bypassed
      const bool saturated =
          in.v_limit > 0.0 && ((out.u > in.v_limit && e_cur > 0) || (out.u < -in.v_limit && e_cur < 0));
      xdot[1] = saturated ? 0.0 : e_cur;
      break;
    }
    case ControllerType::TorqueCascade: {
      out.qdm_ref = in.entry == ControlEntry::MotorVelocity
                        ? in.command
                        : in.ratio * in.qd_set + p_.kp * (in.qm_offset + in.ratio * in.q_set - in.qm_fb);
      const double u = out.qdm_ref - in.qdm_fb;
      out.u = p_.ks * (u + x[0]);
      xdot[0] = u / p_.Ts;
      break;
    }
    case ControllerType::None: break;
  }
  return out;
}

bool JointController::accepts(ControlEntry entry) const {
  switch (p_.type) {
    case ControllerType::VoltageCascade: return true;
    case ControllerType::TorqueCascade: return entry != ControlEntry::Current;
    default: return false;
  }
}

void JointController::matchOutput(const ControllerInputs& in, double u, double i_ref, double* x) const {
  std::vector<double> xdot(2);
  if (p_.type == ControllerType::VoltageCascade) {
    // i_ref = P_vel e_vel + I_vel x0 (velocity loop in use), then V = P_cur (i_ref − i) + I_cur x1.
    if (in.entry != ControlEntry::Current && p_.I_vel > 0.0) {
      x[0] = 0.0;
      const ControllerOutputs o = evaluate(in, x, xdot.data());
      x[0] = (i_ref - o.i_ref) / p_.I_vel;
    }
    if (p_.I_cur > 0.0) {
      x[1] = 0.0;
      const ControllerOutputs o = evaluate(in, x, xdot.data());
      x[1] = (u - o.u) / p_.I_cur;
    }
  } else if (p_.type == ControllerType::TorqueCascade && p_.ks > 0.0) {
    x[0] = 0.0;
    const ControllerOutputs o = evaluate(in, x, xdot.data());
    x[0] = (u - o.u) / p_.ks;  // τ = ks (u + x)
  }
}

double sampledCurrentLoopRadius(const JointControllerParams& params, double R, double L, double Ts) {
  if (params.type != ControllerType::VoltageCascade || !(R > 0.0) || !(L > 0.0) || !(Ts > 0.0)) return 0.0;
  const double a = std::exp(-R * Ts / L), b = (1.0 - a) / R;
  // λ² − (m11 + m22) λ + (m11 m22 − m12 m21) = 0 for [[m11, m12], [m21, m22]] = [[a − b P, b I], [−Ts, 1]].
  const double m11 = a - b * params.P_cur, tr = m11 + 1.0, det = m11 + b * params.I_cur * Ts;
  const double disc = tr * tr - 4.0 * det;
  if (disc < 0.0) return std::sqrt(det);  // complex pair: |λ|² = det
  const double r = std::sqrt(disc);
  return std::max(std::abs(0.5 * (tr + r)), std::abs(0.5 * (tr - r)));
}

}  // namespace jointsim::control
