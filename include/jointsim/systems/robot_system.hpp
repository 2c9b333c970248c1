#pragma once
/// \file
/// A robot with drives: the multibody core plus one drive chain per joint, assembled into one state vector
/// for CVODE (a sim::Plant). Per drive: controller → voltage (saturated PWM) → motor electrics → motor inertia
/// → transmission → gear output shaft, with friction on the gear output shaft; an optional coupling matrix G
/// maps gear output angles to joint angles (q = G φ_out, τ_joint = G⁻ᵀ τ_out).
///
/// State vector: [q (n), q̇ (n)], then per drive k (absent parts skipped):
///   [q_m, q̇_m] (compliant transmission), [i] (motor electrics), [x_gear...], [z_friction...], and finally
///   [x_ctrl...] of every drive (continuous control only).
/// A rigid transmission merges the motor into the joint: q_m = N φ_out and its rotor inertia N² J_M is
/// added to the joint-space inertia (the gear output torque is then N τ_M − N² J_M φ̈_out).
/// Sensors are ideal (the controllers see the true states) unless sampled control adds quantisation and
/// noise (setSampledControl) or a fault adds a joint-angle bias (SensorSpec::joint_bias, both modes).

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "jointsim/control/joint_controller.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/joint_limits.hpp"

namespace jointsim::systems {

/// The fastest pole of a continuous current loop a drive may have [rad/s] (RobotSystem refuses gains beyond it).
constexpr double kMaxCurrentLoopPole = 1e8;

/// Sensor imperfections. Quantisation and noise are used only with sampled (discrete-time) control; the
/// joint-angle bias (a fault, systems/faults.hpp) applies in both modes.
struct SensorSpec {
  double joint_bias = 0.0;            ///< constant offset of the measured joint angle [rad]
  double joint_quantum = 0.0;         ///< joint encoder resolution [rad] (0: none)
  double motor_quantum = 0.0;         ///< motor encoder resolution [rad]; > 0: speed = Δ(quantised angle)/T_s
  double current_quantum = 0.0;       ///< current sensor resolution [A]
  double joint_noise = 0.0;           ///< std of additive Gaussian noise on the joint angle [rad]
  double motor_velocity_noise = 0.0;  ///< std on the motor speed [rad/s]
  double current_noise = 0.0;         ///< std on the current [A]
};

struct DriveSpec {
  std::string joint;           ///< name of the joint this drive moves
  drive::DcMotorParams motor;  ///< motor (J_M always used; electrics if `electrics`)
  bool electrics = true;       ///< false: torque-controlled motor, no current state
  std::shared_ptr<const drive::Transmission> transmission;
  std::shared_ptr<const drive::Friction> friction;  ///< on the gear output shaft; may be null
  control::JointControllerParams controller;
  SensorSpec sensors;  ///< used with sampled control only
};

/// Where the command of a drive enters (RobotSystem::setCommandPort), changeable between steps of a
/// sim::Simulator:
/// - `Setpoint`: the joint reference (q, q̇, q̈) through the drive's controller (the default; the trajectory of
///   setTrajectory/setSetpoints, or values held from setSetpoint);
/// - `MotorVelocity`: a motor speed reference [rad/s] into the velocity loop (the position loop bypassed);
/// - `Current`: a current reference [A] into the current loop (a drive with electrics and voltage_cascade);
/// - `Voltage`: the motor voltage command [V] (a drive with electrics; the PWM saturation at ±V_supply applies);
/// - `MotorTorque`: the electromagnetic motor torque [N·m] (electrics bypassed: the current state then relaxes
///   to τ/k_t with the electrical time constant L/R, so that it is consistent when the port switches back).
/// Loops that a port bypasses hold their integrators; switching back re-initialises them so that the
/// controller's output continues from the value applied just before (bumpless transfer).
enum class CommandPort { Setpoint, MotorVelocity, Current, Voltage, MotorTorque };
/// "setpoint", "motor_velocity", "current", "voltage", "motor_torque".
const char* portName(CommandPort port);
/// Inverse of portName(); InputError listing the ports for another text.
CommandPort parsePort(const std::string& text);

/// Joint-space reference at time t (writes q_set, q̇_set, q̈_set of size n). Part of the constant robot: a pure
/// function of t (no state of its own, safe to call from several threads at once), or snapshots and threads break.
using SetpointFunction = std::function<void(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                            Eigen::Ref<Eigen::VectorXd> qdd)>;

/// External wrenches on the bodies at (t, kinematics in `data`): fills `fext` (6 × n, body frames, as in
/// multibody::rnea). Used for clamps and contacts. Pure and thread-safe like SetpointFunction.
using WrenchFunction = std::function<void(double t, const multibody::Model& model, const multibody::Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& q,
                                          const Eigen::Ref<const Eigen::VectorXd>& qd, multibody::Matrix6Xd& fext)>;

/// Signals of one evaluation, per joint (size n each).
struct RobotSignals {
  Eigen::VectorXd q_set, qd_set, qdd_set;
  Eigen::VectorXd q_fb;            ///< measured joint angle [rad]
  Eigen::VectorXd qm, qdm;         ///< motor angle [rad] and speed [rad/s]
  Eigen::VectorXd current, i_ref;  ///< motor current and its reference [A]
  Eigen::VectorXd u;               ///< controller output: voltage command [V] or motor torque command [N·m]
  Eigen::VectorXd voltage;         ///< supply voltage [V]
  Eigen::VectorXd tau_motor;       ///< electromagnetic motor torque [N·m]
  Eigen::VectorXd tau_gear;        ///< gear output torque [N·m] (before friction, output shaft)
  Eigen::VectorXd tau_friction;    ///< friction torque on the output shaft [N·m]
  Eigen::VectorXd tau_joint;       ///< torque applied to the joints by the drives [N·m]
  Eigen::VectorXd tau_stop;        ///< torque of the end stops on the joints [N·m] (zero without stops)
  Eigen::VectorXd qdd;             ///< joint accelerations [rad/s²]
  void resize(int n);
};

class RobotSystem : public sim::Plant {
 public:
  /// Configuration (setTrajectory, setFaults, setSampledControl, ...) happens before the robot is simulated: once a
  /// simulator uses it (Plant::freeze) the setters refuse with an InputError, since the simulators share it.
  /// `drives` must name every movable joint of `model` exactly once. `coupling` (n × n, optional, empty =
  /// identity) maps gear output angles to joint angles. Throws InputError on inconsistencies.
  RobotSystem(multibody::Model model, std::vector<DriveSpec> drives, Eigen::MatrixXd coupling = {});

