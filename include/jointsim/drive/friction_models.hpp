#pragma once
/// \file
/// Concrete friction models of the drive layer ([Hauschild2003, §4.3], [Raviola2023, eq. 7],
/// [Olsson2017, eq. 3.1], [MSL, Rotational.Components.BearingFriction]). Sign convention of friction.hpp:
/// the returned torque OPPOSES the motion (J q̈ = τ_driving − τ_friction); all quantities are rotary
/// (torque in N·m, velocity in rad/s, bristle deflection in rad) on the shaft the model is attached to.
///
/// | class                  | type()            | states | reference                                       |
/// |------------------------|-------------------|--------|-------------------------------------------------|
/// | CoulombViscousFriction | "coulomb_viscous" | 0      | [Hauschild2003, eq. 4.2], tanh (our choice)     |
/// | TableFriction          | "table"           | 0      | [Olsson2017, eq. 3.1], [MSL] BearingFriction    |
/// | StribeckFriction       | "stribeck"        | 0      | [Hauschild2003, eqs. 4.6, 4.24, Table 4.3]      |
/// | DahlFriction           | "dahl"            | 1 (z)  | [Hauschild2003, eqs. 4.7–4.9]                   |
/// | LuGreFriction          | "lugre"           | 1 (z)  | [Hauschild2003, eqs. 4.15–4.17, 4.20–4.21]      |
/// | LuGreUr5Friction       | "lugre_ur5"       | 1 (z)  | [Raviola2023, §2.4, eq. 7], [CanudasDeWit1995]  |
///
/// Every model is immutable after construction (the parameters are validated by the constructor,
/// InputError otherwise); evaluate() is pure, thread-safe and does not allocate.
///
/// Ambiguities resolved (the sources leave these open; our own analysis):
/// 1. Coulomb + viscous: sgn(v) is regularised as tanh(v/v_reg) (our choice). Chosen over arctan
///    because tanh reaches ±1 exponentially (|tanh(x) − sgn(x)| ≤ 2e^{−2|x|}, so the model equals
///    eq. 4.2 to 1e-8·F_C for |v| > 10 v_reg), is C^∞ and odd, never exceeds F_C, and has the finite
///    slope F_C/v_reg at 0, which keeps CVODE's Newton iteration well posed. Price: no true sticking,
///    creep at speed ~ v_reg·τ/F_C under a static load τ < F_C.
/// 2. Table (BearingFriction): the exact MSL model is hybrid (stuck/forward/backward modes with events).
///    Our right-hand side must be pure, so sticking is approximated with a Karnopp velocity band
///    ([Hauschild2003, §4.3.1], [Karnopp1985]): for |v| < v_stick and |τ_d| ≤ peak·τ0 the friction is
///    clamp(τ_d + d_stick·v, ±peak·τ0), which makes J v̇ = −d_stick·v (v relaxes to 0, the shaft is held
///    against τ_d); for |v| < v_stick and |τ_d| > peak·τ0 the shaft breaks away and the friction is
///    sgn(τ_d)·τ_pos(|v|), i.e. it drops from peak·τ0 to the table value as in MSL's
///    startForward/startBackward phase; for |v| ≥ v_stick it is the sliding table torque sgn(v)·τ_pos(|v|).
///    d_stick = 0 (default) selects d_stick = peak·τ0/v_stick, so the clamp saturates exactly at the band
///    edge when τ_d = 0.
///    Tables: rows [ω ≥ 0, τ ≥ 0] with strictly increasing ω, linear interpolation, linear
///    extrapolation through the first two / last two rows (a one-row table is constant); the
///    extrapolated τ_pos(0) must be ≥ 0 and the last slope ≥ 0 (friction never drives the shaft).
/// 3. Stribeck ([Hauschild2003, eq. 4.6]): |v| inside the exponent (our correction); the zero crossing
///    is smoothed with the slope limiter of [Hauschild2003, eq. 4.24], multiplying the whole branch value,
///    viscous term included (our assumption), default k_S = 300 s/rad. Per-direction parameter sets
///    (Table 4.3), the set for v ≥ 0 being used at v = 0 (where the limited value is 0 anyway).
/// 4. Dahl: eq. 4.7 for general α is written in the bristle state z = F/σ as
///    ż = v·φ(1 − σ z sgn(v)/F_C), φ(u) = sgn(u)|u|^α, which is eq. 4.9 for α = 1 and stays real if a
///    numerical step leaves |σ z| ≤ F_C. α ≥ 1 is required (α < 1 makes the right-hand side
///    non-Lipschitz at |F| = F_C).
/// 5. LuGre (eqs. 4.15–4.17, 4.20): per-direction static parameters as [Hauschild2003, §4.5.4] does
///    (Table 4.3), selected by the sign of v; the choice does not matter at v = 0 because g only enters through
///    |v|·z/g and α2 through α2·v, so the model is continuous in v. δ = 2 (eq. 4.17). α0 > 0 is
///    required so that g(v) ≥ α0 > 0 for all v; α1 ≥ 0 (g decreases from g(0), Stribeck). σ1 > 0
///    as [Hauschild2003] demands. Passivity: with E = σ0 z²/2, dE/dt − F·v = −α2 v² − [σ0²|v|/g·z² +
///    σ1σ0|v|/g·z ż + σ1 ż²], which is ≤ 0 whenever σ1|v| ≤ 4 g(v) (the bracket is a non-negative
///    quadratic form); this sufficient condition is what the passivity test relies on.
/// 6. UR5 LuGre ([Raviola2023, eq. 7]): |q̇|^{2/3} and |q̇_s| (our correction: |q̇|^(2/3) so g stays real
///    for q̇ < 0); no viscous term outside g; f_c, f_v and k_q are not given by [Raviola2023] and are
///    required (NaN by default, rejected by validate()); k_l and k_q are the same parameter.
/// 7. steadyState(v) of the static models returns the same value as evaluate() with driving torque 0
///    outside the sticking band; of TableFriction it returns the sliding map sgn(v)·τ_pos(|v|) for any
///    v ≠ 0 (the band is a numerical device, not part of the physical map), and 0 at v = 0.

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "jointsim/drive/friction.hpp"

