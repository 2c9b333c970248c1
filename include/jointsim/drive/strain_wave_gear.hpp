#pragma once
/// \file
/// Lumped strain-wave-gear (harmonic drive) model of the UR5 ([Raviola2023, §2.3, eqs. 2–6, Table 3,
/// Fig. 3]). Wave generator (WG) on the input (motor) shaft, flexspline (FS) held by the joint
/// case, circular spline (CS) on the output shaft. Four internal degrees of freedom (q_WG, x_FS, y_FS, q_CS)
/// connected by five linear spring–dampers (motor shaft–WG, WG bearing–FS radial, FS–CS mesh, FS–case
/// tangential, CS–output flange); rotations of the WG are mapped to radial displacements through the
/// inclined plane of angle α_n = arctan(1/(τ tan α_t)) (eq. 3), so that q_CS/q_WG = 1/τ with rigid contacts.
///
/// Equations ([Raviola2023, eq. 5] with our corrections of three typos, item 3 below):
///
///     J_WG q̈_WG        = T_in − F_b r_g ρ          ρ = tan α_n (EnergyConsistent) or sin α_n cos α_n (PaperLiteral)
///     (J_FS/r_g²) ẍ_FS = F_b − F_m sin α_t
///     (J_FS/r_g²) ÿ_FS = F_m cos α_t − F_t
///     J_CS q̈_CS        = F_m r_g cos α_t − T_CS
///     T_in = K_WG (q_in − q_WG) + c_WG (q̇_in − q̇_WG)                       (returned as tau_in)
///     F_b  = K_b (x_WG − x_FS) + c_b (ẋ_WG − ẋ_FS),   x_WG = r_g tan α_n q_WG
///     F_m  = K_m δ_m + c_m δ̇_m,   δ_m = x_FS sin α_t − (y_CS + y_FS) cos α_t,   y_CS = r_g q_CS
///     F_t  = (K_FS y_FS + c_FS ẏ_FS) / r_g²
///     T_CS = K_CS (q_CS − q_out) + c_CS (q̇_CS − q̇_out)                      (returned as tau_out)
///
/// State coordinates (stateSize() = 8). The model's own coordinates q_WG, x_FS, q_CS are "unrolled": they
/// grow without bound with the motor angle (x_FS ≈ 0.53 mm per motor radian for size A) while the physical
/// deflections are 1e-9–1e-5. Integrating them directly makes CVODE's relative tolerance rtol·|x_FS| swamp
/// the deflections after a few hundred motor revolutions (and costs digits to cancellation in
/// x_WG − x_FS). By our choice the positions are therefore integrated as deflections
/// relative to the shaft each element is attached to; the velocities are absolute (a deflection *rate*
/// state for the WG would need the input-shaft acceleration, which the two-port interface does not give):
///
///     x[0] = φ_WG = q_in − q_WG        [rad]   motor shaft – WG twist        (T_in = K_WG φ_WG + …)
///     x[1] = q̇_WG                      [rad/s]
///     x[2] = Δ_b  = x_WG − x_FS        [m]     WG bearing radial deflection  (F_b = K_b Δ_b + …)
///     x[3] = ẋ_FS                      [m/s]
///     x[4] = y_FS                      [m]     FS tangential deflection (bounded already)
///     x[5] = ẏ_FS                      [m/s]
///     x[6] = φ_CS = q_CS − q_out       [rad]   CS – output flange twist      (T_CS = K_CS φ_CS + …)
///     x[7] = q̇_CS                      [rad/s]
///
/// The mesh deflection then reads, using tan α_n tan α_t = 1/τ (eq. 3, exact because tan α_n is computed as
/// 1/(τ tan α_t)):  δ_m = r_g cos α_t (q_in/τ − q_out) − sin α_t (r_g tan α_n φ_WG + Δ_b) − cos α_t (r_g φ_CS + y_FS),
/// so the large shaft angles only enter through the net transmission twist q_in/τ − q_out.
///
/// Ambiguities resolved (our reading of [Raviola2023, §2.3, eq. 5]):
/// 1. WG reaction factor: the paper's sin α_n cos α_n is not power-consistent with the constraint
///    x_WG = r_g tan α_n q_WG (static torque ratio τ/cos²α_n = 101.0297, spurious power F_b ẋ_WG sin²α_n).
///    Default ReactionForm::EnergyConsistent uses tan α_n (ratio exactly τ, passive);
///    ReactionForm::PaperLiteral reproduces [Raviola2023].
/// 2. "All the damping factors were set equal to 0.1": default DampingMode::Coefficient reads 0.1 as
///    coefficients in N·m·s/rad (c_WG, c_FS, c_CS) and N·s/m (c_b, c_m) (reading (a)); DampingMode::DampingRatio
///    reads the c_* fields as damping ratios ζ with c = 2ζ√(k m_eq) (reading (b)), m_eq as documented at
///    DampingCoefficients.
/// 3. Typo corrections of eq. 5: ẍ_FS and ÿ_FS (not x̃_FS / I_FS ẏ_FS), damping term c_FS ẏ_FS / r_g² in F_t.
/// 4. Table 3 prints J_WG in "kgm": kg·m² is used.
/// 5. The "radial" FS mass and the tangential FS mass are both J_FS/r_g² (as in eq. 5).
/// 6. Contacts are linear (no loss of contact), as written in eq. 5.
/// 7. Initial conditions: static equilibrium of eq. 6 (all velocities zero) for the given shaft angles,
///    solved in the deflection coordinates above (an exact change of variables of eq. 6); the literal eq. 6
///    in absolute coordinates is available as staticEquilibrium().

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/drive/transmission.hpp"

