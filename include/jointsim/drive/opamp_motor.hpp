#pragma once
/// \file
/// Motor with operational-amplifier current controller of the Modelica RobotR3 axes
/// ([MSL, RobotR3.Utilities.Motor], with its steady-state initial equations; C = 0.004·D/w and
/// La = 250/(2·D·w) derived from it).
///
/// Circuit (ideal op-amps): a difference amplifier forms i − i_ref, an integrator (Ri, C) integrates it,
/// a non-inverting power amplifier with gain 1 + Rp1/Rp2 = 5 drives the armature (Ra, La) and the EMF.
/// Node analysis gives, with the two electrical states v_C (`motor.C.v`, voltage of the integrator
/// capacitor, first pin minus second pin) and i (`motor.La.i`, armature current):
///
///     C  · dv_C/dt = (i − i_ref) / Ri
///     La · di/dt   = −5·v_C − Ra·i − k·ω_m
///     torque on the rotor  τ = k·i
///
/// With u = −v_C the controller is a pure integrator du/dt = (i_ref − i)/(Ri·C) driving the armature
/// with 5·u, and (ignoring back-EMF) i/i_ref = w² / (s² + 2·D·w·s + w²).
///
/// Sign conventions: i > 0 produces a positive torque k·i on the rotor; ω_m is the rotor speed
/// against ground; the back-EMF k·ω_m opposes a positive current. The rotor inertia J is a parameter,
/// but the rotor dynamics J·dω_m/dt = k·i − (load torque) belong to the drive train the motor drives.

#include <Eigen/Core>

namespace jointsim::drive {

struct OpAmpMotorParams {
  double J = 0.0013;      ///< rotor inertia J [kg·m²], > 0 (MSL axis-model default)
  double k = 1.1616;      ///< EMF / torque constant k [N·m/A = V·s/rad], > 0
  double w = 4590.0;      ///< natural frequency of the current loop w [rad/s], > 0 (MSL calls it "time constant")
  double D = 0.6;         ///< damping ratio of the current loop D [-], > 0
  double Ri = 10.0;       ///< integrator input resistor Ri [Ω], > 0
  double Ra = 250.0;      ///< armature resistance Ra [Ω], > 0
  double amp_gain = 5.0;  ///< power-amplifier gain 1 + Rp1/Rp2 = 1 + 200/50 [-], > 0
  double w_max = 315.0;   ///< maximum speed [rad/s], > 0. Unused by any equation (as in MSL: no limiter)
  double i_max = 9.0;     ///< maximum current [A], > 0. Unused by any equation (as in MSL: no saturation)

  /// Integrator capacitance C = 0.004·D/w [F] (MSL formula; gives the loop its natural frequency w
  /// together with Ri = 10 Ω, Ra = 250 Ω and gain 5).
  double C() const { return 0.004 * D / w; }
  /// Armature inductance La = 250/(2·D·w) [H] (MSL formula; Ra/La = 2·D·w for Ra = 250 Ω).
  double La() const { return 250.0 / (2.0 * D * w); }

  /// Throws InputError naming the field, the value and the rule (every field finite and > 0).
  void validate() const;
  /// Motor of FullRobot axis `axis` (1..6), axis parameters of [MSL, RobotR3.FullRobot] (k, w, D, J per
  /// axis; others default).
  /// Throws InputError for an axis outside 1..6.
  static OpAmpMotorParams robotR3Axis(int axis);
  /// Motor of the OneAxis example ([MSL, RobotR3.OneAxis]): the axis-2 motor, k = 1.1616, w = 5500, D = 0.6,
  /// J = 0.0013.
  static OpAmpMotorParams oneAxis();
};

class OpAmpMotor {
 public:
  static constexpr int kNumStates = 2;  ///< electrical states x = [v_C, i]
  static constexpr int kVC = 0;         ///< index of v_C [V] (`motor.C.v`)
  static constexpr int kI = 1;          ///< index of i [A] (`motor.La.i`)

  /// Validates the parameters (InputError).
  explicit OpAmpMotor(const OpAmpMotorParams& params);
  const OpAmpMotorParams& params() const { return p_; }

  /// Electrical state derivatives xdot = [dv_C/dt [V/s], di/dt [A/s]] for current set-point i_ref [A],
  /// rotor speed omega_m [rad/s] and state x = [v_C [V], i [A]]. x and xdot must have size 2
  /// (InputError otherwise); they may alias.
  void derivatives(double i_ref, double omega_m, const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> xdot) const;
  /// Constant Jacobian d xdot / d x (2×2). Its characteristic polynomial is s² + 2·D·w·s + w²
  /// (for the MSL values Ri = 10, Ra = 250, gain 5).
  Eigen::Matrix2d stateJacobian() const;
  /// Partial derivatives of xdot with respect to i_ref [per A] and omega_m [per rad/s].
  Eigen::Vector2d inputJacobianIref() const;
  Eigen::Vector2d inputJacobianOmega() const;

  /// Armature drive voltage v(N_o) = amp_gain·u = −amp_gain·v_C [V].
  double armatureVoltage(double v_C) const { return -p_.amp_gain * v_C; }
  /// Back-EMF voltage k·ω_m [V].
  double emfVoltage(double omega_m) const { return p_.k * omega_m; }
  /// Electromagnetic torque on the rotor k·i [N·m].
  double torque(double i) const { return p_.k * i; }

  /// Electrical steady state [v_C, i] for armature current i [A] at rotor speed omega_m [rad/s]
  /// (the model's initial equations dv_C/dt = 0 ⇒ i = i_ref, di/dt = 0 ⇒
  /// v_C = −(Ra·i + k·ω_m)/amp_gain; [MSL, RobotR3.Utilities.Motor]). Pass i = i_ref(0).
  Eigen::Vector2d steadyState(double i, double omega_m) const;

 private:
  OpAmpMotorParams p_;
  double inv_RiC_;  // 1/(Ri·C) [1/s]
  double inv_La_;   // 1/La [1/H]
};

}  // namespace jointsim::drive
