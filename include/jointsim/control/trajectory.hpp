#pragma once
/// \file
/// Joint-space reference trajectories for tracking experiments (e.g. the UR5 digital twin):
/// - `PointToPointTrajectory` — multi-segment joint moves like UR's movej: trapezoidal (triangular when
///   short) velocity profiles, time-synchronised across joints.
/// - `FourierTrajectory` — finite Fourier series excitation for dynamic identification (Swevers et al.),
///   with a quintic fade-in so the robot starts at rest.
/// - `SampledTrajectory` — set-points from a CSV file (e.g. logged at 125 Hz on the real robot),
///   interpolated by a natural C² cubic spline.
/// - `LoggedTrajectory` — a robot log's commanded q, q̇, q̈ replayed by Hermite interpolation.
/// All quantities are SI: positions [rad], velocities [rad/s], accelerations [rad/s²], times [s].
/// Trajectories are immutable after construction; evaluate() is pure, thread-safe and allocation-free.

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "jointsim/multibody/model.hpp"

namespace jointsim::control {

/// Desired joint positions, velocities, accelerations at time t (size n each).
struct JointSetpoint {
  Eigen::VectorXd q;    ///< joint positions [rad]
  Eigen::VectorXd qd;   ///< joint velocities [rad/s]
  Eigen::VectorXd qdd;  ///< joint accelerations [rad/s²]
};

/// A joint-space trajectory of dof() joints over [0, duration()].
/// Before t = 0 it rests at its first point (qd = qdd = 0; a Fourier series without fade-in continues
/// periodically); after duration() it holds its last point (qd = qdd = 0), except periodic trajectories
/// (FourierTrajectory), which continue their period.
class JointTrajectory {
 public:
  virtual ~JointTrajectory() = default;
  /// Number of joints n.
  virtual int dof() const = 0;
  /// Length of the trajectory [s].
  virtual double duration() const = 0;
  /// Writes q [rad], qd [rad/s], qdd [rad/s²] at time t [s]; each output must have size dof().
  /// At a breakpoint, qdd is the value of the phase that starts there (right-continuous).
  virtual void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                        Eigen::Ref<Eigen::VectorXd> qdd) const = 0;
  /// Times in (0, duration()] [s], increasing, at which qdd (or qd) jumps: integrators should restart there.
  virtual std::vector<double> breakpoints() const { return {}; }
  /// One-line description for summaries, e.g. "point_to_point(6 joints, 3 segments, duration 4.2 s)".
  virtual std::string describe() const = 0;
  /// Where the robot should start [rad] when it does not start on q(0): a replayed log's measured first
  /// positions. Writes q (size dof()) and returns true, or returns false (the default: start on q(0)).
  virtual bool startPositions(Eigen::Ref<Eigen::VectorXd> q) const {
    (void)q;
    return false;
  }

  /// Per joint (dof() lists), the closed intervals [t_begin, t_end] of trajectory time [s] over which the joint
  /// rests (q̇ = q̈ = 0, q constant), increasing and disjoint; t_begin may be -inf (resting since before t = 0) and
  /// t_end +inf. Empty (the default): not known. A replay relative to the robot (systems::RobotSystem::
  /// setRelativeReplay) re-anchors each move at its start and lets the position loops follow the robot at rest.
  virtual std::vector<std::vector<std::pair<double, double>>> rests() const { return {}; }

  /// Convenience (allocates): the set-point at time t [s].
  JointSetpoint setpoint(double t) const;
};

/// Checks the trajectory against the joint limits on [0, duration()]: sampled every 1 ms (coarser only
/// beyond 10^7 samples), plus t = 0, duration() and every breakpoint (where the extrema of point-to-point
/// moves lie). Positions must stay in [lower, upper] and, where the velocity limit is finite, |qd| <=
/// velocity (tolerance 1e-9 rad, rad/s). Throws InputError on the first violation in time:
/// "trajectory leaves the limits of joint <name> at t = <time> s: q = <value> rad outside [lower, upper]"
/// or "trajectory exceeds the velocity limit of joint <name> at t = <time> s: |qd| = <v> rad/s > <limit> rad/s".
/// Also throws InputError when `joint_names` or `limits` do not have dof() entries.
void checkLimits(const JointTrajectory& trajectory, const std::vector<std::string>& joint_names,
                 const std::vector<multibody::JointLimits>& limits);

