#pragma once
/// \file
/// Algorithm II preprocessing of a clamping experiment ([KR300Thesis, §4.3, Table 6.1]): the motor is
/// driven slowly back and forth against a clamped output; the clamping curve is motor torque vs motor
/// angle. The data are cut into half-cycles (runs of one direction of motion), each half-cycle is cleaned
/// (turning regions and outliers removed), outlier half-cycles are rejected, the rest are classified as
/// upper (loading, φ̇ > 0) or lower (unloading) curves and merged onto grids. The fold of the aligned,
/// merged curve gives the initial estimates of the stiffness c, the total backlash b and the Coulomb
/// friction F that clamping_fit.hpp refines with Ceres.
///
/// All quantities are motor side: angles [rad], torques [N·m], c [N·m/rad]. Defaults of the steps the
/// source leaves open are documented field by field and in docs/identify_clamping.md.
///
/// Errors: InputError for data that are not a clamping experiment (missing columns, NaN, time not
/// strictly increasing, too few rows, fewer than 2 half-cycles); UnidentifiableError when half-cycles
/// exist but too many are rejected (joint 2 of [KR300Thesis]) or no linear region is left.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim::identify {

/// One clamping log, motor side.
struct ClampingData {
  std::string source;      ///< file name (for messages), may be empty
  Eigen::VectorXd time;    ///< sample times [s], strictly increasing
  Eigen::VectorXd angle;   ///< motor angle [rad] (zero arbitrary)
  Eigen::VectorXd torque;  ///< motor-side torque [N·m]
  std::vector<int> lines;  ///< 1-based file line of each sample (empty when not read from a file)
  /// Throws InputError if the sizes differ, a value is not finite, the time is not strictly increasing
  /// (naming the file line when known) or there are fewer than `min_rows` samples.
  void validate(int min_rows = 20) const;
};

/// Reads a CSV log with columns `time[s]`, `motor_angle[rad]`, `motor_torque[N*m]` (matched by base name;
/// other columns are ignored) and divides the torque by `gear_ratio` [-] (KUKA logs the arm-side torque,
/// i.e. motor torque × ratio; 1 = the column is already motor side). Throws InputError (file:line) for a
/// missing column, a non-numeric or non-finite cell, an unsorted time, too few rows or gear_ratio ≤ 0.
ClampingData readClampingCsv(const std::string& path, double gear_ratio = 1.0);

