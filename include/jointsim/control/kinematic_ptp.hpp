#pragma once
/// \file
/// `KinematicPtpTrajectory` — the Modelica Standard Library path planner
/// `Modelica.Blocks.Sources.KinematicPTP2` (used by the RobotR3 examples FullRobot and OneAxis through
/// `PathPlanning6` / `PathPlanning1`), re-implemented with the MSL equations operation for operation so
/// that the set-points agree with Dymola reference results to rounding ([MSL, Blocks.Sources.KinematicPTP2]).
///
/// Semantics (time-optimal, synchronised point-to-point move; all axes share one normalised path s(t)):
///
///     Δ_i = q_end_i − q_begin_i
///     q_i = q_begin_i + Δ_i·s(t),   qd_i = Δ_i·ṡ(t),   qdd_i = Δ_i·s̈(t)
///     V = 1 / max_i |Δ_i / qd_max_i|      (path speed limit; the slowest axis w.r.t. speed decides)
///     A = 1 / max_i |Δ_i / qdd_max_i|     (path acceleration limit; may be decided by another axis)
///     Ta1 = sqrt(1/A),  Ta2 = V/A,  triangular ("no constant-velocity phase") ⇔ Ta2 >= Ta1
///     triangular:  Tv = Ta1, Te = Ta1 + Ta1, peak path speed V2 = A·Ta1
///     trapezoidal: Tv = 1/V, Te = Tv + Ta2
///     endTime = start_time + Te
///
/// Every axis therefore starts, switches phase and stops at the same instants; exactly one axis reaches
/// its speed limit (trapezoidal case) and one (possibly other) axis its acceleration limit, the others
/// stay below theirs. Phase switches use "t < boundary" comparisons against start_time + Ta1/Ta2/Tv/Te,
/// so at a boundary the later phase applies (right-continuous qdd; at t = start_time the motion is
/// already accelerating: qdd = Δ·A). After endTime the planner holds q_begin + Δ·s_end, where s_end is the
/// MSL's closed-form end value (1 up to rounding; not forced to be bit-exactly q_end).
///
/// Degenerate motion: if max_i |Δ_i/qd_max_i| <= ε or max_i |Δ_i/qdd_max_i| <= ε (ε = 10·1e-15 = 1e-14, the
/// MSL's 10·Modelica.Constants.eps), then s ≡ 0 (q = q_begin, even for an axis with a tiny non-zero Δ)
/// and endTime() = 0 — NOT start_time (MSL quirk, kept on purpose).
///
/// `moving(i, t)` = (|q_begin_i − q_end_i| > ε) and (t < endTime()), the MSL `moving` output.
///
/// Simulation termination rule ([MSL, RobotR3.Utilities.PathPlanning1/PathPlanning6], MSL
/// `TerminateSimulation(condition = time >= path.endTime + swingTime)`): the robot experiments FullRobot and
/// OneAxis stop the simulation at the first instant t with t >= endTime() + swingTime (swingTime = 0.5 s in
/// both), i.e. at `terminationTime(0.5)` (FullRobot 1.8560450019 s, OneAxis 1.4981317008 s; both before their
/// stop times 2 s / 1.6 s, so the reference files end there). A simulator driving this trajectory should
/// integrate up to exactly terminationTime(swing) and end the run there (the Dymola results have their last row
/// at that instant).
///
/// JointTrajectory mapping: duration() = endTime(); breakpoints() = start_time (if > 0) and the phase switches
/// start_time + Ta2 (or Ta1), + Tv, + Te; before start_time the trajectory rests at q_begin. The
/// acceleration-only variant `KinematicPTP` ([MSL, Blocks.Sources.KinematicPTP]) uses the same timing: it
/// equals this trajectory's qdd with q_begin = 0, q_end = deltaq (minus the degenerate-motion guard).
/// Units: SI, positions [rad], speeds [rad/s], accelerations [rad/s²], times [s].

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/trajectory.hpp"

namespace jointsim::control {

/// MSL KinematicPTP2 (see the file comment for the exact semantics).
class KinematicPtpTrajectory final : public JointTrajectory {
 public:
  /// ε of the degenerate-motion test and of `moving` (10·Modelica.Constants.eps, with eps = 1e-15).
  static constexpr double kEps = 1e-14;