namespace jointsim::drive {

/// Form of the WG reaction term F_b r_g ρ in the WG equation of eq. 5 (derived from [Raviola2023, eq. 5]).
enum class ReactionForm {
  /// ρ = tan α_n, consistent with x_WG = r_g tan α_n q_WG: static torque ratio exactly τ, stored energy
  /// never increases without input power. Default.
  EnergyConsistent,
  /// ρ = sin α_n cos α_n as printed in [Raviola2023, eq. 5]: static torque ratio τ/cos²α_n (101.0297 for τ = 101,
  /// α_t = 30°) and a spurious power source F_b ẋ_WG sin²α_n.
  PaperLiteral,
};

/// Meaning of the damping fields c_WG, c_b, c_m, c_FS, c_CS (our two readings of [Raviola2023, §2.3]).
enum class DampingMode {
  /// Reading (a): the fields are the damping coefficients themselves (N·m·s/rad or N·s/m). Default.
  Coefficient,
  /// Reading (b): the fields are damping ratios ζ [-] per element, c = 2 ζ √(k m_eq).
  DampingRatio,
};

/// Parameters of the strain wave gear ([Raviola2023, Table 3]). Defaults are size A (UR5 joints 1–3).
struct StrainWaveGearParams {
  double r_g = 30.65e-3;                 ///< primitive radius = undeformed FS radius [m], > 0
  double alpha_t = 0.52359877559829887;  ///< tooth pressure angle α_t [rad], in (0, π/2) (30°)
  double tau = 101.0;                    ///< reduction ratio τ = Z_CS/(Z_CS − Z_FS) [-] (eq. 2), > 1
  double K_WG = 1.92e5;                  ///< motor shaft – WG torsional stiffness [N·m/rad], > 0
  double K_b = 1.9e8;                    ///< WG bearing – FS radial contact stiffness [N/m], > 0
  double K_FS = 3.99e5;                  ///< FS torsional stiffness to the case [N·m/rad], > 0
  double K_m = 5.70e8;                   ///< FS – CS mesh contact stiffness [N/m], > 0
  double K_CS = 1.98e7;                  ///< CS – output flange torsional stiffness [N·m/rad], > 0
  double J_WG = 2.60e-5;                 ///< WG inertia [kg·m²], > 0
  double J_FS = 2.65e-4;                 ///< FS inertia [kg·m²], > 0 (equivalent mass J_FS/r_g² [kg])
  double J_CS = 2.43e-4;                 ///< CS inertia [kg·m²], > 0
  /// Damping of the motor shaft – WG element, >= 0: [N·m·s/rad] (Coefficient) or ζ [-] (DampingRatio).
  double c_WG = 0.1;
  /// Damping of the WG bearing – FS radial contact, >= 0: [N·s/m] (Coefficient) or ζ [-] (DampingRatio).
  double c_b = 0.1;
  /// Damping of the FS – CS mesh contact, >= 0: [N·s/m] (Coefficient) or ζ [-] (DampingRatio).
  double c_m = 0.1;
  /// Damping of the FS – case tangential element, >= 0: [N·m·s/rad] (Coefficient; the force is
  /// c_FS ẏ_FS / r_g²) or ζ [-] (DampingRatio).
  double c_FS = 0.1;
  /// Damping of the CS – output flange element, >= 0: [N·m·s/rad] (Coefficient) or ζ [-] (DampingRatio).
  double c_CS = 0.1;
  ReactionForm reaction_form = ReactionForm::EnergyConsistent;  ///< see ReactionForm
  DampingMode damping_mode = DampingMode::Coefficient;          ///< see DampingMode

