#pragma once
/// \file
/// DC motor electrics ([Raviola2023, §2.2, eq. 1, Table 2]) with an averaged PWM voltage source saturated
/// at the supply (48 V, [Raviola2023, §2.1]; the averaged clamp model is our assumption):
/// L di/dt = V_sup − R i − k_e ω,  T_M = k_t i,  V_sup = clamp(V_ref, ±V_supply).
/// The rotor inertia J_M is a parameter here, but its dynamics belong to the shaft the motor drives.

#include <string>
#include <vector>

#include "jointsim/drive/parameters.hpp"

namespace jointsim::drive {

struct DcMotorParams {
  double R = 0.30;         ///< armature resistance R [Ω], > 0
  double L = 0.83e-3;      ///< armature inductance L [H], > 0
  double kt = 0.1350;      ///< torque constant k_t [N·m/A], > 0
  double ke = 0.1350;      ///< back-EMF constant k_e [V·s/rad], > 0 ([Raviola2023] uses k_e = k_t; may differ)
  double J_M = 1.877e-4;   ///< rotor inertia J_M [kg·m²], > 0
  double V_supply = 48.0;  ///< supply (network) voltage V_net [V], > 0: |V_sup| ≤ V_supply

  /// Throws InputError naming the field, the value and the rule.
  void validate() const;
  /// UR5 motor of joint `joint` (1..6), [Raviola2023, Table 2].
  static DcMotorParams ur5(int joint);
};

/// The parameter table of a DC motor (parameters.hpp): R, L, kt and ke (role torque_constant), J_M, V_supply.
std::vector<ParameterInfo> parameterTable(const DcMotorParams& params);
/// `params` with `changes` (keys of parameterTable()) applied, validated. \throws InputError as assignParameters.
DcMotorParams withParameters(DcMotorParams params, const ParameterChanges& changes);

class DcMotor {
 public:
  explicit DcMotor(const DcMotorParams& params);
  const DcMotorParams& params() const { return p_; }
  /// Averaged PWM output: the commanded voltage clamped to ±V_supply [V].
  double supplyVoltage(double V_ref) const;
  /// di/dt [A/s] for current i [A], commanded voltage V_ref [V] and rotor speed ω [rad/s].
  double currentDerivative(double i, double V_ref, double omega) const;
  /// Electromagnetic torque k_t i [N·m].
  double torque(double i) const { return p_.kt * i; }
  /// Steady free-running speed at voltage V with a constant load torque T_load on the shaft [rad/s]:
  /// ω = (V − R T_load / k_t) / k_e (no friction).
  double steadySpeed(double V, double T_load = 0.0) const;

 private:
  DcMotorParams p_;
};

}  // namespace jointsim::drive
