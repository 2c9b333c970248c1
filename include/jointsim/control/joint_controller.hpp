#pragma once
/// \file
/// Per-joint drive controllers (continuous-time):
/// - `VoltageCascade` — [Raviola2023, §2.1, Table 1, App. A]: position P with motor-speed
///   feed-forward N q̇_set, motor-velocity PI giving the current reference, current PI giving the voltage
///   reference. Output: voltage [V] (saturated by the PWM stage). The current integrator stops while the
///   voltage is saturated and the error drives further into saturation (conditional-integration
///   anti-windup; [Raviola2023] states none — without it a saturated start winds up and overshoots).
/// - `TorqueCascade` — [Olsson2017, §2.8, §3.10, Table 3.7, A.12]: u = N q̇_ref + kp (φ_0 + N q_ref − φ_m) − ω_m,
///   τ_m = ks (u + x), ẋ = u/Ts, x(0) = −u(0). Output: motor torque [N·m] (no current loop). The same P/PI law is
///   the RobotR3 axis controller of [MSL, RobotR3.Utilities.Controller] (output the current reference [A], ks in
///   A·s/rad) and the clamping robot's (φ_0 its start motor angle): the one implementation for all of them.
/// - `None` — zero motor torque (uncontrolled).
/// Each controller is a pure function of its inputs and its internal state slice.

#include <string>

namespace jointsim::control {

enum class ControllerType { None, VoltageCascade, TorqueCascade };

/// Where a command enters a controller (the command ports of systems::RobotSystem):
/// - `Position`: the joint reference (q_set, q̇_set) through every loop;
/// - `MotorVelocity`: a motor speed reference [rad/s] replaces the position loop's output;
/// - `Current`: a current reference [A] replaces the velocity loop's output (VoltageCascade only).
/// Integrators of loops that a command bypasses are frozen (their derivative is zero).
enum class ControlEntry { Position, MotorVelocity, Current };

struct JointControllerParams {
  ControllerType type = ControllerType::None;
  // VoltageCascade ([Raviola2023, Table 1])
  double P_pos = 0.0;  ///< position P: joint error [rad] → motor speed [rad/s] [1/s], >= 0
  double P_vel = 0.0;  ///< velocity P [A·s/rad], >= 0
  double I_vel = 0.0;  ///< velocity I [A/rad], >= 0
  double P_cur = 0.0;  ///< current P [V/A], >= 0
  double I_cur = 0.0;  ///< current I [V/(A·s)], >= 0
  // TorqueCascade ([Olsson2017, A.12])
  double kp = 0.0;   ///< position gain [1/s], >= 0
  double ks = 0.0;   ///< speed PI gain [N·m·s/rad], >= 0
  double Ts = 0.01;  ///< PI integrator time constant [s], > 0
  /// Throws InputError naming the gain and the rule (gains must be >= 0, Ts > 0).
  void validate(const std::string& where) const;
};

/// Measured and desired signals at one instant.
struct ControllerInputs {
  double q_set = 0, qd_set = 0;                 ///< joint-side reference [rad], [rad/s]
  double q_fb = 0;                              ///< measured joint angle [rad]
  double qm_fb = 0, qdm_fb = 0;                 ///< measured motor angle [rad] and speed [rad/s]
  double i_fb = 0;                              ///< measured motor current [A]
  double ratio = 1;                             ///< gear ratio N used to scale references
  double v_limit = 0;                           ///< supply voltage [V] (VoltageCascade anti-windup)
  ControlEntry entry = ControlEntry::Position;  ///< where the command enters
  double command = 0;  ///< motor speed reference [rad/s] (MotorVelocity) or current reference [A] (Current)
  /// φ_0 [rad]: the motor angle reference is φ_0 + N q_set (TorqueCascade). Last, so that positional initialisers
  /// of the fields above stay valid.
  double qm_offset = 0;
};

struct ControllerOutputs {
  bool voltage = false;  ///< true: `u` is a voltage command [V]; false: a motor torque [N·m]
  double u = 0.0;
  double i_ref = 0.0;    ///< current reference [A] (VoltageCascade), else 0
  double qdm_ref = 0.0;  ///< motor speed reference [rad/s]
};

class JointController {
 public:
  explicit JointController(const JointControllerParams& p) : p_(p) {}
  /// The TorqueCascade (P position loop, PI speed loop) with gains kp [1/s], ks [output·s/rad] and Ts [s].
  static JointController torqueCascade(double kp, double ks, double Ts);
  const JointControllerParams& params() const { return p_; }
  int stateSize() const;
  /// Internal state at t0 for the given inputs ([Olsson2017]: zero initial output; [Raviola2023]: zero
  /// integrals).
  void initialState(const ControllerInputs& in, double* x) const;
  /// Outputs and state derivatives.
  ControllerOutputs evaluate(const ControllerInputs& in, const double* x, double* xdot) const;
  /// Whether commands may enter at `entry` (Current needs a current loop: VoltageCascade).
  bool accepts(ControlEntry entry) const;
  /// Bumpless transfer: sets the integrator states x so that evaluate(in, x) gives the output `u` [V or N·m]
  /// (and, for VoltageCascade with a velocity loop in use, the current reference `i_ref` [A]) at this instant.
  /// Integrators with a zero gain are left as they are.
  void matchOutput(const ControllerInputs& in, double u, double i_ref, double* x) const;

 private:
  JointControllerParams p_;
};

/// The velocity PI loop of a test rig (the friction-map measurement of [Hauschild2003, §4.5.4]):
///   u = clamp(kp e + ki x, −limit, limit),  ẋ = e, except 0 while the output is saturated and e drives it further
/// (conditional integration, anti-windup). e [rad/s] the velocity error, x [rad] its integral; kp [out·s/rad],
/// ki [out/rad], limit [out] > 0, the output a torque [N·m] or a voltage [V]. Returns u and sets `xdot`.
double velocityPi(double kp, double ki, double limit, double e, double x, double& xdot);

/// Spectral radius of the cascade's current loop when it is sampled every Ts [s] (zero-order hold, the integrator
/// by forward Euler as in sampled control) around the motor's R–L circuit (R [Ω], L [H]; back-EMF, a slow
/// mechanical coupling, neglected):
///   i_{k+1} = a i_k + b u_k,  a = e^{−R Ts/L},  b = (1 − a)/R,  u_k = P_cur (r − i_k) + I_cur x_k,
///   x_{k+1} = x_k + Ts (r − i_k),
/// the eigenvalues of [[a − b P_cur, b I_cur], [−Ts, 1]]. ≥ 1: the sampled loop is unstable (it rings at the
/// Nyquist frequency and saturates the supply). 0 for a controller without a current loop.
double sampledCurrentLoopRadius(const JointControllerParams& params, double R, double L, double Ts);

}  // namespace jointsim::control
