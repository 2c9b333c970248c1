#pragma once
/// \file
/// Drive parameters from measured motor currents along a robot's motion (docs/replay.md): the fast inner model of
/// the calibration from a robot log. Per joint j, with the joint torque of the inverse dynamics along the motion,
///
///   τ_j = RNEA_j(q, q̇, q̈) + J_M,j N_j² q̈_j                                    [N·m]  (rotor inertia reflected)
///   i_j = (τ_j + τ_f,j(q̇_j)) / (N_j k_t,j s_j) + i₀,j                            [A]
///   τ_f(v) = F_c⁺ + F_v⁺ v for v > 0,  −(F_c⁻ + F_v⁻ |v|) for v < 0                [N·m]
///
/// the torque-constant scale s (the arm's k_t = s × the nominal), the Coulomb F_c and viscous F_v friction of each
/// direction at the joint, or (`fit_offset`) a symmetric Coulomb friction and a current offset i₀, are fitted by bounded nonlinear least squares (Ceres,
/// automatic differentiation) to the measured currents. Samples with |q̇| < min_speed are left out: there the
/// static friction is anywhere within ±F_c (the model has no stiction). Joints are independent problems.
/// Bounds (documented, physically meaningful): |s − 1| ≤ scale_bound (default 0.4), F_c, F_v ≥ 0, |i₀| ≤
/// max_offset. Standard errors from the Gauss–Newton covariance scaled by the residual variance SSR/(m − p).
/// Ceres is an implementation detail: it does not appear in this header.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/identify/friction_fit.hpp"
#include "jointsim/multibody/model.hpp"

namespace jointsim::identify {

/// A robot's motion with measured motor currents, K samples of n joints.
struct CurrentLog {
  std::string source = "log";  ///< names the data in messages
  Eigen::MatrixXd q;           ///< K × n joint positions [rad] (measured)
  Eigen::MatrixXd qd;          ///< K × n joint velocities [rad/s] (the controller's command: noise-free)
  Eigen::MatrixXd qdd;         ///< K × n joint accelerations [rad/s²] (the controller's command)
  Eigen::MatrixXd current;     ///< K × n measured motor currents [A]
  /// The samples' times since the log's first sample [s] (set by readCurrentLog; the fit does not use them).
  std::vector<double> t;
};

/// The nominal drive of a joint.
struct DriveNominal {
  double ratio = 1.0;          ///< N: motor angle / joint angle [-]
  double kt = 1.0;             ///< k_t: torque constant [N·m/A]
  double rotor_inertia = 0.0;  ///< J_M [kg·m²]
};

struct CurrentFitOptions {
  double min_speed = 0.01;   ///< samples with |q̇| below are not fitted [rad/s], >= 0
  double scale_bound = 0.4;  ///< |s − 1| ≤ scale_bound [-], in (0, 1)
  double max_offset = 1.0;   ///< |i₀| ≤ max_offset [A], >= 0
  int max_iterations = 200;  ///< Levenberg–Marquardt iteration limit [-]
  /// Fit a current offset i₀ instead of a direction-dependent Coulomb friction (then F_c⁻ = F_c⁺): the two are one
  /// degree of freedom of moving samples (i₀ ± F_c/(N k_t s)), so only one of them can be fitted. Default: the
  /// Coulomb friction per direction, i₀ = 0.
  bool fit_offset = false;
  /// \throws InputError naming the field, its value and the rule.
  void validate() const;
};

/// Fit of one joint.
struct JointCurrentFit {
  ParameterEstimate kt_scale;     ///< s [-]
  ParameterEstimate coulomb_pos;  ///< F_c⁺ [N·m]
  ParameterEstimate coulomb_neg;  ///< F_c⁻ [N·m] (a magnitude)
  ParameterEstimate viscous_pos;  ///< F_v⁺ [N·m·s/rad]
  ParameterEstimate viscous_neg;  ///< F_v⁻ [N·m·s/rad] (a magnitude)
  ParameterEstimate offset;       ///< i₀ [A] (0, not fitted, unless fit_offset)
  int points = 0;                 ///< samples fitted [-]
  /// True when the motion moved this joint in one direction only (fewer than 20 samples the other way): one
  /// Coulomb and one viscous coefficient for both directions (the negative ones equal the positive ones).
  bool tied = false;
  double rms = 0.0;                   ///< RMS current residual over the fitted samples [A]
  std::vector<std::string> at_bound;  ///< names of the parameters that ended on a bound
};

struct CurrentFit {
  std::vector<JointCurrentFit> joints;  ///< one per joint, in model order
};

/// Fits every joint (see the file comment). InputError on inconsistent sizes, non-finite data or bad options;
/// UnidentifiableError (naming the joint) when a joint has fewer than 40 moving samples or a singular covariance.
/// A joint moved in one direction only (fewer than 20 samples the other way) gets one friction law for both
/// (JointCurrentFit::tied).
CurrentFit fitDriveCurrents(const multibody::Model& model, const std::vector<DriveNominal>& drives,
                            const CurrentLog& log, const CurrentFitOptions& options = {});

/// The inner model's currents (K × n) [A] along `log` with the parameters of `fit` (every sample, also at rest:
/// τ_f = 0 there).
Eigen::MatrixXd predictCurrents(const multibody::Model& model, const std::vector<DriveNominal>& drives,
                                const CurrentLog& log, const CurrentFit& fit);

}  // namespace jointsim::identify
