#pragma once
/// \file
/// Joint position limits of a robot as a choice per experiment (`joint_limits:`):
///   ignore  the limits are informative only;
///   warn    the run reports every joint that left its range: when it first did, how far and when farthest
///           (checked at the output rows, so an excursion shorter than one log interval can be missed);
///   stop    a mechanical end stop at each finite limit, a linear spring–damper acting on the joint only while
///           it is beyond the limit (penetration δ > 0):
///             τ_stop = −max(0, k δ + d δ̇)   at the upper limit, δ = q − q_upper,
///             τ_stop = +max(0, k δ + d δ̇)   at the lower limit, δ = q_lower − q,
///           i.e. the Kelvin–Voigt contact with the pulling part cut off (a stop pushes, it never holds the joint
///           back as it leaves). With d ≥ 0 the stop never adds energy: the stored energy ½ k δ² plus the robot's
///           mechanical energy E satisfies dE/dt = −d δ̇² while the stop pushes and dE/dt = k δ δ̇ < 0 while the
///           cut-off holds (then δ̇ < −k δ / d < 0). The force jumps only where a moving joint reaches its limit
///           (δ = 0, δ̇ ≠ 0: the damper engages); those instants are CVODE root functions (q − q_upper and
///           q_lower − q for every limited joint), so the integrator restarts exactly there.
/// Default stiffness 1e5 N·m/rad (N/m for a prismatic joint) and damping 100 N·m·s/rad (N·s/m): a stiff but
/// not rigid stop — under a 150 N·m gravity load (a UR5 shoulder) it deflects 1.5 mrad; with a 5 kg·m² arm
/// inertia it rings at √(k/I)/2π ≈ 23 Hz with damping ratio d / (2√(k I)) ≈ 0.07, with a 0.01 kg·m² wrist at
/// ≈ 500 Hz and ≈ 1.6 (overdamped). A lightly damped stiff contact is a fast mode: use BDF (stiff) when it
/// is hit often. A joint whose lower and upper limits are both infinite has no stop.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/multibody/model.hpp"

namespace jointsim::systems {

enum class JointLimitMode { Ignore, Warn, Stop };

/// "ignore", "warn" or "stop".
const char* jointLimitModeName(JointLimitMode mode);

struct JointLimitSettings {
  JointLimitMode mode = JointLimitMode::Warn;
  double stiffness = 1.0e5;  ///< end-stop stiffness k [N·m/rad] (prismatic joints: [N/m]), > 0
  double damping = 100.0;    ///< end-stop damping d [N·m·s/rad] (prismatic: [N·s/m]), >= 0
  /// Throws InputError (component "joint_limits") for k <= 0, d < 0 or a non-finite value.
  void validate() const;
};

/// The end stops of a model (mode stop), evaluated without heap allocation.
class EndStops {
 public:
  EndStops() = default;
  /// Stops at every finite limit of `model` when settings.mode is Stop; none otherwise.
  EndStops(const multibody::Model& model, const JointLimitSettings& settings);

  bool active() const { return !joints_.empty(); }
  /// Indices of the joints with at least one stop.
  const std::vector<int>& joints() const { return joints_; }
  /// Root functions: two per stopped joint, q − q_upper and q_lower − q (an infinite limit gives −1).
  int rootCount() const { return 2 * static_cast<int>(joints_.size()); }
  void roots(const Eigen::Ref<const Eigen::VectorXd>& q, double* g) const;
  /// τ_stop of every joint (size nq; zero for joints without a stop or inside their range) [N·m or N].
  void torques(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               Eigen::Ref<Eigen::VectorXd> tau) const;
  /// Energy stored in the stops, Σ ½ k δ² over penetrated limits [J].
  double energy(const Eigen::Ref<const Eigen::VectorXd>& q) const;

 private:
  std::vector<int> joints_;
  std::vector<double> lower_, upper_;  // per stopped joint
  double k_ = 0.0, d_ = 0.0;
};

/// One joint that left its range during a run.
struct JointLimitViolation {
  std::string joint;
  double lower = 0.0, upper = 0.0;  ///< the range [rad or m]
  double first_time = 0.0;          ///< first output time outside the range [s]
  double max_excursion = 0.0;       ///< largest distance beyond a limit [rad or m], > 0
  double max_time = 0.0;            ///< output time of the largest excursion [s]
  double max_position = 0.0;        ///< the joint position then [rad or m]
};

/// Watches the joint positions of the output rows (modes warn and stop) and lists the joints that left their
/// range. A position exactly at a limit is inside.
class JointLimitMonitor {
 public:
  JointLimitMonitor() = default;
  /// `columns[i]`: index in an output row (time first) of the position of joint i of `model`, or −1.
  JointLimitMonitor(const multibody::Model& model, std::vector<int> columns, JointLimitSettings settings);
  const JointLimitSettings& settings() const { return settings_; }
  bool enabled() const { return settings_.mode != JointLimitMode::Ignore && !columns_.empty(); }
  void observe(const Eigen::VectorXd& row);
  /// Forgets the violations seen (a new run).
  void reset();
  /// Violations in joint order.
  std::vector<JointLimitViolation> violations() const;
  /// One line per violation: "joint elbow_joint left its range [-3.1416, 3.1416] rad at t = 0.73 s, by up to
  /// 5.36 rad (q = 8.50 rad at t = 1.90 s)".
  std::vector<std::string> describe() const;

 private:
  JointLimitSettings settings_;
  std::vector<int> columns_;
  std::vector<std::string> names_, units_;
  std::vector<multibody::JointLimits> limits_;
  std::vector<JointLimitViolation> state_;
  std::vector<char> seen_;
};

}  // namespace jointsim::systems