  /// Parameters as in MSL: `q_begin`, `q_end` [rad], `qd_max` [rad/s] > 0, `qdd_max` [rad/s²] > 0, one
  /// entry per axis; as in MSL, a vector of size 1 is broadcast to the common size n = max of the sizes
  /// (any other size mismatch is an error). `start_time` [s] must be >= 0 (the trajectory is defined from
  /// t = 0; MSL would also allow negative values). Throws InputError on sizes, non-finite values or limits
  /// that are not > 0.
  KinematicPtpTrajectory(const Eigen::VectorXd& q_begin, const Eigen::VectorXd& q_end, const Eigen::VectorXd& qd_max,
                         const Eigen::VectorXd& qdd_max, double start_time = 0.0);

  int dof() const override { return static_cast<int>(qb_.size()); }
  /// = endTime() [s].
  double duration() const override { return end_time_; }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                Eigen::Ref<Eigen::VectorXd> qdd) const override;
  std::vector<double> breakpoints() const override;
  /// E.g. "kinematic_ptp(6 joints, trapezoidal, start 0 s, end 1.35605 s)".
  std::string describe() const override;

  /// MSL output `endTime` = start_time + Te [s]; 0 for a degenerate motion (see the file comment).
  double endTime() const { return end_time_; }
  /// The instant at which a robot experiment ends ([MSL, RobotR3.Utilities.PathPlanning1/PathPlanning6]):
  /// endTime() + swing_time [s].
  double terminationTime(double swing_time) const { return end_time_ + swing_time; }
  /// MSL output moving[i] at time t [s] (0-based axis i).
  bool moving(int i, double t) const;

  /// Normalised path s(t) ∈ [0, 1] and its exact derivatives ṡ [1/s], s̈ [1/s²] (MSL branches).
  void evaluatePath(double t, double& s, double& sd, double& sdd) const;

  bool degenerate() const { return degenerate_; }
  /// True for the triangular profile (MSL noWphase: no constant-velocity phase).
  bool triangular() const { return no_w_phase_; }
  double startTime() const { return t0_; }
  /// max_i |Δ_i/qd_max_i| [s] and max_i |Δ_i/qdd_max_i| [s²], with the (first) axes attaining them.
  double speedRatioMax() const { return sd_max_inv_; }
  double accelerationRatioMax() const { return sdd_max_inv_; }
  int speedLimitingAxis() const { return speed_axis_; }
  int accelerationLimitingAxis() const { return accel_axis_; }
  /// V [1/s] and A [1/s²] (0 when degenerate).
  double pathSpeed() const { return sd_max_; }
  double pathAcceleration() const { return sdd_max_; }
  /// Phase durations relative to start_time [s] (all 0 when degenerate): Ta1 = sqrt(1/A), Ta2 = V/A,
  /// Tv = start of deceleration (Ta1 if triangular, else 1/V), Te = end of motion.
  double Ta1() const { return Ta1_; }
  double Ta2() const { return Ta2_; }
  double Tv() const { return Tv_; }
  double Te() const { return Te_; }
  /// Peak path speed actually reached [1/s]: A·Ta1 if triangular, else V.
  double peakPathSpeed() const { return no_w_phase_ ? sd_max2_ : sd_max_; }

  const Eigen::VectorXd& qBegin() const { return qb_; }
  const Eigen::VectorXd& qEnd() const { return qe_; }
  const Eigen::VectorXd& qdMax() const { return qd_max_; }
  const Eigen::VectorXd& qddMax() const { return qdd_max_; }
  /// Δ = q_end − q_begin [rad].
  const Eigen::VectorXd& delta() const { return dq_; }

 private:
  Eigen::VectorXd qb_, qe_, qd_max_, qdd_max_, dq_;
  double t0_ = 0.0;
  bool degenerate_ = true, no_w_phase_ = false;
  double sd_max_inv_ = 0, sdd_max_inv_ = 0;
  int speed_axis_ = 0, accel_axis_ = 0;
  double sd_max_ = 0, sdd_max_ = 0, Ta1_ = 0, Ta2_ = 0, Tv_ = 0, Te_ = 0;
  double Ta1s_ = 0, Ta2s_ = 0, Tvs_ = 0, Tes_ = 0, sd_max2_ = 0, s1_ = 0, s2_ = 0, s3_ = 0;
  double end_time_ = 0.0;
};

}  // namespace jointsim::control