  const multibody::Model& model() const { return model_; }
  /// The drives as configured (nominal: the faults that act during the run are applied to the state's copies).
  const std::vector<DriveSpec>& drives() const { return drives_; }
  /// The drives as they are in `state`: with the parameter faults at their values at the state's last event.
  const std::vector<DriveSpec>& drives(const sim::PlantState& state) const { return own<State>(state).drives; }
  int dof() const { return model_.nq; }

  /// Reference of every joint from a function (no time events: a reference whose q̈ jumps should come
  /// through setTrajectory, so the integrator restarts at its breakpoints).
  void setSetpoints(SetpointFunction f);
  /// Reference from a trajectory (its breakpoints become time events under continuous control).
  void setTrajectory(std::shared_ptr<const control::JointTrajectory> trajectory);
  /// Replay relative to the robot, for a reference recorded on another robot (a measured log): each joint's
  /// reference is followed relative to where the joint is, q_set(t) = q_ref(t) + a_k with the anchor
  /// a_k = q_meas(t_a) − q_ref(t_a) taken at the start of the run and at the start t_a of every rest of the joint's
  /// reference (the trajectory's rests(), control::JointTrajectory; time events). So at a rest the joint is held
  /// where it stopped, not pulled to where the recorded robot stopped (a stuck joint's position loop would otherwise
  /// wind its velocity integrator up against the friction for as long as the rest lasts), and the next move starts
  /// from there, as on a robot controller that sets its target to the measured position at rest. Without it (the
  /// default) the reference is followed as it is; a trajectory without rests is replayed relative to the start pose.
  /// q_meas is the measured joint angle of the state (sensor bias and faults included, without noise).
  /// Held references (setSetpoint) are followed as they are.
  void setRelativeReplay(bool on);
  bool relativeReplay() const { return relative_; }
  void setExternalWrenches(WrenchFunction f);
  /// Joint limits: with mode stop, an end stop at every finite joint limit (systems/joint_limits.hpp) acts on
  /// the joint, its instants of contact become root functions and end_stop_torque_<joint> [N·m] signals are
  /// appended; other modes leave the system unchanged (the monitor of warn lives in the experiment).
  void setJointLimits(const JointLimitSettings& settings);
  const EndStops& endStops() const { return stops_; }
  // ----------------------------------------------------------------------------------- the run's state
  /// Everything of one run that changes (sim::Simulator::plantState()): the inputs set between steps, sampled
  /// control's controller states, held outputs and sensor memory, the sensor-noise generator, the faults' applied
  /// values with the drives they make, and the workspace of the right-hand side. The robot itself is constant.
  struct State : sim::PlantStateOf<State> {
    explicit State(const RobotSystem& robot);
    // Command ports (inputs between steps).
    std::vector<CommandPort> port, applied_port;  ///< per joint: the port; the port last applied (applyInputs)
    Eigen::VectorXd cmd, applied_cmd;  ///< per joint: the port's command [rad/s, A, V or N·m]; the one last applied
    std::vector<char> ref_held;        ///< per joint: the reference is held (setSetpoint)
    Eigen::VectorXd ref_q, ref_qd, ref_qdd;  ///< held references [rad, rad/s, rad/s²]
    /// Joint angles at the start [rad] (start()): the reference of a robot without a trajectory or setpoint function.
    Eigen::VectorXd q_start;
    std::vector<std::pair<int, Eigen::Matrix<double, 6, 1>>> user_wrenches;  ///< frame index, world wrench [N; N·m]
    // Sampled control: discrete controller states, held outputs [V or N·m; A], held measured joint angle [rad],
    // the last quantised motor angle [rad] of the encoder-difference speed, the sample counters.
    std::vector<double> ctrl_x;
    Eigen::VectorXd held_u, held_i_ref, held_q_fb, prev_qm_meas;
    bool first_sample = true;
    long inner_count = 0;    ///< current-loop samples since the start (multi-rate)
    std::mt19937_64 engine;  ///< sensor noise
    std::normal_distribution<double> normal{0.0, 1.0};
    // Faults during the run: per fault the parameter value applied now (parameter faults, bearing ripple), and for
    // a stuck sensor the episode and the value it holds; the drives with the parameter faults applied now.
    std::vector<double> fault_applied;
    std::vector<long> stuck_episode;
    std::vector<double> stuck_value;
    /// Relative replay: per joint, the measured minus the reference joint angle at the run's start or the start of
    /// the joint's last rest [rad].
    Eigen::VectorXd anchor;
    /// Load torques at the joints (the `<joint>.load_torque` inputs; 0 until set) [N·m, N for a prismatic joint].
    sim::HeldInputs loads;
    std::vector<DriveSpec> drives;
    std::vector<drive::DcMotor> motors;
    // Workspace of the right-hand side (holds nothing between calls; not saved).
    mutable multibody::Data data, id_data;
    mutable RobotSignals sig;
    mutable std::vector<char> out_is_voltage;
    mutable Eigen::VectorXd phi, phid, tau_out, tau, tmp, zero;
    mutable multibody::Matrix6Xd fext;
    mutable Eigen::MatrixXd M;
    mutable Eigen::LLT<Eigen::MatrixXd> llt;
    mutable Eigen::VectorXd jac_y, jac_f, jac_tau0, jac_qdd0, jac_tau;
    mutable Eigen::MatrixXd jac_P;
    mutable sim::JacobianStructure jac_structure;
    mutable std::vector<int> jac_block_drive;
    mutable std::vector<size_t> jac_block_columns;  // per block: how many of its states get a column evaluation
    /// Per drive, the last friction evaluation of a model that reads only v and its one state z (bit patterns
    /// compared): the Jacobian's drive columns evaluate the drives a dozen times at the same joint speed, where
    /// LuGre's Stribeck curve (a pow and an exp) would be recomputed each time. Holding the model keeps its address
    /// from being reused by another while the entry exists.
    struct FrictionMemo {
      std::shared_ptr<const drive::Friction> model;
      double v = 0.0, z = 0.0, tau = 0.0, zdot = 0.0;
    };
    mutable std::vector<FrictionMemo> friction_memo;
    mutable multibody::Data jac_data;  ///< the analytic ABA derivatives of the Jacobian (robot_dynamics.cpp)
    mutable Eigen::VectorXd jac_tau_base;
    double gauss(double sigma) { return sigma > 0.0 ? sigma * normal(engine) : 0.0; }
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }

  // ----------------------------------------------------------------------------------- command ports
  // Inputs a user's controller sets between steps of a sim::Simulator, in the simulator's state
  // (sim::Simulator::plantState()). Each call that changes a value counts as an input change, so the simulator
  // restarts the integrator there (and only there). Bad input (unknown joint or frame, a port the drive lacks, a
  // non-finite value): InputError, nothing changed.
  /// Port of joint `joint` (index in model().joint_names or its name).
  void setCommandPort(sim::PlantState& state, int joint, CommandPort port) const;
  void setCommandPort(sim::PlantState& state, const std::string& joint, CommandPort port) const {
    setCommandPort(state, model_.jointIndex(joint), port);
  }
  CommandPort commandPort(const sim::PlantState& state, int joint) const;
  /// Value of the command of joint `joint` for its port MotorVelocity [rad/s], Current [A], Voltage [V] or
  /// MotorTorque [N·m] (held until changed; InputError under the Setpoint port: use setSetpoint).
  void setCommand(sim::PlantState& state, int joint, double value) const;
  /// Values for every joint (size dof()); the entries of joints under the Setpoint port are ignored.
  void setCommands(sim::PlantState& state, const Eigen::VectorXd& values) const;
  double command(const sim::PlantState& state, int joint) const;
  /// Holds the reference of joint `joint` at (q [rad], q̇ [rad/s], q̈ [rad/s²]) from now on, in place of the
  /// trajectory (the q̈ feed-forward enters the logged inverse-dynamics reference; the cascade uses q and q̇).
  void setSetpoint(sim::PlantState& state, int joint, double q, double qd = 0.0, double qdd = 0.0) const;
  /// Held references of every joint (sizes dof(); qd and qdd may be empty: zero).
  void holdSetpoints(sim::PlantState& state, const Eigen::VectorXd& q, const Eigen::VectorXd& qd = {},
                     const Eigen::VectorXd& qdd = {}) const;
  /// Back to the trajectory (or setpoint function) for every joint.
  void releaseSetpoints(sim::PlantState& state) const;
  /// An external wrench [f (N); n (N·m)], both in world coordinates, applied at the origin of frame `frame`,
  /// held until changed (zero removes it). Acts on the body that carries the frame.
  void setExternalWrench(sim::PlantState& state, const std::string& frame,
                         const Eigen::Matrix<double, 6, 1>& wrench) const;
  void clearExternalWrenches(sim::PlantState& state) const;
  /// The command ports as named inputs (sim::Plant::inputPorts): per joint J, in joint order, `J.q` [rad], `J.qd`
  /// [rad/s], `J.qdd` [rad/s²] (mode "setpoint": the held reference, setSetpoint) and, where the drive has them,
  /// `J.motor_velocity` [rad/s], `J.current` [A], `J.voltage` [V], `J.motor_torque` [N·m] (setCommand); group J.
  /// Setting one selects its port for the joint (setCommandPort, bumpless). Any finite value is admissible (the
  /// voltage saturates at the supply, as a command would). After them, per joint, `J.load_torque` [N·m]: an external
  /// torque at the joint (a disturbance, a payload's torque; 0 until set, no group, always in effect), added to the
  /// drives' joint torques before the forward dynamics; it takes a profile (setInputProfile: the `inputs:` key of a
  /// tracking file) and can be released (back to its profile or 0).
  std::vector<sim::InputPort> inputPorts() const override;
  void setInput(sim::PlantState& state, int port, double value) const override;
  double input(const sim::PlantState& state, int port) const override;
  bool inputActive(const sim::PlantState& state, int port) const override;
  /// Only the `J.load_torque` inputs take profiles (the command ports are set between steps).
  void setInputProfile(int port, const control::Profile& profile) override;
  /// Only the `J.load_torque` inputs are released (a command port is left by choosing another).
  void releaseInput(sim::PlantState& state, int port) const override;
  /// Bumpless transfer for joints whose port changed since the last call (or the start).
  void applyInputs(sim::PlantState& state, double t, Eigen::Ref<Eigen::VectorXd> y) const override;