// ---------------------------------------------------------------------------------------------------

/// One move of a PointToPointTrajectory: from the previous target (or the start) to `target`.
/// Either `velocity` and `acceleration` (movej's v and a: the duration follows), or `duration` (and
/// optionally `acceleration`).
struct PtpSegment {
  Eigen::VectorXd target;     ///< joint positions at the end of the move [rad] (size n)
  double velocity = 0.0;      ///< max joint speed [rad/s], > 0; must be 0 (unset) when `duration` is given
  double acceleration = 0.0;  ///< max joint acceleration [rad/s²], > 0 (optional with `duration`: 0 = unset)
  double dwell = 0.0;         ///< rest at the target after the move [s], >= 0
  /// If > 0, the move takes exactly this long [s]. With `acceleration` the profile is the trapezoid
  /// with that acceleration (shortest accel phase, lowest peak speed; needs acceleration >= 4 D / T² for
  /// the largest joint distance D); without it the profile is triangular (lowest peak acceleration 4 D / T²).
  double duration = 0.0;
};

/// Multi-segment joint moves (UR movej-like). Each segment moves all joints from the previous target to
/// the next with a trapezoidal velocity profile (triangular when the move is too short to reach the
/// velocity), time-synchronised: the joint with the largest distance D sets the timing (accel phase
/// t_a, cruise t_c, decel t_a) and every other joint follows the same normalised profile scaled by its
/// own distance, so all joints start, switch phases and stop together (lower peak speed/acceleration).
///   trapezoid (D >= v²/a): t_a = v/a, t_c = D/v − v/a; triangle: t_a = √(D/a), t_c = 0.
/// q, qd, qdd are analytic; each segment ends exactly (bit for bit) at its target with qd = qdd = 0.
/// Breakpoints: every phase switch of a move (start, end of acceleration, end of cruise, end).
class PointToPointTrajectory final : public JointTrajectory {
 public:
  /// `start`: joint positions at t = 0 [rad] (size n >= 1). Throws InputError (naming the segment,
  /// 0-based) on a wrong size, a non-finite value or a parameter outside its range.
  PointToPointTrajectory(Eigen::VectorXd start, std::vector<PtpSegment> segments);

  int dof() const override { return static_cast<int>(start_.size()); }
  double duration() const override { return duration_; }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                Eigen::Ref<Eigen::VectorXd> qdd) const override;
  std::vector<double> breakpoints() const override;
  std::string describe() const override;

  int segmentCount() const { return static_cast<int>(segs_.size()); }
  /// Time at which segment k starts moving [s].
  double segmentStart(int k) const { return segs_.at(static_cast<size_t>(k)).t0; }
  /// Time at which segment k reaches its target (its dwell starts) [s].
  double segmentEnd(int k) const;
  /// Acceleration-phase and cruise-phase durations of segment k [s] (decel phase = accel phase).
  double accelTime(int k) const { return segs_.at(static_cast<size_t>(k)).ta; }
  double cruiseTime(int k) const { return segs_.at(static_cast<size_t>(k)).tc; }
  const Eigen::VectorXd& start() const { return start_; }
  const std::vector<PtpSegment>& segments() const { return spec_; }

 private:
  struct Seg {
    double t0 = 0, ta = 0, tc = 0, T = 0;  // start [s], accel, cruise, total move time [s]
    double V = 0, A = 0;                   // normalised peak speed [1/s] and acceleration [1/s²]
    Eigen::VectorXd from, to, delta;       // [rad]
  };
  Eigen::VectorXd start_;
  std::vector<PtpSegment> spec_;
  std::vector<Seg> segs_;
  std::vector<double> starts_;  // segs_[k].t0, for the binary search
  double duration_ = 0.0;
};

// ---------------------------------------------------------------------------------------------------

