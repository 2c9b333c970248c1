#pragma once
/// \file
/// Joint test rig: one drive — motor (torque source or DC electrics), transmission, friction — turning a
/// load inertia or clamped at its output (the clamping bench of [KR300Thesis], the friction-map bench of
/// [Hauschild2003, §4.5.4]).
///
/// State vector (in this order, absent parts skipped):
///   [q_m, qd_m]            motor shaft angle [rad] and velocity [rad/s]
///   [i]                    motor current [A]            (voltage input, or PI with voltage output)
///   [x_transmission...]    transmission internal states (e.g. strain-wave gear)
///   [z_friction...]        friction internal states (LuGre, Dahl)
///   [q_l, qd_l]            output shaft angle and velocity (compliant transmission, free load)
///   [e_int]                integral of the velocity error [rad] (velocity PI input)
/// A rigid transmission merges the shafts (q_l = q_m / N); a clamped output holds q_l = qd_l = 0.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/profile.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::systems {

enum class RigInput { MotorTorque, Voltage, VelocityPI };
enum class Side { Motor, Output };

/// Velocity PI loop (the friction-map measurement of [Hauschild2003, §4.5.4]): u = kp e + ki ∫e,
/// e = ω_ref − ω_measured, clamped to ±limit with conditional integration (anti-windup).
struct VelocityPi {
  double kp = 1.0;              ///< proportional gain [N·m·s/rad] (torque output) or [V·s/rad] (voltage output)
  double ki = 10.0;             ///< integral gain [N·m/rad] or [V/rad]
  double limit = 1e9;           ///< output saturation [N·m] or [V], > 0
  bool voltage_output = false;  ///< false: u is the motor torque; true: u is the voltage command
  Side measure = Side::Motor;   ///< which shaft's velocity is controlled
};

struct JointRigSetup {
  std::string name = "joint_rig";
  std::optional<drive::DcMotorParams> motor;  ///< electrics (needed for voltage input / voltage PI)
  double rotor_inertia = 1e-3;                ///< J_m [kg·m²] when `motor` is absent (else motor->J_M)
  std::shared_ptr<const drive::Transmission> transmission;
  std::shared_ptr<const drive::Friction> friction;  ///< may be null
  Side friction_side = Side::Motor;
  bool clamped = false;       ///< output held at q_l = 0
  double load_inertia = 1.0;  ///< J_l [kg·m²], > 0 unless clamped
  double load_damping = 0.0;  ///< viscous load b_l [N·m·s/rad], >= 0
  /// External torque on the output shaft over time [N·m] (a load step, a disturbance; any profile, also from a
  /// CSV file), added to the `load_torque` input port; not with a clamped output. Logged as load_torque[N·m].
  std::optional<control::Profile> load_torque;
  RigInput input = RigInput::MotorTorque;
  control::Profile profile = control::Profile::constant(0.0);  ///< torque [N·m], voltage [V] or ω_ref [rad/s]
  VelocityPi pi;
  double q_m0 = 0.0, qd_m0 = 0.0;  ///< initial motor angle [rad] and velocity [rad/s]
  double q_l0 = 0.0, qd_l0 = 0.0;  ///< initial output angle/velocity (free compliant load)
  double duration = 1.0;           ///< [s]
  double log_rate = 1000.0;        ///< [Hz]
  /// Integrator settings. max_step = 0 means one log interval (1/log_rate): the solver never steps over
  /// more than one logged sample, so it cannot skip a slip phase between two "stuck" states.
  sim::CvodeOptions solver = defaultSolver();
  /// BDF capped at order 2 (A-stable; see docs/design.md), rtol 1e-8, atol 1e-10.
  static sim::CvodeOptions defaultSolver();
  /// Throws InputError for inconsistent settings (e.g. voltage input without motor, output friction on a
  /// clamped output).
  void validate() const;
};

/// The assembled rig: state layout, pure right-hand side and logged signals. Its only time events are the
/// breakpoints of the input and load-torque profiles (the integrator restarts there).
class JointRig : public sim::Plant {
 public:
  explicit JointRig(JointRigSetup setup);
  const JointRigSetup& setup() const { return s_; }
  /// Run settings of the setup: t_end = duration, outputs at log_rate, its solver with max_step = one log
  /// interval when 0. A stuck shaft (sticking friction) makes the state nearly constant, the step size grows
  /// without bound, and a step whose two ends are both "stuck" can jump over the whole slip phase in between
  /// unseen by the error test (measured on the [KR300Thesis] clamping rig: one 40 s BDF1 step skipped a
  /// break-away); one log interval at most prevents that.
  sim::SimulateOptions simulateOptions() const;

  /// The run's inputs (sim::Simulator::plantState()): the held command and the load torque.
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    bool held = false;         ///< the command holds the input in place of the profile
    double command = 0.0;      ///< the held command [N·m, V or rad/s: the rig's input type]
    double load_torque = 0.0;  ///< external torque on the output shaft [N·m]
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }

  /// Command port (sim::Simulator): holds the input of the rig's configured type — motor torque [N·m], voltage
  /// [V] or velocity reference [rad/s] of the PI loop — at `value` in place of the profile, until changed or
  /// released. InputError for a non-finite value (nothing changed). A change restarts the integrator.
  void setCommand(sim::PlantState& state, double value) const;
  /// Back to the input profile.
  void releaseCommand(sim::PlantState& state) const;
  /// External torque on the output shaft [N·m] (a load the user applies; ignored while clamped or for a rigid
  /// transmission, where it acts on the merged shaft as τ/N on the motor side).
  void setLoadTorque(sim::PlantState& state, double tau) const;

  /// Named inputs (sim::Plant::inputPorts): `command` (setCommand; its unit is the rig's input type's: N·m, V or
  /// rad/s; 0 until set) and, unless the output is clamped, `load_torque` [N·m] (setLoadTorque).
  std::vector<sim::InputPort> inputPorts() const override;
  void setInput(sim::PlantState& state, int port, double value) const override;
  double input(const sim::PlantState& state, int port) const override;
  /// `command` is in effect while held (until releaseCommand); `load_torque` always.
  bool inputActive(const sim::PlantState& state, int port) const override;
  /// `command`: releaseCommand; `load_torque`: back to 0.
  void releaseInput(sim::PlantState& state, int port) const override;

  std::string name() const override;
  int stateSize() const override { return n_; }
  Eigen::VectorXd initialState() const override;
  /// ẏ = f(t, y). Pure; no allocation.
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  std::vector<double> timeEvents(double t_end) const override;
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override;

 private:
  struct Eval;  // all algebraic signals at (t, y)
  Eval evaluate(const State& s, double t, const Eigen::Ref<const Eigen::VectorXd>& y, double* xdot_tr,
                double* zdot) const;
  JointRigSetup s_;
  double J_m_ = 0;
  int n_ = 0, i_idx_ = -1, x_idx_ = -1, z_idx_ = -1, l_idx_ = -1, e_idx_ = -1;
  int nx_ = 0, nz_ = 0;
  std::optional<drive::DcMotor> motor_;
  std::vector<std::string> signals_;
};

}  // namespace jointsim::systems