  /// Faults that act during the run (Fault::timeVarying(): a later onset, a progression, intermittent sensor
  /// faults, bearing ripple; systems/faults.hpp for their laws). Parameter faults are applied by rebuilding the
  /// drive's components from their values before these faults at the schedule's instants (time events); sensor
  /// faults change the measured joint angle the controller reads (and the q_fb signal); the bearing ripple adds to
  /// the friction torque. Each is checked against its drive now (InputError as applyFault). Replaces earlier ones.
  void setFaults(std::vector<Fault> faults);
  const std::vector<Fault>& faults() const { return faults_; }

  /// Joint positions [rad] at t = 0 for initialState() (default: the reference at t = 0, or zeros).
  void setInitialPositions(const Eigen::VectorXd& q0);

  /// Switches to sampled (discrete-time) control at `rate` [Hz]: the controller states leave the ODE state
  /// vector (stateSize() shrinks) and live in the sampled-control state; between samples the controller
  /// outputs are held (zero-order hold). Call before initialState(). `seed` fixes the sensor noise sequence.
  /// `current_rate` [Hz] (0: `rate`): a faster rate for the cascades' current loops, an integer multiple of
  /// `rate` (multi-rate control as in servo drives: the current loop at the PWM rate, position and velocity loops
  /// at `rate`). InputError for a rate at which a current loop is unstable (control::sampledCurrentLoopRadius,
  /// the message names the rate from which it is stable) or a current rate that is not such a multiple.
  void setSampledControl(double rate, unsigned seed, double current_rate = 0.0);
  bool sampled() const { return sample_rate_ > 0.0; }
  double sampleRate() const { return sample_rate_; }
  /// Rate of the current loops under sampled control [Hz] (sampleRate() unless set faster).
  double currentRate() const { return current_rate_ > 0.0 ? current_rate_ : sample_rate_; }
  /// One sample at time t (every 1/currentRate()): measure (noise, quantisation, encoder-difference speed), advance
  /// the discrete controllers by forward Euler and hold their outputs; with a faster current rate the position and
  /// velocity loops advance over 1/rate at every (currentRate()/rate)-th call, the current loops at every call. The
  /// held inputs jump: the simulators stop there (and restart or keep the history, CvodeOptions::input_jump).
  void controlStep(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;

  /// Initial state: joints at q0 (at rest), motors at N φ_out, gear internal states at static equilibrium,
  /// friction states at rest, controller states holding the gravity load.
  Eigen::VectorXd initialState(const Eigen::VectorXd& q0, double t0 = 0.0) const;
  /// All drive signals at (t, y) (evaluates the right-hand side; the result lives in the state's workspace).
  const RobotSignals& driveSignals(const sim::PlantState& state, double t,
                                   const Eigen::Ref<const Eigen::VectorXd>& y) const;
  /// Mechanical energy (the nominal drives: no parameter faults): multibody kinetic + potential, motor rotor kinetic, stored transmission and end-stop
  /// energy [J].
  double mechanicalEnergy(const Eigen::Ref<const Eigen::VectorXd>& y) const;
  /// Index of the first state of drive k's parts (-1 if absent).
  struct DriveLayout {
    int motor = -1, current = -1, gear = -1, friction = -1, controller = -1;
    int n_gear = 0, n_friction = 0, n_controller = 0;
    bool rigid = false;
    double ratio = 1.0;
  };
  const DriveLayout& layout(int k) const { return layout_[static_cast<size_t>(k)]; }
  /// Speed of drive k's motor shaft [rad/s] in state y: its own state, or N·q̇_k where a rigid gear merges the motor
  /// into the joint (N the gear ratio). What a motor encoder measures: the collocated rate for damping injection.
  double motorVelocity(const Eigen::Ref<const Eigen::VectorXd>& y, int k) const {
    const DriveLayout& L = layout(k);
    return L.motor >= 0 ? y[L.motor + 1] : L.ratio * y[model_.nq + k];
  }

  // sim::Plant
  std::string name() const override { return "robot with drives '" + model_.name + "'"; }
  int stateSize() const override { return n_states_; }
  /// "q_<joint> [rad]", "qd_<joint> [rad/s]", then per drive "drive of joint '<joint>': motor angle [rad]", ...
  std::string stateName(int i) const override;
  /// The joint angles and the motor angles (joints and motors may keep turning).
  bool unboundedState(int i) const override;
  /// initialState(q0) with the positions of setInitialPositions().
  Eigen::VectorXd initialState() const override;
  /// ẏ = f(t, y): pure apart from the workspace; no heap allocation.
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  /// End stops (mode stop): q − q_upper and q_lower − q per limited joint.
  int rootCount() const override { return stops_.rootCount(); }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  /// The trajectory's breakpoints under continuous control (sampled control restarts at every sample), and the
  /// instants of the faults' schedules and episodes.
  std::vector<double> timeEvents(double t_end) const override;
  /// The faults' state at t0; sampled control: the controller states holding the gravity load at the joint angles
  /// of y (as initialState(q0) sets them under continuous control), then the controllers' first sample at t0.
  void start(sim::PlantState& state, double t0, const Eigen::Ref<const Eigen::VectorXd>& y) const override;
  /// At time events: the faults' parameter schedule and the value a stuck sensor holds.
  void updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   const std::vector<int>& fired) const override;
  double samplePeriod() const override { return sampled() ? 1.0 / currentRate() : 0.0; }
  void sample(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    controlStep(state, t, y);
  }
  /// Per joint: q_set, q, q_fb, qd, motor_velocity, current, current_ref, voltage, gear_torque,
  /// friction_torque and the inverse-dynamics reference id_torque = RNEA(q_set, q̇_set, q̈_set) + N² J_M q̈_set
  /// + friction steady state at q̇_set (the classic rigid model, [Raviola2023, Fig. 9]); then the TCP
  /// position [m] and roll-pitch-yaw [rad] of the tip frame.
  const std::vector<std::string>& signalNames() const override { return signal_names_; }
  /// The Jacobian from the system's structure: the hub is the multibody [q, q̇]; each drive's states form a
  /// block, coupled to the joints only. Hub columns by difference quotients of the whole right-hand side
  /// (2n evaluations); drive columns by perturbing one state of every drive at once (as many evaluations as
  /// the largest drive has states), the drive's own rows from the difference and the q̈ rows through the
  /// drive's output torque, ∂q̈/∂x = (∂q̈/∂τ_out,k)(∂τ_out,k/∂x), with ∂q̈/∂τ_out = M⁻¹G⁻ᵀ exact (q̈ is
  /// affine in the joint torques). With the same increments the result equals plain difference quotients of every
  /// column to rounding (tested), at about a quarter of their evaluations on the UR5 twin.
  bool providesJacobian() const override { return true; }
  /// JacobianKind::Analytic, without a coupling matrix, external wrenches or reflected rotor inertias (the CRBA
  /// path): the multibody's columns from the analytic ABA derivatives and two evaluations that perturb every joint at
  /// once (jacobianByJoint, robot_dynamics.cpp); otherwise as above.
  void jacobian(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                Eigen::Ref<Eigen::MatrixXd> J, sim::JacobianKind kind) const override;
  sim::JacobianStructure jacobianStructure() const override;
  /// Without a wrench function of time and without a load-torque port driven by its profile, under sampled control
  /// or with every drive on a port that replaces its controller (voltage, motor torque): the right-hand side reads
  /// only held values and y (the reference and the sensor faults' episodes, functions of t, reach it only through a
  /// continuous controller).
  bool timeInvariant(const sim::PlantState& state) const override;
  /// The joint angles and each drive's motor, current and gear states: the drive trains' lightly damped modes (the
  /// strain-wave gear's 4.6–5.3 kHz motor–gear modes, ζ ≈ 0.001–0.006). Not the joint velocities (friction's σ₁ż and
  /// the gear torques act there: the stick–slip's stiff real and growing modes), the friction states or a continuous
  /// controller's states.
  std::vector<int> oscillatoryStates() const override;
  /// The same, and for each block the index of its drive.
  sim::JacobianStructure jacobianStructure(std::vector<int>* drive_of_block) const;
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override;