/// Parameters of a FourierTrajectory (n joints, N harmonics).
struct FourierParams {
  double base_frequency = 0.0;  ///< f_base [Hz], > 0 (period 1/f_base; ω_f = 2π f_base)
  Eigen::VectorXd offset;       ///< q0 [rad] (n): the start position and the mean of the series
  Eigen::MatrixXd a;            ///< sine coefficients a_ik [rad/s] (n × N)
  Eigen::MatrixXd b;            ///< cosine coefficients b_ik [rad/s] (n × N)
  double fade_in = 1.0;         ///< T_fade [s], >= 0 (0: the pure series from t = 0)
  double duration = 0.0;        ///< [s], >= fade_in; 0 = fade_in + one period
};

/// Finite Fourier series excitation (Swevers et al. 1997):
///   q_F,i(τ) = Σ_{k=1..N} [a_ik/(ω_f k) sin(ω_f k τ) − b_ik/(ω_f k) cos(ω_f k τ)],
///   q_i(t)   = q0_i + w(t) · q_F,i(t − T_fade),
/// with the quintic fade-in w(t) = 10s³ − 15s⁴ + 6s⁵, s = clamp(t/T_fade, 0, 1). Hence q(0) = q0 and
/// qd(0) = qdd(0) = 0 (the robot starts at rest at the offset), and from T_fade on the trajectory is the
/// pure series q0 + q_F(t − T_fade), starting a period at t = T_fade (whole periods after the fade).
/// qd, qdd are analytic (product rule); qdd is continuous everywhere, so there are no breakpoints.
/// Periodic: after duration() it continues the series (no hold).
class FourierTrajectory final : public JointTrajectory {
 public:
  /// Throws InputError on inconsistent sizes or parameters outside their range.
  explicit FourierTrajectory(FourierParams params);

  int dof() const override { return static_cast<int>(p_.offset.size()); }
  double duration() const override { return p_.duration; }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                Eigen::Ref<Eigen::VectorXd> qdd) const override;
  std::string describe() const override;

  /// The pure series q0 + q_F(τ) and its derivatives at series time τ [s] (no fade-in).
  void evaluateSeries(double tau, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                      Eigen::Ref<Eigen::VectorXd> qdd) const;
  int harmonics() const { return static_cast<int>(p_.a.cols()); }
  double period() const { return 1.0 / p_.base_frequency; }
  /// The parameters, with `duration` resolved.
  const FourierParams& params() const { return p_; }

 private:
  FourierParams p_;
};

// ---------------------------------------------------------------------------------------------------

/// Set-points interpolated by a natural cubic spline (C²; second derivative zero at both ends, which
/// matches the hold outside the samples, so qdd is continuous there too; not-a-knot would be slightly
/// more accurate within the first and last intervals but extrapolates curvature into the hold). qd and qdd
/// are the spline's derivatives. Time is measured from the first sample: trajectory time t corresponds to
/// source time startTime() + t. Before the first sample it rests there; after the last it holds the last
/// (qd jumps to 0 if the data does not end at rest: duration() is a breakpoint).
class SampledTrajectory final : public JointTrajectory {
 public:
  /// `times` [s] strictly increasing, at least 2; `positions` (n × times.size()) [rad], column k at
  /// times[k]. `source` names the data in describe(). Throws InputError on bad sizes or times.
  SampledTrajectory(std::vector<double> times, Eigen::MatrixXd positions, std::string source = "samples");

  /// Reads a CSV file: a header line, then one row per sample; the first column is time [s]. Without
  /// `columns` the file must have exactly 1 + dof columns (time, then one per joint in order); otherwise
  /// `columns` (dof names from the header) selects the joint columns in joint order and other columns
  /// are ignored. Every cell of every row must be a finite number. Blank lines are skipped.
  /// Throws InputError "<path>: row <r>: ..." (r = line number in the file, header = row 1, as in a
  /// spreadsheet) on: a non-numeric cell, a wrong column count, a time not after the previous one, and a
  /// gap, i.e. a time step larger than gap_factor × the median step ("row 57: time step 0.05 s is more
  /// than 3x the median 0.008 s (a gap)"); gap_factor = 0 disables the gap check, otherwise it must be > 1.
  static SampledTrajectory fromCsv(const std::string& path, int dof, const std::vector<std::string>& columns = {},
                                   double gap_factor = 3.0);

