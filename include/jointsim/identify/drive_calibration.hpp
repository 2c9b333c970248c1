#pragma once
/// \file
/// Calibrating a robot's drives from a measured log (`jointsim identify currents`, docs/replay.md): reads the
/// motion and the measured motor currents of a robot log, fits the fast inner model of identify/current_fit.hpp
/// with the nominal drives of a robot-with-drives file, and writes a new robot-with-drives file with the calibrated
/// values, which `tracking` experiments accept:
/// - motor: k_t and k_e multiplied by the fitted scale s (a DC motor's k_e = k_t in SI units);
/// - friction (on the gear output, as before): `{type: lugre, sigma0, sigma1, positive: {alpha0: F_c⁺, alpha1: 0,
///   alpha2: F_v⁺, v_s}, negative: {...}}`, whose steady state is the fitted Coulomb + viscous law of each direction;
///   the bristle stiffness and damping are kept from the file's friction when it has them (sigma0, sigma1), else
///   1e5 N·m/rad and 300 N·m·s/rad;
/// - a fitted current offset (fit_offset) belongs to the measurement, not the drive: it is reported, not written.
/// Everything else of the file (multibody, transmissions, controllers, sensors) is copied; the multibody path is
/// rewritten relative to the new file.

#include <limits>
#include <string>
#include <vector>

#include "jointsim/identify/current_fit.hpp"

namespace jointsim::identify {

/// Columns of a log with measured currents: patterns with {j} (joint 1..n) or {i} (index 0..n−1), expanded for the
/// robot's joints.
struct CurrentLogColumns {
  std::string time;                      ///< time [s]; empty: the first column
  std::string q = "q_actual_{j}";        ///< measured positions [rad]
  std::string qd = "qd_target_{j}";      ///< velocities [rad/s] (the controller's: noise-free)
  std::string qdd = "qdd_target_{j}";    ///< accelerations [rad/s²]
  std::string current = "i_actual_{j}";  ///< measured motor currents [A]
  /// UR RTDE: actual_q_{i}, target_qd_{i}, target_qdd_{i}, actual_current_{i}, timestamp.
  static CurrentLogColumns urRtde();
};

struct DriveCalibrationOptions {
  CurrentFitOptions fit;
  double t_begin = -std::numeric_limits<double>::infinity();  ///< use samples from this log time [s]
  double t_end = std::numeric_limits<double>::infinity();     ///< ... up to this log time [s]
  double gap_factor = 3.0;  ///< a time step > gap_factor × the median is an error (0: no check)
  /// Refinement against the full twin (empty: none): a `tracking` experiment file that replays this log from its
  /// first sample (e.g. config/experiments/ur5_measured_replay.yaml; its `robot` is replaced by the calibrated
  /// drives). Per joint, factors on the inner model's values of k_t (= k_e) and of the Coulomb and viscous friction of
  /// each direction (one law for a joint moved one way only) are then fitted so that the replayed twin's currents
  /// match the measured ones over the window: Levenberg–Marquardt per joint on whole replays (a joint's currents
  /// depend mostly on its own drive, so one replay perturbs one factor of every joint; finite-difference steps of 5 %
  /// of max(factor, 0.2), as stick–slip makes the response rough; up to 8 replays per iteration; a joint whose
  /// accepted step comes out worse with the others' goes back), within the inner fit's bounds (|s − 1| ≤
  /// scale_bound) and friction factors in [0.1, 5] (a vanishing LuGre Coulomb level is a degenerate, very stiff
  /// model; a friction value the inner fit put at 0 stays there). The replay's t = 0 must be the log's first sample.
  /// A trial replay that fails or takes more than max(10 × the first replay's steps, 10⁶) steps counts as worse;
  /// a stop request (sim::Interrupted) ends the calibration. With fit_offset the fitted current offset is taken
  /// off the measured currents and the friction keeps one law for both directions.
  std::string refine_experiment;
  std::vector<std::string> refine_overrides;  ///< further overrides of that experiment ("key.path=value")
  int refine_iterations = 5;                  ///< iterations of the refinement, >= 1
};

/// The refinement against the full twin (DriveCalibrationOptions::refine_experiment).
struct TwinRefinement {
  /// Per joint, factors on the inner fit's values [-]: k_t (= k_e), Coulomb and viscous friction of each direction.
  std::vector<double> kt_factor, coulomb_factor, viscous_factor, coulomb_neg_factor, viscous_neg_factor;
  std::vector<double> rms_before, rms_after;  ///< per joint, the twin against the measurement, % of range
  int replays = 0;                            ///< replays run
};

struct DriveCalibration {
  std::vector<std::string> joints;    ///< joint names, model order
  std::vector<DriveNominal> nominal;  ///< the file's drives
  CurrentFit fit;
  long samples = 0;                 ///< log samples in the window
  std::vector<double> rms_percent;  ///< inner model vs measured over every sample of the window, % of range
  std::string drives_yaml;          ///< the calibrated robot-with-drives file (text)
  TwinRefinement refinement;        ///< empty unless refined against the full twin
};

/// Reads the motion and currents of the `dof` joints from `log_csv` within [t_begin, t_end] (io::readCsv: InputError
/// naming the file, line and column for a missing column, a non-number or non-finite cell; io::checkedTimes: a time
/// that does not increase or a gap).
CurrentLog readCurrentLog(const std::string& log_csv, int dof, const CurrentLogColumns& columns,
                          const DriveCalibrationOptions& options = {});

/// Calibrates the drives of `robot_file` (a robot-with-drives YAML) from `log_csv`; `output_file` is where the
/// drives file will be written (for its relative multibody path). InputError / UnidentifiableError as the parts.
DriveCalibration calibrateDrives(const std::string& robot_file, const std::string& log_csv,
                                 const CurrentLogColumns& columns, const DriveCalibrationOptions& options,
                                 const std::string& output_file);

/// A text report: per joint the estimates ± standard errors, the bounds hit and the inner model's RMS.
std::string formatCalibration(const DriveCalibration& calibration);
/// The same as JSON text.
std::string calibrationJson(const DriveCalibration& calibration);

}  // namespace jointsim::identify
