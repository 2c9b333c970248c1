#pragma once
/// \file
/// Rigid, elastic and elasto-backlash gears, and the coupling matrix of coupled wrists / multigears.
/// See transmission.hpp for the port and sign conventions.
///
/// Compliance can be specified on the motor side ([Olsson2017], [KR300Thesis, §3.2, §7.3]: c, d, b in
/// motor-side units, deflection δ_m = q_in − N q_out) or on the output side ([EJModel], [Hauschild2003]: K, D
/// on the link side, δ = q_in/N − q_out). They are equivalent with c_out = N² c_m, d_out = N² d_m,
/// b_out = b_m / N (our derivation).

#include <Eigen/Core>

#include "jointsim/drive/transmission.hpp"

namespace jointsim::drive {

/// Which shaft the compliance parameters refer to.
enum class ComplianceSide { Motor, Output };

/// Ideal rigid reducer q_in = N q_out, τ_out = N τ_in ([Olsson2017, §3.8, eqs. 3.2–3.3, A.9]). Has no
/// evaluate(): the joint rig merges the two shafts into one degree of freedom.
class RigidGear : public Transmission {
 public:
  explicit RigidGear(double ratio);
  std::string type() const override { return "rigid"; }
  double ratio() const override { return N_; }
  bool isRigid() const override { return true; }
  /// Not meaningful for a constraint: returns zero torques. Callers check isRigid() first.
  PortTorques evaluate(const ShaftPorts&, const double*, double*) const override { return {}; }
  double storedEnergy(const ShaftPorts&, const double*) const override { return 0.0; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Transmission> withParameters(const ParameterChanges& changes) const override;

 private:
  double N_;
};

struct ElasticGearParams {
  double ratio = 1.0;      ///< N = q_in / q_out [-], > 0
  double stiffness = 1.0;  ///< c [N·m/rad] on `side`, > 0
  double damping = 0.0;    ///< d [N·m·s/rad] on `side`, >= 0
  ComplianceSide side = ComplianceSide::Motor;
  void validate() const;
};

/// Spring–damper gear (elastic joint of [Spong1987], [EJModel, §2.2–2.3], [Hauschild2003, §5.2.1]):
/// τ_s = c δ + d δ̇ on the chosen side.
class ElasticGear : public Transmission {
 public:
  explicit ElasticGear(const ElasticGearParams& params);
  std::string type() const override { return "elastic"; }
  double ratio() const override { return p_.ratio; }
  PortTorques evaluate(const ShaftPorts& ports, const double* x, double* xdot) const override;
  double storedEnergy(const ShaftPorts& ports, const double* x) const override;
  const ElasticGearParams& params() const { return p_; }

  std::string complianceSide() const override { return p_.side == ComplianceSide::Motor ? "motor" : "output"; }
  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Transmission> withParameters(const ParameterChanges& changes) const override;

 private:
  ElasticGearParams p_;
};

struct ElastoBacklashParams {
  double ratio = 1.0;      ///< N = q_in / q_out [-], > 0
  double stiffness = 1.0;  ///< c [N·m/rad] on `side`, > 0
  double damping = 0.0;    ///< d [N·m·s/rad] on `side`, >= 0
  double backlash = 0.0;   ///< total backlash b [rad] on `side`, >= 0 (gap ±b/2 around zero deflection)
  ComplianceSide side = ComplianceSide::Motor;
  void validate() const;
};

/// Modelica ElastoBacklash law ([MSL, Rotational.Components.ElastoBacklash]) in series with an ideal gear:
/// no torque inside the gap, c (|δ| − b/2) outside it; the damper never makes the contact torque change
/// sign and is limited to the spring torque, so the torque is continuous at contact onset. b < 1e-10 rad:
/// plain spring–damper.
class ElastoBacklash : public Transmission {
 public:
  explicit ElastoBacklash(const ElastoBacklashParams& params);
  std::string type() const override { return "elasto_backlash"; }
  double ratio() const override { return p_.ratio; }
  PortTorques evaluate(const ShaftPorts& ports, const double* x, double* xdot) const override;
  double storedEnergy(const ShaftPorts& ports, const double* x) const override;
  const ElastoBacklashParams& params() const { return p_; }
  /// The contact law itself: torque for deflection δ [rad] and deflection rate δ̇ [rad/s] on `side`.
  double contactTorque(double delta, double delta_dot) const;

  std::string complianceSide() const override { return p_.side == ComplianceSide::Motor ? "motor" : "output"; }
  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Transmission> withParameters(const ParameterChanges& changes) const override;

 private:
  ElastoBacklashParams p_;
};

/// Coupling matrix G between n motors and n joints (wrist of [Olsson2017, §2.2, eqs. 2.1–2.2], multigear
/// of [KR300Thesis]): q_joint = G q_motor, τ_motor = Gᵀ τ_joint. Power is conserved:
/// q̇_jointᵀ τ_joint = q̇_motorᵀ τ_motor.
class CouplingMatrix {
 public:
  /// Throws InputError if G is not square or not invertible.
  explicit CouplingMatrix(const Eigen::MatrixXd& G);
  const Eigen::MatrixXd& G() const { return G_; }
  Eigen::VectorXd jointAngles(const Eigen::VectorXd& q_motor) const { return G_ * q_motor; }
  Eigen::VectorXd motorAngles(const Eigen::VectorXd& q_joint) const { return Ginv_ * q_joint; }
  Eigen::VectorXd motorTorques(const Eigen::VectorXd& tau_joint) const { return G_.transpose() * tau_joint; }
  /// Joint torques delivered by given motor torques: τ_joint = G⁻ᵀ τ_motor.
  Eigen::VectorXd jointTorques(const Eigen::VectorXd& tau_motor) const;
  /// Motor inertias diag(J_m) reflected to the joints: G⁻ᵀ diag(J_m) G⁻¹ [kg·m²].
  Eigen::MatrixXd reflectedInertia(const Eigen::VectorXd& motor_inertias) const;
  /// The IRB140 wrist matrix of [Olsson2017, §3.12, A.13, Listing 4.1] (exact rational form derived from
  /// Listing 4.1).
  static Eigen::Matrix3d irb140Wrist();

 private:
  Eigen::MatrixXd G_;
  Eigen::MatrixXd Ginv_;
};

}  // namespace jointsim::drive