  int dof() const override { return static_cast<int>(y_.rows()); }
  double duration() const override { return t_.back(); }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                Eigen::Ref<Eigen::VectorXd> qdd) const override;
  std::vector<double> breakpoints() const override { return {t_.back()}; }
  std::string describe() const override;

  /// Knot times relative to the first sample [s].
  const std::vector<double>& times() const { return t_; }
  /// Sampled positions (n × samples) [rad].
  const Eigen::MatrixXd& positions() const { return y_; }
  /// Source time of the first sample [s].
  double startTime() const { return t_start_; }

 private:
  std::vector<double> t_;
  Eigen::MatrixXd y_;  // n × K positions [rad]
  Eigen::MatrixXd m_;  // n × K spline second derivatives [rad/s²]
  double t_start_ = 0.0;
  std::string source_;
};

// ---------------------------------------------------------------------------------------------------

/// Column names of a robot log (LoggedTrajectory::fromCsv), one list per quantity in joint order.
struct LogColumns {
  std::string time;                     ///< time column [s]; empty: the first column
  std::vector<std::string> q;           ///< commanded positions [rad] (n names, required)
  std::vector<std::string> qd;          ///< commanded velocities [rad/s] (n names, required)
  std::vector<std::string> qdd;         ///< commanded accelerations [rad/s²] (n names or none)
  std::vector<std::string> q_measured;  ///< measured positions [rad] (n names or none): the start state
  /// The UR RTDE names: `timestamp`, `target_q_0`…, `target_qd_0`…, `target_qdd_0`…, `actual_q_0`….
  static LogColumns urRtde(int dof);
  /// Expands a pattern with `{j}` (joint number 1..n) or `{i}` (index 0..n−1) into n names; a name without
  /// either is an error (InputError naming `what`).
  static std::vector<std::string> expand(const std::string& pattern, int dof, const std::string& what);
};

/// A trajectory replayed from a robot log that carries the controller's own derivatives (e.g. UR RTDE's
/// target_q, target_qd, target_qdd at 125–500 Hz): on each interval [t_k, t_k+1] every joint follows the
/// quintic Hermite polynomial through q, q̇, q̈ at both ends (C², so no breakpoints inside), or the cubic
/// Hermite through q, q̇ when the log has no accelerations (C¹: q̈ jumps at every sample, each one a
/// breakpoint). The logged derivatives are used as they are: quantised positions are never differentiated
/// (a spline through 1e-6 rad steps turns them into acceleration noise). With
///   Δ = q₁ − q₀ − h q̇₀ − h² q̈₀/2,  V = h (q̇₁ − q̇₀) − h² q̈₀,  A = h² (q̈₁ − q̈₀),  s = (t − t_k)/h:
///   q(s) = q₀ + h q̇₀ s + h² q̈₀ s²/2 + (10Δ − 4V + A/2) s³ + (−15Δ + 7V − A) s⁴ + (6Δ − 3V + A/2) s⁵.
/// Trajectory time t is log time startTime() + t. Before t = 0 it rests at q(0); after the last sample it holds
/// the last position (q̇, q̈ jump to 0: duration() is a breakpoint).
///
/// Positions (`from_derivatives`, the default when the log has accelerations): the replay does not interpolate the
/// logged positions but integrates the logged derivatives, q_k+1 = q_k + h (q̇_k + q̇_k+1)/2 + h² (q̈_k − q̈_k+1)/12
/// (the exact integral of the cubic Hermite velocity; the quintic of an interval is then that quartic), because
/// the logged positions carry two things a twin must not chase:
/// - their quantisation (1e-6 rad in text logs): interpolated, it becomes q̈ noise of about 6·δ/h²;
/// - at rest a robot controller sets its target to the measured position (the shipped UR5 log: one sample later,
///   jitter 1e-5 … 4e-4 rad). Chased, that jitter makes the twin hunt in its friction at rest (about 50,000 solver
///   steps per second of log).
/// A sample rests when |q̇| <= rest_speed and |q̈| <= rest_speed / (mean sample period) (kRestSpeed = 1e-4 rad/s by
/// default; 0: only exact zeros); its q̇, q̈ are then taken as 0 (rests(): the intervals).
/// So per joint: over a rest the replay holds the logged position the next move starts from; a move starts there,
/// follows the integral of the logged derivatives, and the mismatch E with the next rest's position is blended in
/// over the move by the quintic smoothstep E w(u) (w' = w'' = 0 at both ends; its q̇ and q̈ are added to the
/// samples): a drift of E/T_move, about 1e-4 rad/s for the shipped log, instead of a jump. Where the logged
/// velocity itself jumps (|Δq̇ − h (q̈_k + q̈_k+1)/2| > h max |q̈| + 1e-4 rad/s: more than an acceleration switch
/// inside the interval can make), the integral restarts on the logged position.
class LoggedTrajectory final : public JointTrajectory {
 public:
  /// `times` [s] strictly increasing, at least 2; q, qd (and qdd unless empty) n × times.size() [rad, rad/s,
  /// rad/s²]; `start` [s] the log time that becomes t = 0, within [times.front(), times.back()).
  /// `rest_speed` [rad/s] >= 0: a sample rests when |q̇| <= rest_speed and |q̈| <= rest_speed / (mean sample period)
  /// (its derivatives are then taken as 0; see the class comment).
  LoggedTrajectory(std::vector<double> times, Eigen::MatrixXd q, Eigen::MatrixXd qd, Eigen::MatrixXd qdd, double start,
                   std::string source = "log", bool from_derivatives = true, double rest_speed = kRestSpeed);