namespace jointsim::drive {

// ===================================================================================================
// 1. Coulomb + viscous
// ===================================================================================================

/// Parameters of CoulombViscousFriction ([Hauschild2003, eq. 4.2]). Defaults: the table of
/// [Olsson2017, Listing 4.1], [0, 0.1; 1, 0.3], i.e. F_C = 0.1 N·m, F_v = 0.2 N·m·s/rad (motor side).
struct CoulombViscousParams {
  double f_c = 0.1;     ///< F_C: Coulomb friction level [N·m], >= 0
  double f_v = 0.2;     ///< F_v: viscous coefficient [N·m·s/rad], >= 0
  double v_reg = 1e-3;  ///< v_reg: regularisation velocity of tanh(v/v_reg) [rad/s], > 0
  /// \throws InputError naming the field, its value and the rule.
  void validate() const;
};

/// Coulomb + viscous friction, τ_f = F_C·tanh(v/v_reg) + F_v·v ([Hauschild2003, eq. 4.2] with sgn
/// regularised, our choice). Stateless; ignores the driving torque.
class CoulombViscousFriction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit CoulombViscousFriction(const CoulombViscousParams& params);
  std::string type() const override { return "coulomb_viscous"; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  double steadyState(double v) const override;
  bool readsDrivingTorque() const override { return false; }
  const CoulombViscousParams& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  CoulombViscousParams p_;
};

// ===================================================================================================
// 2. Table friction (Modelica BearingFriction)
// ===================================================================================================

/// Parameters of TableFriction ([Olsson2017, §3.8, eq. 3.1], [KR300Thesis, §3.1],
/// [MSL, Rotational.Interfaces.PartialFriction], [MSL, Rotational.Components.BearingFriction]).
/// Defaults: [Olsson2017, Listing 4.1] (tau_pos = [0, 0.1; 1, 0.3], peak = 1).
struct TableFrictionParams {
  /// tau_pos: rows [ω, τ(ω)] of the sliding friction for ω ≥ 0: ω [rad/s] strictly increasing and
  /// >= 0, τ [N·m] >= 0; at least one row. Linear interpolation, linear extrapolation through the
  /// first/last two rows. For [[0, m], [1, m + k]] the sliding torque is k·ω + m.
  std::vector<std::array<double, 2>> tau_pos{{{0.0, 0.1}}, {{1.0, 0.3}}};
  /// peak: stiction factor [-], >= 1; stiction torque = peak·τ_pos(0) (MSL `peak`, `friction_peak` of
  /// [Olsson2017]).
  double peak = 1.0;
  /// v_stick: half-width of the Karnopp sticking band [rad/s], > 0.
  double v_stick = 1e-3;
  /// d_stick: damping that brings v to 0 inside the band [N·m·s/rad], >= 0; 0 selects
  /// peak·τ_pos(0)/v_stick. A shaft of inertia J relaxes with time constant J/d_stick.
  double d_stick = 0.0;
  /// \throws InputError naming the field (tau_pos[i] for a row), its value and the rule.
  void validate() const;
};

/// Modelica BearingFriction semantics with a Karnopp sticking band (see the file comment, item 2):
/// stuck while |τ_d| ≤ peak·τ_pos(0), sliding torque sgn(v)·τ_pos(|v|). Stateless; uses
/// FrictionInput::driving_torque.
///
/// Numerical note: while stuck the caller's net torque τ_d − τ_f = −d_stick·v is a cancellation with a
/// rounding error ~ulp(τ_d), so v settles at rounding-noise level. A CVODE absolute tolerance on the
/// shaft velocity close to that noise makes the difference-quotient Jacobian meaningless (observed:
/// repeated Newton/error-test failures with atol = 1e-14 rad/s, J = 1e-3 kg·m², τ_d = 0.15 N·m; 1e-12
/// and looser work). The band is stiff (eigenvalue −d_stick/J): use BDF.
class TableFriction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit TableFriction(const TableFrictionParams& params);
  std::string type() const override { return "table"; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  /// Sliding map sgn(v)·τ_pos(|v|) [N·m], 0 at v = 0.
  double steadyState(double v) const override;
  /// τ_pos(w) for w >= 0 [N·m]: the interpolated / extrapolated table.
  double tableTorque(double w) const;
  /// τ0 = τ_pos(0) [N·m] (the Coulomb level m of a two-row table).
  double tau0() const { return tau0_; }
  /// Stiction (break-away) torque peak·τ0 [N·m].
  double stictionTorque() const { return p_.peak * tau0_; }
  /// Sticking damping actually used [N·m·s/rad] (d_stick, or its automatic value).
  double stickDamping() const { return d_stick_; }
  const TableFrictionParams& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  TableFrictionParams p_;
  double tau0_ = 0.0;
  double d_stick_ = 0.0;
};

// ===================================================================================================
// 3. Exponential Stribeck model
// ===================================================================================================

/// Static (Stribeck) parameters of one direction of motion ([Hauschild2003, Tables 4.2–4.3]). Defaults:
/// Table 4.3, Watflex shoulder, v > 0.
struct StribeckBranch {
  double alpha0 = 7.9707;  ///< α0: Coulomb friction F_C [N·m], >= 0 (> 0 for LuGre)
  double alpha1 = 1.4476;  ///< α1: additional stiction F_S − F_C [N·m], >= 0 (static friction α0 + α1)
  double alpha2 = 4.9349;  ///< α2: viscous coefficient F_v [N·m·s/rad], >= 0
  double v_s = 0.0363;     ///< v_S: Stribeck velocity [rad/s], > 0
};

/// Parameters of StribeckFriction. Defaults: [Hauschild2003, Table 4.3] (shoulder actuator, output side,
/// δ = 2).
struct StribeckParams {
  /// Parameters used for v >= 0.
  StribeckBranch positive{7.9707, 1.4476, 4.9349, 0.0363};
  /// Parameters used for v < 0 (magnitudes; the map is applied to |v| and given the sign of v).
  StribeckBranch negative{7.7538, 0.8626, 4.3267, 0.0221};
  double delta = 2.0;  ///< δ: form factor of the Stribeck exponential [-], > 0
  double k_s = 300.0;  ///< k_S: slope-limiter factor of eq. 4.24 [s/rad], > 0
  /// \throws InputError naming the field (e.g. "negative.v_s"), its value and the rule.
  void validate() const;
};

/// Exponential friction model ([Hauschild2003, eq. 4.6]) with the slope limiter of eq. 4.24:
/// τ_f = [(α0 + α1·e^{−(|v|/v_S)^δ})·sgn(v) + α2·v]·(1 − e^{−k_S|v|}), per-direction parameters.
/// Continuous with finite slope k_S·(α0 + α1) at v = 0. Stateless; ignores the driving torque.
class StribeckFriction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit StribeckFriction(const StribeckParams& params);
  std::string type() const override { return "stribeck"; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  double steadyState(double v) const override;
  bool readsDrivingTorque() const override { return false; }
  const StribeckParams& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  StribeckParams p_;
};

// ===================================================================================================
// 4. Dahl
// ===================================================================================================

/// Parameters of DahlFriction ([Hauschild2003, eqs. 4.7–4.9]). [Hauschild2003] gives no Dahl values; the
/// defaults are illustrative: σ = the LuGre σ0 of [Hauschild2003] and F_C = Table 4.3 α0 (v > 0) of the
/// shoulder actuator.
struct DahlParams {
  double sigma = 259.0;  ///< σ: rest stiffness, slope dF/dx at F = 0 [N·m/rad], > 0
  double f_c = 7.9707;   ///< F_C: Coulomb friction level [N·m], > 0
  double alpha = 1.0;    ///< α: form factor [-], >= 1 (1 gives eqs. 4.8–4.9)
  /// \throws InputError naming the field, its value and the rule.
  void validate() const;
};

/// Dahl model, state z [rad] (bristle deflection), τ_f = σ·z,
/// ż = v·φ(1 − σ·z·sgn(v)/F_C), φ(u) = sgn(u)|u|^α ([Hauschild2003, eq. 4.7]; eq. 4.9 for α = 1).
/// Rate independent, no stiction; steady state F_C·sgn(v).
class DahlFriction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit DahlFriction(const DahlParams& params);
  std::string type() const override { return "dahl"; }
  int stateSize() const override { return 1; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  /// F_C·sgn(v) [N·m] (0 at v = 0).
  double steadyState(double v) const override;
  bool readsDrivingTorque() const override { return false; }
  std::vector<std::string> stateNames() const override { return {"z[rad]"}; }
  const DahlParams& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  DahlParams p_;
};

// ===================================================================================================
// 5. LuGre
// ===================================================================================================

/// Parameters of LuGreFriction ([Hauschild2003, Table 4.2]). Defaults: the shoulder actuator of
/// [Hauschild2003] (Table 4.3 and §4.5.6: σ0 = 259 N·m/rad, σ1 = 10 N·m·s/rad), output side.
struct LuGreParams {
  double sigma0 = 259.0;  ///< σ0: bristle stiffness (micro-deformation) [N·m/rad], > 0
  double sigma1 = 10.0;   ///< σ1: bristle damping [N·m·s/rad], > 0
  /// Static parameters α0, α1, α2, v_S used for v >= 0 (alpha0 > 0 required).
  StribeckBranch positive{7.9707, 1.4476, 4.9349, 0.0363};
  /// Static parameters used for v < 0 (magnitudes).
  StribeckBranch negative{7.7538, 0.8626, 4.3267, 0.0221};
  /// \throws InputError naming the field (e.g. "positive.alpha0"), its value and the rule.
  void validate() const;
};

/// LuGre model ([Hauschild2003, eqs. 4.15–4.17], joint form eq. 4.20; [CanudasDeWit1995]), state z [rad]:
///   ż = v − σ0·|v|·z/g(v),  g(v) = α0 + α1·e^{−(v/v_S)²},  τ_f = σ0·z + σ1·ż + α2·v,
/// with the α-set of the direction of v. Steady state (eq. 4.21): (α0 + α1·e^{−(v/v_S)²})·sgn(v) + α2·v.
/// Break-away (static friction) level α0 + α1 (Table 4.2). Ignores the driving torque.
class LuGreFriction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit LuGreFriction(const LuGreParams& params);
  std::string type() const override { return "lugre"; }
  int stateSize() const override { return 1; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  /// Static map, eq. 4.21 [N·m].
  double steadyState(double v) const override;
  bool readsDrivingTorque() const override { return false; }
  std::vector<std::string> stateNames() const override { return {"z[rad]"}; }
  /// g(v) of eq. 4.17 with the α-set of the direction of v [N·m].
  double g(double v) const;
  const LuGreParams& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  LuGreParams p_;
};

// ===================================================================================================
// 6. UR5 LuGre variant
// ===================================================================================================

/// Parameters of LuGreUr5Friction ([Raviola2023, §2.4, eq. 7]). σ0, σ1, q̇_s, K_static and the
/// exponent are the values of [Raviola2023]; f_c, f_v and k_q are not given by [Raviola2023] and default to
/// NaN so that validate() rejects a model where they were not set (k_q = 1 is a sensible start).
struct LuGreUr5Params {
  double sigma0 = 5e6;    ///< σ0: bristle stiffness [N·m/rad], > 0
  double sigma1 = 100.0;  ///< σ1: bristle damping [N·m·s/rad], > 0
  double qd_s = 0.5;      ///< q̇_s: sliding-speed threshold (Stribeck) [rad/s], > 0
  double k_static = 0.3;  ///< K_static: static increment over Coulomb [-], >= 0 (break-away (1 + K_static)·f_c)
  double viscous_exponent = 2.0 / 3;                      ///< exponent on |q̇| in the viscous term [-], > 0
  double f_c = std::numeric_limits<double>::quiet_NaN();  ///< f_c: Coulomb coefficient [N·m], > 0, required
  double f_v =
      std::numeric_limits<double>::quiet_NaN();  ///< f_v: viscous coefficient [N·m·(s/rad)^exponent], >= 0, required
  double k_q =
      std::numeric_limits<double>::quiet_NaN();  ///< k_q (k_l in eq. 7): Stribeck shape factor [-], >= 0, required
  /// \throws InputError naming the field, its value and the rule (also for an unset f_c, f_v, k_q).
  void validate() const;
};

/// LuGre variant of the UR5 joints ([Raviola2023, eq. 7]), state z [rad], q̇ = v the joint (output) speed:
///   T_f = σ0·z + σ1·ż,  ż = q̇ − σ0·|q̇|·z/g(q̇),
///   g(q̇) = f_c·(1 + K_static·e^{−k_q|q̇|/|q̇_s|}) + f_v·|q̇|^{2/3}.
/// The viscous part lives inside g, so the steady state is sgn(q̇)·g(q̇). Ignores the driving torque.
class LuGreUr5Friction : public Friction {
 public:
  /// \throws InputError if the parameters are invalid.
  explicit LuGreUr5Friction(const LuGreUr5Params& params);
  std::string type() const override { return "lugre_ur5"; }
  int stateSize() const override { return 1; }
  double evaluate(const FrictionInput& in, const double* z, double* zdot) const override;
  /// Static map sgn(q̇)·g(q̇) [N·m].
  double steadyState(double v) const override;
  bool readsDrivingTorque() const override { return false; }
  std::vector<std::string> stateNames() const override { return {"z[rad]"}; }
  /// g(q̇) of eq. 7 [N·m].
  double g(double v) const;
  const LuGreUr5Params& params() const { return p_; }

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const override;

 private:
  LuGreUr5Params p_;
};

}  // namespace jointsim::drive
