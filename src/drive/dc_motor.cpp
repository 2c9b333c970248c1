#include "jointsim/drive/dc_motor.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::drive {

void DcMotorParams::validate() const {
  auto positive = [](double v, const char* name, const char* unit) { check::positive("motor", name, v, unit); };
  positive(R, "R", "Ω");
  positive(L, "L", "H");
  positive(kt, "kt", "N·m/A");
  positive(ke, "ke", "V·s/rad");
  positive(J_M, "J_M", "kg·m²");
  positive(V_supply, "V_supply", "V");
}

DcMotorParams DcMotorParams::ur5(int joint) {
  static const double kt[6] = {0.1350, 0.1361, 0.1355, 0.0957, 0.0865, 0.0893};
  if (joint < 1 || joint > 6) throw InputError("UR5 motor: joint must be 1..6, got " + std::to_string(joint));
  DcMotorParams p;
  const bool big = joint <= 3;
  p.J_M = big ? 1.877e-4 : 2.076e-5;
  p.R = big ? 0.30 : 1.65;
  p.L = big ? 0.83e-3 : 2.50e-3;
  p.kt = p.ke = kt[joint - 1];
  p.V_supply = 48.0;
  return p;
}

DcMotor::DcMotor(const DcMotorParams& params) : p_(params) { p_.validate(); }

double DcMotor::supplyVoltage(double V_ref) const { return std::clamp(V_ref, -p_.V_supply, p_.V_supply); }

double DcMotor::currentDerivative(double i, double V_ref, double omega) const {
  return (supplyVoltage(V_ref) - p_.R * i - p_.ke * omega) / p_.L;
}

double DcMotor::steadySpeed(double V, double T_load) const { return (V - p_.R * T_load / p_.kt) / p_.ke; }

}  // namespace jointsim::drive

namespace jointsim::drive {
namespace {
std::vector<ParameterRef> motorRefs(DcMotorParams& p) {
  const auto R = ParameterRange::positive();
  const auto none = ParameterRole::None;
  return {{{"R", "Ω", 0.0, R, none, "armature resistance R"}, &p.R},
          {{"L", "H", 0.0, R, none, "armature inductance L"}, &p.L},
          {{"kt", "N·m/A", 0.0, R, ParameterRole::TorqueConstant, "torque constant k_t"}, &p.kt},
          {{"ke", "V·s/rad", 0.0, R, ParameterRole::TorqueConstant, "back-EMF constant k_e"}, &p.ke},
          {{"J_M", "kg·m²", 0.0, R, none, "rotor inertia J_M"}, &p.J_M},
          {{"V_supply", "V", 0.0, R, none, "supply voltage (the PWM output saturates at ±V_supply)"}, &p.V_supply}};
}
}  // namespace

std::vector<ParameterInfo> parameterTable(const DcMotorParams& params) {
  DcMotorParams p = params;
  return describeParameters(motorRefs(p));
}

DcMotorParams withParameters(DcMotorParams params, const ParameterChanges& changes) {
  assignParameters(motorRefs(params), changes, "motor");
  params.validate();
  return params;
}

}  // namespace jointsim::drive