  /// The default rest speed [rad/s]: above the 1e-6 rad/s print resolution of text logs and the slow tails of a UR
  /// controller's decelerations (a few 1e-5 rad/s held for seconds, moving the target by about 1e-4 rad), which,
  /// replayed as moves, keep a twin's stuck joints hunting in their friction; far below any programmed speed.
  static constexpr double kRestSpeed = 1e-4;

  /// Reads a log CSV (io::readCsv: any other columns are ignored). `start` < 0: the first sample's time.
  /// InputError "<path>:<line>:<column>: ..." on a missing column (listing the columns), a non-numeric or
  /// non-finite cell, a time not after the previous row's, or a gap (a time step > gap_factor × the median;
  /// gap_factor 0 disables the check), a start time outside the log.
  static LoggedTrajectory fromCsv(const std::string& path, int dof, const LogColumns& columns, double start = -1.0,
                                  double gap_factor = 3.0, bool from_derivatives = true,
                                  double rest_speed = kRestSpeed);

  int dof() const override { return static_cast<int>(q_.rows()); }
  double duration() const override { return t_.back() - start_; }
  void evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                Eigen::Ref<Eigen::VectorXd> qdd) const override;
  std::vector<double> breakpoints() const override;
  std::string describe() const override;
  bool startPositions(Eigen::Ref<Eigen::VectorXd> q) const override;
  /// The held rests (positions integrated from the derivatives; none with `positions: logged` or without q̈).
  std::vector<std::vector<std::pair<double, double>>> rests() const override;

  /// Log time of t = 0 [s].
  double startTime() const { return start_; }
  /// The measured positions at the start (interpolated linearly between the samples around it), when the log
  /// had measured-position columns (set by fromCsv).
  void setMeasuredStart(Eigen::VectorXd q) { measured_start_ = std::move(q); }
  /// The positions the replay uses at the samples (n × samples) [rad] (see the class comment).
  const Eigen::MatrixXd& positions() const { return q_; }

 private:
  void positionsFromDerivatives(Eigen::Index j);
  std::vector<double> t_;  // log times [s]
  Eigen::MatrixXd q_, qd_, qdd_;
  double start_ = 0.0;
  std::string source_;
  Eigen::VectorXd measured_start_;
  double rest_speed_ = kRestSpeed;
  std::vector<std::vector<std::pair<double, double>>> rests_;  // per joint, log-time sample ranges of the rests
};

}  // namespace jointsim::control
