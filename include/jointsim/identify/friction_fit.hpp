#pragma once
/// \file
/// Identification of the static friction map ([Hauschild2003, §4.5.4]): per direction of motion, the
/// exponential (Stribeck) model of [Hauschild2003, eq. 4.6, Table 4.3], which is also the steady state of the LuGre
/// model (eq. 4.21, δ = 2),
///
///   F(v) = (α0 + α1·exp(−(|v|/v_S)^δ))·sgn(v) + α2·v,
///
/// is fitted to measured (velocity, friction torque) pairs by nonlinear least squares (Ceres, automatic
/// differentiation; [Hauschild2003] used a Nelder–Mead simplex). Ceres is an implementation detail: it does not
/// appear in this header.
///
/// Procedure (docs/identify_friction.md):
/// 1. Points with v = 0 belong to neither direction and are dropped (counted in FrictionFit::dropped_zero).
///    Points with v > 0 form the positive direction, v < 0 the negative one; each is fitted in magnitudes
///    (|v|, −F for v < 0). Order and duplicates do not matter.
/// 2. Initial guesses per direction from the data: a straight line through the fastest third of the points
///    gives α2 (slope, ≥ 0) and α0 (intercept, > 0); the excess of the slowest points over that line gives
///    α1; the speed at which the excess has decayed to 1/e of α1 gives v_S.
/// 3. Bounds: α0 ≥ 0, α1 ≥ 0, α2 ≥ 0, v_S in [min|v|/100, 100·max|v|], δ in [0.25, 8] when free.
/// 4. Standard errors from the Gauss–Newton covariance (J^T J)^{-1} at the optimum (ceres::Covariance), scaled
///    by the residual variance σ² = SSR/(m − p) of the direction (m points, p fitted parameters).
/// 5. Identifiability checks (UnidentifiableError naming the direction): fewer than `min_points` points; no
///    Stribeck dip (α1 not significantly above zero, so v_S has no effect); fewer than three points slower
///    than 2·v_S (the dip is not sampled); a singular covariance; a relative standard error of α0, α1 or v_S
///    above `max_relative_std_error`.

#include <string>
#include <vector>

#include "jointsim/drive/friction_models.hpp"