  /// Throws jointsim::InputError "StrainWaveGearParams.<field> = <value> <unit>: <rule>" on the first
  /// invalid field (non-finite, out of range).
  void validate() const;
  /// Equivalent inclined-plane angle α_n = arctan(1/(τ tan α_t)) [rad] (eq. 3).
  double alphaN() const;
  /// [Raviola2023, Table 3], size A (UR5 joints 1–3), damping 0.1 read as coefficients.
  static StrainWaveGearParams ur5SizeA();
  /// [Raviola2023, Table 3], size B (UR5 joints 4–6), damping 0.1 read as coefficients.
  static StrainWaveGearParams ur5SizeB();
};

/// Interaction forces of eq. 5 (spring plus damper parts).
struct StrainWaveGearForces {
  double T_in = 0.0;  ///< motor shaft – WG torque T_SWG,in [N·m]
  double F_b = 0.0;   ///< WG bearing – FS radial force [N]
  double F_m = 0.0;   ///< FS – CS mesh force [N]
  double F_t = 0.0;   ///< FS – case tangential force [N]
  double T_CS = 0.0;  ///< CS – output flange torque T_CS [N·m]
};

/// Damping coefficients actually used by the model.
///
/// In DampingMode::DampingRatio, c = 2 ζ √(k m_eq) where m_eq is the effective inertia of the element's
/// deflection coordinate δ with both shafts held: 1/m_eq = Σ_j (∂δ/∂z_j)² / m_j over the internal
/// coordinates z = (q_WG, x_FS, y_FS, q_CS) with masses (J_WG, J_FS/r_g², J_FS/r_g², J_CS):
/// - c_WG: δ = q_in − q_WG, m_eq = J_WG [kg·m²], so c_WG = 2ζ√(K_WG J_WG).
/// - c_b:  δ = r_g tan α_n q_WG − x_FS, 1/m_eq = (r_g tan α_n)²/J_WG + r_g²/J_FS [1/kg].
/// - c_m:  δ = δ_m, 1/m_eq = r_g²/J_FS + r_g² cos²α_t / J_CS [1/kg].
/// - c_FS: δ = y_FS with stiffness K_FS/r_g² and mass J_FS/r_g², so c_FS = 2ζ√(K_FS J_FS) [N·m·s/rad].
/// - c_CS: δ = q_CS − q_out, m_eq = J_CS, so c_CS = 2ζ√(K_CS J_CS).
struct DampingCoefficients {
  double c_WG = 0.0;  ///< [N·m·s/rad]
  double c_b = 0.0;   ///< [N·s/m]
  double c_m = 0.0;   ///< [N·s/m]
  double c_FS = 0.0;  ///< [N·m·s/rad] (tangential force c_FS ẏ_FS / r_g²)
  double c_CS = 0.0;  ///< [N·m·s/rad]
};

/// The strain wave gear as a two-port Transmission (see transmission.hpp for the sign conventions):
/// tau_in = T_SWG,in (against the motor shaft), tau_out = T_CS (delivered to the output shaft).
class StrainWaveGear : public Transmission {
 public:
  /// Number of internal states (4 positions as deflections, 4 velocities).
  static constexpr int kStateSize = 8;
  /// Indices into the internal state vector (see the file comment).
  enum StateIndex : int {
    kTwistWG = 0,  ///< φ_WG = q_in − q_WG [rad]
    kVelWG = 1,    ///< q̇_WG [rad/s]
    kBearing = 2,  ///< Δ_b = x_WG − x_FS [m]
    kVelFSx = 3,   ///< ẋ_FS [m/s]
    kFSy = 4,      ///< y_FS [m]
    kVelFSy = 5,   ///< ẏ_FS [m/s]
    kTwistCS = 6,  ///< φ_CS = q_CS − q_out [rad]
    kVelCS = 7,    ///< q̇_CS [rad/s]
  };

  /// Validates the parameters (InputError) and precomputes the constant coefficients.
  explicit StrainWaveGear(const StrainWaveGearParams& params);

  std::string type() const override { return "strain_wave_gear"; }
  /// τ [-].
  double ratio() const override { return p_.tau; }
  int stateSize() const override { return kStateSize; }
  /// Static equilibrium (eq. 6, all velocities zero) for motor angle q_in [rad] and joint angle q_out
  /// [rad]. Unloaded (all deflections zero) when q_in = τ q_out; otherwise the gear carries the torque
  /// T_CS = staticOutputStiffness()·(q_in/τ − q_out).
  void initialState(double q_in, double q_out, double* x) const override;
  /// Port torques (tau_in = T_SWG,in [N·m], tau_out = T_CS [N·m]) and xdot (8 values). Pure,
  /// allocation-free.
  PortTorques evaluate(const ShaftPorts& ports, const double* x, double* xdot) const override;
  /// E = ½J_WG q̇_WG² + ½(J_FS/r_g²)(ẋ_FS² + ẏ_FS²) + ½J_CS q̇_CS² + ½K_WG φ_WG² + ½K_b Δ_b² + ½K_m δ_m²
  ///     + ½(K_FS/r_g²) y_FS² + ½K_CS φ_CS²  [J]  (the energy-consistent storage function).
  /// Energy balance: dE/dt = tau_in q̇_in − tau_out q̇_out − dissipatedPower() + spuriousPower().
  double storedEnergy(const ShaftPorts& ports, const double* x) const override;
  /// "phi_WG[rad]", "qd_WG[rad/s]", "delta_b[m]", "xd_FS[m/s]", "y_FS[m]", "yd_FS[m/s]", "phi_CS[rad]",
  /// "qd_CS[rad/s]".
  std::vector<std::string> stateNames() const override;