 private:
  // The right-hand side, stage by stage as the signals flow (each fills the state's signals and its part of ẏ).
  // Signals: every signal (the reference too); Derivatives: ẏ (under sampled control without the reference, which
  // only the samples read); DrivesOnly: as Derivatives up to the joint torques (st.tau) and the drives' rows of ẏ,
  // not q̈ (its rows of ydot are left as they were).
  enum class Pass { Signals, Derivatives, DrivesOnly };
  void evaluate(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot, Pass pass) const;
  // The Jacobian's drive columns (the general path and jacobianByJoint), and its joint-local fast path (no coupling,
  // no external wrenches, ABA): robot_dynamics.cpp.
  void driveColumns(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                    const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                    Eigen::Ref<Eigen::MatrixXd> J) const;
  void jacobianByJoint(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                       Eigen::Ref<Eigen::MatrixXd> J) const;
  // The reference at t (`anchored`: plus the relative replay's anchors).
  void setpointStage(const State& st, double t, bool anchored = true) const;
  void measurementStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  // Relative replay: a rest of joint k's reference starts within `tol` [s] of t.
  bool restStartsAt(int k, double t, double tol) const;
  // Relative replay: the anchors of the joints whose reference's rest starts at t (all joints when `all`).
  void reanchor(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool all) const;
  // The faults at time t: rebuilds the state's drives whose scheduled parameter values changed, captures stuck
  // sensor values (`restart`: from the nominal drives, as at the start of a run).
  void updateFaults(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool restart) const;
  // The state's drives from the nominal ones with the parameter faults at their applied values (`dirty`: the drives
  // to rebuild; empty: all).
  void rebuildDrives(State& st, const std::vector<char>& dirty) const;
  // Measured joint angle of drive k at t from the sensor's reading `q_meas` (true angle plus bias): the intermittent
  // sensor faults of the drive.
  double faultySensor(const State& st, int k, double t, double q_meas) const;
  void controllerStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const;
  void powerElectronicsStage(const State& st) const;
  void motorElectricsStage(const State& st, double* ydot) const;
  void transmissionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const;
  void frictionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const;
  void jointTorqueStage(const State& st) const;
  void jointLoadStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;  // stops, loads
  void multibodyStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  void rotorReactionStage(const State& st) const;
  void checkJoint(int joint, const char* what) const;
  // Why joint `joint`'s drive cannot take commands at `port` (empty: it can).
  std::string portRefusal(int joint, CommandPort port) const;
  /// The inputs (inputPorts()): joint and kind (0, 1, 2: reference q, q̇, q̈; 3 + CommandPort: a command port;
  /// kLoadTorqueInput: the joint's load torque).
  struct InputSlot {
    int joint;
    int kind;
  };
  std::vector<InputSlot> inputs_;
  static constexpr int kLoadTorqueInput = 3 + 5;
  std::vector<sim::InputPort> load_ports_;  ///< the `J.load_torque` inputs, per joint
  sim::InputProfiles load_profiles_;        ///< their profiles (setInputProfile)
  const InputSlot& inputSlot(int port) const;
  void bumpless(State& st, int k, CommandPort from, double t, Eigen::Ref<Eigen::VectorXd> y) const;
  void multiRateStep(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  // The full initial state (controller states included, also under sampled control) with the joints at q0.
  Eigen::VectorXd initialFull(const Eigen::VectorXd& q0, double t0) const;
  // Sampled control's sensors of drive k (noise, quantisers): the joint and motor angles and the encoder speed
  // differenced over Ts (updates the encoder memory and the held joint feedback), and the current.
  struct MotionMeasurement {
    double q = 0.0, qm = 0.0, qdm = 0.0;
  };
  MotionMeasurement measureMotion(State& st, int k, double t, const Eigen::Ref<const Eigen::VectorXd>& y, double phi,
                                  double phid, double Ts) const;
  double measureCurrent(State& st, int k, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  control::ControllerInputs controllerInputs(const State& st, int k) const;  // after the measurement stage

  multibody::Model model_;
  std::vector<DriveSpec> drives_;  // nominal (the faults apply to the state's copies)
  std::vector<control::JointController> controllers_;
  std::vector<DriveLayout> layout_;
  Eigen::MatrixXd G_, Ginv_;
  bool coupled_ = false;
  bool crba_path_ = false;     // coupled rigid drives: non-diagonal reflected inertia
  Eigen::MatrixXd reflected_;  // G⁻ᵀ diag(N² J_M rigid) G⁻¹ (crba path)
  int n_states_ = 0;
  SetpointFunction setpoints_;
  std::vector<double> setpoint_breaks_;
  bool relative_ = false;                                      // setRelativeReplay
  std::vector<std::vector<std::pair<double, double>>> rests_;  // the trajectory's rests (relative replay)
  WrenchFunction wrenches_;
  EndStops stops_;
  Eigen::VectorXd q0_;
  // Sampled control (settings; its run-time part is in State).
  double sample_rate_ = 0.0;
  double current_rate_ = 0.0;  // multi-rate: the current loops' rate (0: single rate)
  long inner_per_outer_ = 1;   // current-loop samples per outer sample
  int n_ctrl_sampled_ = 0;     // controller states outside the ODE state (sampled control)
  unsigned seed_ = 0;          // of the sensor noise
  // Faults during the run (setFaults): per fault its drive.
  std::vector<Fault> faults_;
  std::vector<int> fault_drive_;
  // Logged signals.
  std::vector<std::string> signal_names_;
  multibody::Model id_model_;  // rotor inertias of every drive as armature (inverse-dynamics reference)
  int tip_ = 0;
};

}  // namespace jointsim::systems
