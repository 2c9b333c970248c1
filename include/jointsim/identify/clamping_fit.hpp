#pragma once
/// \file
/// Ceres fit of the 1-D transmission model of [KR300Thesis, §3.2, §7.3] to a clamping experiment:
///   J φ̈ = τ_meas − τ_fr(φ̇) − EB_{c,d,b}(φ − φ0, φ̇) − d_small φ̇.
/// The clamping procedure is quasi-static by design ([KR300Thesis, §5]); in that limit the model's response on a
/// branch of direction s = sgn(φ̇) is exact:
///   τ = EB_static(φ − φ0; c, b) + s·F [+ k_v φ̇] [+ d φ̇ in contact],
/// with EB_static(x) = c (|x| − b/2) sgn(x) outside the gap |x| ≤ b/2 and 0 inside. The fit minimises the
/// torque residuals of the cleaned half-cycle points of Algorithm II (clamping_curve.hpp) over c, b, F and
/// the nuisance centre φ0 (the encoder zero is arbitrary), starting from the Algorithm II estimates.
/// Standard errors: Ceres covariance (JᵀJ)⁻¹ scaled by the residual variance SSR/(n − p).
/// Optionally the dynamic model is simulated (joint rig, clamped, driven by the measured torque) and the
/// angle residual is reported as a validation.
///
/// Motor side throughout: c [N·m/rad], b [rad] (total backlash, ElastoBacklash's b), F [N·m].

#include <optional>
#include <string>

#include "jointsim/drive/parameters.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/identify/clamping_curve.hpp"

namespace jointsim::identify {

struct ClampingFitOptions {
  ClampingCurveOptions curve;  ///< Algorithm II settings
  /// Known total backlash [rad], >= 0: b is held fixed (for data that never cross zero torque, where the
  /// backlash is unobservable). Empty: b is fitted.
  std::optional<double> fixed_backlash;
  bool fit_viscous = false;  ///< also fit a viscous friction k_v [N·m·s/rad] (acts everywhere)
  bool fit_damping = false;  ///< also fit the transmission damper d [N·m·s/rad] (acts in contact)
  /// Half-width of the central difference that estimates φ̇ for the optional terms [samples], >= 1.
  int velocity_half_window = 2;
  int max_iterations = 100;  ///< Ceres iterations [-]
  /// An optional velocity term (viscous, damping) is reported unidentifiable when its standard error times
  /// the RMS speed exceeds this fraction of the fitted friction F [-].
  double max_relative_std_error = 0.5;
  // --- validation simulation (simulate_validation)
  bool simulate_validation = false;  ///< simulate the dynamic model driven by the measured torque
  double rotor_inertia = 0.01;       ///< J [kg·m²] for the validation ([KR300Thesis] does not give it), > 0
  double validation_damping = 0.5;   ///< EB damper d [N·m·s/rad] if not fitted ([KR300Thesis]: "small"), >= 0
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// One identified parameter.
struct FittedParameter {
  double value = 0.0;      ///< in `unit`
  double std_error = 0.0;  ///< standard error [unit]; 0 when fixed
  bool fitted = false;     ///< false: held at a given value
  double initial = 0.0;    ///< Algorithm II estimate (start value) [unit]
};

struct ClampingFitResult {
  FittedParameter stiffness;               ///< c [N·m/rad]
  FittedParameter backlash;                ///< total backlash b [rad]
  FittedParameter friction;                ///< Coulomb friction F [N·m]
  FittedParameter center;                  ///< gap centre φ0 in the log's angle [rad] (nuisance)
  std::optional<FittedParameter> viscous;  ///< k_v [N·m·s/rad] (fit_viscous)
  std::optional<FittedParameter> damping;  ///< d [N·m·s/rad] (fit_damping)
  double rms_residual = 0.0;               ///< RMS torque residual of the fit [N·m]
  int points = 0;                          ///< residuals used
  int iterations = 0;                      ///< Ceres iterations
  std::string solver_summary;              ///< Ceres one-line report
  /// Validation simulation: RMS of simulated − measured angle over all samples [rad] (if run).
  std::optional<double> validation_angle_rms;
  ClampingCurves curves;  ///< Algorithm II results and diagnostics
};

/// Algorithm II + Ceres fit. Throws UnidentifiableError (naming the parameter and why) when the data
/// cannot determine a parameter: the curve never crosses zero torque (backlash; set fixed_backlash), too
/// many half-cycles rejected, no linear region, a rank-deficient fit; InputError for bad data/options.
ClampingFitResult identifyClamping(const ClampingData& data, const ClampingFitOptions& options = {});

/// The static model: EB_static(x; c, b) [N·m] for deflection x [rad].
double elastoBacklashStatic(double x, double stiffness, double backlash);

/// YAML report of a result (parameters with value, unit, std_error; Algorithm II estimates; residuals;
/// half-cycles; side and gear ratio). `data_path` and `gear_ratio` [-] are echoed.
std::string clampingReportYaml(const ClampingFitResult& result, const std::string& data_path, double gear_ratio);

/// The fit applied to a drive's gear by the keys of its parameter table (drive/parameters.hpp): `stiffness` and
/// `backlash` (and `damping` when it was fitted) of a gear with one spring (elastic, elasto_backlash), converted from
/// the motor side on which they are identified to the gear's compliance side (output side: c = N² c_m, b = b_m / N,
/// d = N² d_m with N = gear.ratio()). The Coulomb friction F belongs to the friction model and is not included.
/// \throws InputError naming the gear's type when it has no such keys or more than one stiffness (a strain-wave gear).
drive::ParameterChanges clampingChanges(const ClampingFitResult& fit, const drive::Transmission& gear);

}  // namespace jointsim::identify