  const StrainWaveGearParams& params() const { return p_; }
  /// Damping coefficients in use (= the c_* fields in Coefficient mode).
  const DampingCoefficients& damping() const { return c_; }
  /// α_n [rad] (eq. 3).
  double alphaN() const;
  /// Static torque ratio tau_out/tau_in under load: τ (EnergyConsistent) or τ/cos²α_n (PaperLiteral) [-].
  double staticTorqueRatio() const;
  /// Static output stiffness with the input shaft held [N·m/rad] (derived from [Raviola2023, eq. 5]):
  /// 1/K_out = (ρ/tan α_n)/(τ² K_WG) + tan²α_t/(r_g² K_b) + 1/(r_g² K_m cos²α_t) + 1/K_FS + 1/K_CS,
  /// where ρ/tan α_n = 1 (EnergyConsistent) or cos²α_n (PaperLiteral).
  double staticOutputStiffness() const;
  /// Literal eq. 6 in the model's absolute coordinates: returns (q_WG [rad], x_WG [m], x_FS [m],
  /// y_FS [m], y_CS [m], q_CS [rad]) at static equilibrium for motor angle q_M and joint angle q_0 [rad].
  /// Row 1 uses the reaction factor ρ of the chosen ReactionForm. Solved with a pivoted QR (Eigen).
  Eigen::Matrix<double, 6, 1> staticEquilibrium(double q_M, double q_0) const;
  /// Absolute coordinates (q_WG, x_WG, x_FS, y_FS, y_CS, q_CS) reconstructed from ports and state.
  Eigen::Matrix<double, 6, 1> absoluteCoordinates(const ShaftPorts& ports, const double* x) const;
  /// Interaction forces of eq. 5 at (ports, x).
  StrainWaveGearForces forces(const ShaftPorts& ports, const double* x) const;
  /// Power dissipated by the five dampers [W], >= 0.
  double dissipatedPower(const ShaftPorts& ports, const double* x) const;
  /// Power injected by the WG reaction form [W]: F_b r_g q̇_WG (tan α_n − ρ), i.e. 0 for EnergyConsistent
  /// and F_b ẋ_WG sin²α_n for PaperLiteral (derived from [Raviola2023, eq. 5]).
  double spuriousPower(const ShaftPorts& ports, const double* x) const;
  /// Undamped small-motion eigenfrequencies [Hz], ascending, of the linear model with DoFs
  /// (q_in, q_WG, x_FS, y_FS, q_CS, q_out), the input shaft of inertia J_in and the output shaft of
  /// inertia J_out [kg·m²] attached (no other forces). Pass +infinity for a held shaft (its DoF is
  /// removed). Both shafts free give a rigid-body mode at 0 Hz. Solved as the generalized eigenproblem
  /// K v = ω² M v (EnergyConsistent: symmetric, GeneralizedSelfAdjointEigenSolver; PaperLiteral: K is
  /// not symmetric, EigenSolver on M⁻¹K, real parts). Throws InputError if J_in or J_out is not > 0.
  Eigen::VectorXd linearisedModes(double J_in, double J_out) const;

  std::vector<ParameterInfo> parameters() const override;
  std::shared_ptr<const Transmission> withParameters(const ParameterChanges& changes) const override;

 private:
  double meshDeflection(const ShaftPorts& ports, const double* x) const;
  double meshRate(const double* x) const;

  StrainWaveGearParams p_;
  DampingCoefficients c_;
  double tn_ = 0.0;    // tan α_n = 1/(τ tan α_t)
  double rho_ = 0.0;   // WG reaction factor ρ
  double st_ = 0.0;    // sin α_t
  double ct_ = 0.0;    // cos α_t
  double rtn_ = 0.0;   // r_g tan α_n [m/rad]
  double m_FS_ = 0.0;  // J_FS / r_g² [kg]
  double kFSt_ = 0.0;  // K_FS / r_g² [N/m]
  double cFSt_ = 0.0;  // c_FS / r_g² [N·s/m]
};

}  // namespace jointsim::drive
