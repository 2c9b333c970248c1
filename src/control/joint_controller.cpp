#include "jointsim/control/joint_controller.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::control {

void JointControllerParams::validate(const std::string& where) const {
  auto nonneg = [&](double v, const char* name) { check::nonNegative(where, name, v, "(a gain)"); };
  if (type == ControllerType::Cascade002) {
    nonneg(P_pos, "P_pos");
    nonneg(P_vel, "P_vel");
    nonneg(I_vel, "I_vel");
    nonneg(P_cur, "P_cur");
    nonneg(I_cur, "I_cur");
  } else if (type == ControllerType::MotorPPI000) {
    nonneg(kp, "kp");
    nonneg(ks, "ks");
    check::positive(where, "Ts", Ts, "s");
  }
}

int JointController::stateSize() const {
  switch (p_.type) {
    case ControllerType::Cascade002: return 2;
    case ControllerType::MotorPPI000: return 1;
    default: return 0;
  }
}

void JointController::initialState(const ControllerInputs& in, double* x) const {
  if (p_.type == ControllerType::Cascade002) {
    x[0] = x[1] = 0.0;
  } else if (p_.type == ControllerType::MotorPPI000) {
    const double u = in.ratio * in.qd_set + p_.kp * (in.ratio * in.q_set - in.qm_fb) - in.qdm_fb;
    x[0] = -u;  // InitialOutput: y(0) = 0
  }
}

ControllerOutputs JointController::evaluate(const ControllerInputs& in, const double* x, double* xdot) const {
  ControllerOutputs out;
  switch (p_.type) {
    case ControllerType::Cascade002: {
      out.voltage = true;
      out.qdm_ref = p_.P_pos * (in.q_set - in.q_fb) + in.ratio * in.qd_set;
      const double e_vel = out.qdm_ref - in.qdm_fb;
      out.i_ref = p_.P_vel * e_vel + p_.I_vel * x[0];
      const double e_cur = out.i_ref - in.i_fb;
      out.u = p_.P_cur * e_cur + p_.I_cur * x[1];
      xdot[0] = e_vel;
      const bool saturated =
          in.v_limit > 0.0 && ((out.u > in.v_limit && e_cur > 0) || (out.u < -in.v_limit && e_cur < 0));
      xdot[1] = saturated ? 0.0 : e_cur;
      break;
    }
    case ControllerType::MotorPPI000: {
      const double u = in.ratio * in.qd_set + p_.kp * (in.ratio * in.q_set - in.qm_fb) - in.qdm_fb;
      out.qdm_ref = in.ratio * in.qd_set + p_.kp * (in.ratio * in.q_set - in.qm_fb);
      out.u = p_.ks * (u + x[0]);
      xdot[0] = u / p_.Ts;
      break;
    }
    case ControllerType::None: break;
  }
  return out;
}

}  // namespace jointsim::control