namespace jointsim::identify {

/// Robust loss applied to the torque residuals (ceres::HuberLoss / ceres::CauchyLoss with scale loss_scale).
enum class FitLoss { None, Huber, Cauchy };

/// Options of fitFrictionMap().
struct FrictionFitOptions {
  double delta = 2.0;            ///< δ: form factor [-] (start value when fit_delta), > 0; 2 = LuGre (eq. 4.17)
  bool fit_delta = false;        ///< fit one δ shared by both directions (default: fixed at `delta`)
  int min_points = 8;            ///< minimum number of points per direction [-], >= 6
  FitLoss loss = FitLoss::None;  ///< robust loss on the residuals
  double loss_scale = 0.1;       ///< residual scale of the robust loss [N·m], > 0
  /// Largest accepted relative standard error of α0, α1 and v_S [-]; above it the direction is unidentifiable.
  double max_relative_std_error = 0.5;
  int max_iterations = 200;  ///< Levenberg–Marquardt iteration limit [-]
  /// \throws InputError naming the field, its value and the rule.
  void validate() const;
};

/// One fitted parameter.
struct ParameterEstimate {
  double value = 0.0;      ///< estimate [unit of the parameter]
  double std_error = 0.0;  ///< standard error (1σ) [unit of the parameter]; 0 for a fixed parameter
  double initial = 0.0;    ///< initial guess derived from the data [unit of the parameter]
};

/// Fit of one direction of motion. All values are magnitudes (the map of v < 0 is −F(|v|)).
struct DirectionFit {
  std::string direction;      ///< "positive" (v > 0) or "negative" (v < 0)
  ParameterEstimate alpha0;   ///< α0: Coulomb friction [N·m]
  ParameterEstimate alpha1;   ///< α1: additional stiction, static friction α0 + α1 [N·m]
  ParameterEstimate alpha2;   ///< α2: viscous coefficient [N·m·s/rad]
  ParameterEstimate v_s;      ///< v_S: Stribeck velocity [rad/s]
  int points = 0;             ///< number of points used [-]
  double min_speed = 0.0;     ///< smallest |v| of the direction [rad/s]
  double max_speed = 0.0;     ///< largest |v| of the direction [rad/s]
  double rms_residual = 0.0;  ///< root mean square of the torque residuals, sqrt(SSR/m) [N·m]
  double sigma = 0.0;         ///< residual standard deviation sqrt(SSR/(m − p)) used for the std errors [N·m]
  /// The estimates as a drive::StribeckBranch (α0, α1, α2, v_S).
  drive::StribeckBranch branch() const;
  /// Fitted static map (magnitude) at speed w >= 0 with form factor delta: α0 + α1·e^{−(w/v_S)^δ} + α2·w [N·m].
  double magnitude(double w, double delta) const;
};

/// Result of fitFrictionMap().
struct FrictionFit {
  DirectionFit positive;      ///< parameters for v > 0
  DirectionFit negative;      ///< parameters for v < 0 (magnitudes)
  ParameterEstimate delta;    ///< δ [-] (std_error 0 when fixed)
  bool delta_fitted = false;  ///< whether δ was a free parameter
  int dropped_zero = 0;       ///< points with v = 0, belonging to neither direction [-]
  int iterations = 0;         ///< Ceres iterations [-]
  double solve_time_s = 0.0;  ///< wall time of the fit including the covariance [s]
  /// Steady-state friction of the fitted map at velocity v [rad/s] (0 at v = 0) [N·m].
  double map(double v) const;
};

/// Fits the static friction map to the points (velocity[i] [rad/s], torque[i] [N·m]) — the torque the
/// friction exerts against the motion, positive for v > 0.
/// \throws InputError if the vectors differ in size or contain a non-finite value, or the options are invalid.
/// \throws UnidentifiableError (message naming the direction and the reason) if a direction cannot be fitted.
FrictionFit fitFrictionMap(const std::vector<double>& velocity, const std::vector<double>& torque,
                           const FrictionFitOptions& options = {});

/// A measured friction map read from a CSV file.
struct FrictionMapData {
  std::vector<double> velocity;  ///< velocity [rad/s]
  std::vector<double> torque;    ///< friction torque [N·m]
  std::vector<int> lines;        ///< 1-based file line of each point
};

/// Reads a CSV with the columns `velocity[rad/s]` and `friction_torque[N*m]` (matched by base name; other
/// columns are ignored but must be numeric).
/// \throws InputError "PATH:LINE: ..." for an unreadable file, a missing column, a non-numeric or non-finite
/// cell, or a file without data rows.
FrictionMapData readFrictionMap(const std::string& path);

/// The fit applied to a friction model of a drive by the keys of the model's parameter table (drive/parameters.hpp):
/// the static set of both directions (positive.alpha0 … negative.v_s) and, where the model has it, the form factor
/// delta; for any model with those keys (stribeck, lugre), e.g. `model.withParameters(frictionChanges(fit, model))`
/// or the same keys under an experiment's `drives: {JOINT: {friction: ...}}`.
/// \throws InputError naming the model and the missing key when its table lacks one of the static set, or when the
/// fit has δ ≠ 2 and the model has no delta (LuGre's Stribeck curve has δ = 2).
drive::ParameterChanges frictionChanges(const FrictionFit& fit, const drive::Friction& model);

/// Options of frictionFitYaml().
struct FrictionYamlOptions {
  std::string source;         ///< name of the map file, written as fit.source (may be empty)
  bool lugre = false;         ///< write `type: lugre` with sigma0/sigma1 instead of `type: stribeck`
  double sigma0 = 259.0;      ///< σ0 for `lugre` [N·m/rad] ([Hauschild2003, §4.5.4]), > 0
  double sigma1 = 10.0;       ///< σ1 for `lugre` [N·m·s/rad] ([Hauschild2003, §4.5.4]), > 0
  double k_s = 300.0;         ///< slope-limiter factor of `stribeck` ([Hauschild2003, eq. 4.24]) [s/rad], > 0
  double wall_time_s = -1.0;  ///< identification wall time written as fit.wall_time_s when >= 0 [s]
};

/// YAML text with a top-level `friction:` mapping, directly readable by the friction-model YAML reader
/// (type stribeck with delta, k_s, positive:, negative:; or type lugre with sigma0, sigma1), and a `fit:`
/// mapping with, per direction and parameter, value, unit and std_error, plus rms_residual [N·m] and points.
/// \throws InputError if `lugre` is requested with δ ≠ 2 or the options are invalid.
std::string frictionFitYaml(const FrictionFit& fit, const FrictionYamlOptions& options = {});

}  // namespace jointsim::identify