/// Settings of Algorithm II. "Source" marks values given by [KR300Thesis]; the others are not given there.
struct ClampingCurveOptions {
  // --- step 1: half-cycle segmentation
  /// Steps |x[k+1] − x[k]| below this factor × the mean |step| are set to 0 [-] (source: 1, the mean).
  double step_threshold_factor = 1.0;
  /// Zero-phase (centred) moving-average window on the step signal [samples], odd, >= 1.
  int step_filter_window = 5;
  /// Direction runs shorter than this are turning-region flicker and are dropped [samples], >= 2.
  int min_run_samples = 10;
  // --- step 2: per half-cycle cleaning
  /// Drop stuck samples inside a half-cycle: both adjacent angle steps below the step-1 threshold. Only
  /// sliding points obey the branch law τ = EB + sgn(φ̇) F; in torque-driven data the motor sticks for a
  /// moment after it has flown across the gap (overshoot), which would widen the fitted backlash.
  bool drop_stuck_points = true;
  /// Fraction of the points with the smallest and (separately) the largest positions removed [-].
  double extreme_fraction = 0.02;
  /// Fraction of the half-cycle's position interval removed at each end (turning dynamics) [-]
  /// (0.1 is the source's Algorithm I end trim).
  double end_trim_fraction = 0.1;
  /// Point outliers: |residual to the half-cycle's LS line| > point_kappa × σ are removed [-].
  double point_kappa = 3.0;
  /// A half-cycle with fewer cleaned points is dropped (N_min) [-].
  int min_points = 20;
  // --- steps 3 and 5: half-cycle outlier rejection
  /// Reject a half-cycle whose slope or representative torque differs from the group mean by more than
  /// half_cycle_kappa standard deviations [-] (source: 2).
  double half_cycle_kappa = 2.0;
  /// ... and by more than this fraction of the mean slope [-] (floor: identical half-cycles are not
  /// rejected for noise-level differences).
  double min_slope_deviation = 0.05;
  /// ... or, for the representative torque, by more than this fraction of the data's torque half-span [-].
  double min_torque_deviation = 0.05;
  /// The data set is rejected (UnidentifiableError) when more than this fraction of the half-cycles
  /// was dropped in steps 2–5 [-].
  double max_rejected_fraction = 0.5;
  // --- step 6: merge
  /// The merged interval is covered by at least ceil(coverage_fraction × group size) half-cycles [-].
  double coverage_fraction = 0.5;
  /// Half-cycles spanning less than this fraction of the longest span in their group are partial (the
  /// log's first loading from zero, a last swing cut short) and left out of the merge [-].
  double min_span_fraction = 0.6;
  /// Grid points of each merged curve (n_grid) [-], >= 20.
  int grid_points = 400;
  // --- steps 8–11: backlash interval, alignment, fold
  /// Low-slope threshold φ: a derivative below φ × (LS slope of the whole curve) is "flat" [-].
  double slope_threshold = 0.3;
  /// Width of the local LS window that estimates the curve's derivative, as a fraction of the curve's
  /// position span [-] (at least 3 grid points).
  double slope_window_fraction = 0.03;
  /// The backlash is observable only if the mid-line (upper + lower)/2 of the curves is below
  /// −zero_margin and above +zero_margin (fraction of max |mid-line|) on at least min_side_fraction of
  /// the common interval each [-]. Otherwise the curve never crosses zero torque (joint 2 of [KR300Thesis]).
  double zero_margin = 0.05;
  double min_side_fraction = 0.1;  ///< see zero_margin [-]
  /// Minimum number of folded-curve points beyond the flat interval (linear region) [-].
  int min_linear_points = 10;
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// One half-cycle: a run of one direction of motion.
struct HalfCycle {
  int first = 0, last = 0;  ///< sample range [first, last] in the data
  int direction = 0;        ///< +1 (angle increasing: loading, upper curve) or −1
  std::vector<int> kept;    ///< indices of the cleaned points (empty if dropped in step 2)
  double slope = 0.0;       ///< LS slope of the cleaned points [N·m/rad]
  double rep_torque = 0.0;  ///< the line at the mean position of all data [N·m]
  bool upper = false;       ///< classified upper (step 4)
  bool rejected = false;    ///< dropped in steps 2, 3 or 5
  std::string reason;       ///< why it was dropped
};

/// A curve sampled on an evenly spaced grid.
struct GridCurve {
  Eigen::VectorXd x;    ///< positions [rad], increasing
  Eigen::VectorXd tau;  ///< torques [N·m]
  bool empty() const { return x.size() == 0; }
  /// Linear interpolation; positions outside the grid are clamped to its ends [N·m].
  double at(double position) const;
};

/// Algorithm II results and diagnostics.
struct ClampingCurves {
  std::vector<HalfCycle> half_cycles;  ///< every half-cycle found (step 1), with its fate
  int used_upper = 0, used_lower = 0;  ///< half-cycles kept per curve
  int rejected = 0;                    ///< half-cycles dropped
  GridCurve upper, lower;              ///< merged curves (step 6)
  GridCurve merged;                    ///< aligned and merged single curve (step 9), upper-curve level
  GridCurve folded;                    ///< fold F[j] vs distance from the middle (step 10) [rad, N·m]
  double mean_position = 0.0;          ///< mean angle of all data [rad]
  double torque_half_span = 0.0;       ///< (max τ − min τ)/2 of all data [N·m]
  bool crosses_zero = false;           ///< the mid-line crosses zero torque: backlash observable
  double backlash_upper = 0.0;         ///< length of the upper curve's low-slope interval [rad] (0: none)
  double backlash_lower = 0.0;         ///< same for the lower curve [rad]
  double fold_flat = 0.0;              ///< flat length of the folded curve = half the backlash [rad]
  /// Initial estimates: c [N·m/rad], total backlash b = 2 × fold_flat [rad], friction F = half the mean
  /// distance of the curves [N·m], centre of the gap φ0 [rad] (angle of the fold's middle).
  double stiffness = 0.0, backlash = 0.0, friction = 0.0, center = 0.0;
};

/// Runs Algorithm II on `data` (validated first). If the mid-line never crosses zero torque the fold is
/// skipped, `crosses_zero` is false and the backlash estimate is 0 (the fit decides whether that is an
/// error). Throws InputError for fewer than 2 half-cycles, UnidentifiableError when too many half-cycles
/// were rejected, a curve is left without half-cycles, or no linear region remains.
ClampingCurves preprocessClampingCurve(const ClampingData& data, const ClampingCurveOptions& options = {});

// ---- building blocks (exposed for tests)

/// Step 1: half-cycles (direction runs) of the angle sequence; `kept` left empty.
std::vector<HalfCycle> segmentHalfCycles(const Eigen::VectorXd& angle, const ClampingCurveOptions& options);

/// Step 6 "merge": averages the piecewise-linear curves (x sorted per curve) on n evenly spaced points of
/// the interval covered by at least `min_cover` of them (the longest such interval). Empty if none.
GridCurve mergeCurves(const std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>& curves, int min_cover, int n);

/// Local LS slope of a grid curve over a centred window of `window` points (shortened at the ends) [N·m/rad].
Eigen::VectorXd localSlope(const GridCurve& curve, int window);

/// Longest interior run of grid indices [first, last] with slope < threshold; {-1, -1} if none. Runs
/// touching the first or last grid point are not interior.
std::pair<int, int> longestFlatRun(const Eigen::VectorXd& slope, double threshold);

/// Steps 10–11 on a single (merged) curve: fold about `middle` [rad]; returns F[j] vs distance and sets
/// `flat` to the length of the initial interval with dF/dj < φ × (LS slope of F) [rad] and `stiffness` to
/// the LS slope beyond it [N·m/rad]. Throws UnidentifiableError if fewer than options.min_linear_points
/// points remain beyond the flat interval or the slope is not positive.
GridCurve foldCurve(const GridCurve& merged, double middle, const ClampingCurveOptions& options, double& flat,
                    double& stiffness);

}  // namespace jointsim::identify
