#pragma once
/// \file
/// The Modelica RobotR3 FullRobot ([MSL, RobotR3.FullRobot]; docs/validation.md): the Manutec r3 arm (a
/// multibody model) driven by six axes — type 1 (op-amp motor, motor-side bearing friction, spring–damper,
/// ideal gear) or type 2 (op-amp motor, ideal gear with the rotor inertia N² J added to the arm, joint-side
/// bearing friction) — each with the P/PI cascade, following one synchronised KinematicPTP2 path, ending at the
/// path end + swing time. Friction follows the exact MSL logic; the stuck torques of stuck type-2 joints are
/// solved together with the arm dynamics (M̄ q̈ + h = τ with q̈_j = 0 for every stuck joint j).
/// States (36 for the r3): q, q̇, then φ_rel, ω_rel of each type-1 axis, then x, v_C, i of each axis (then four energy
/// integrals with RobotR3FullSetup::energy). The same plant runs one axis on a load ([MSL, RobotR3.OneAxis],
/// robotr3_axis.hpp: systems::oneAxisRobot).
/// The plant is constant during a run; the friction modes (the discrete state) and the workspace of the
/// right-hand side are in its State (makeState()).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/joint_controller.hpp"
#include "jointsim/control/kinematic_ptp.hpp"
#include "jointsim/drive/opamp_motor.hpp"
#include "jointsim/drive/parameters.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/systems/drive_chain.hpp"

namespace jointsim::systems {

struct RobotR3AxisParams {
  int type = 1;        ///< 1: elastic gear, motor-side friction; 2: rigid gear, joint-side friction
  double ratio = 1.0;  ///< motor angle / joint angle [-]
  drive::OpAmpMotorParams motor;
  double c = 0.0, d = 0.0;      ///< type 1 spring [N·m/rad] and damper [N·m·s/rad], motor side
  double Rv0 = 0.0, Rv1 = 0.0;  ///< friction f(v) = Rv0 + Rv1 v [N·m, N·m·s/rad]
  double peak = 1.0;            ///< stiction factor (type 1 uses 1, [MSL, RobotR3.Utilities.GearType1])
  double kp = 5.0, ks = 0.5, Ts = 0.05;
  /// Axis j (1..6) of FullRobot (axis parameters of [MSL, RobotR3.FullRobot]).
  static RobotR3AxisParams fullRobot(int j);
  /// The axis of [MSL, RobotR3.OneAxis]: type 1, ratio 210, c = 8 N·m/rad, d = 0.01 N·m·s/rad, Rv0 = 0.5 N·m,
  /// Rv1 = 0.1/130 N·m·s/rad, peak 1 (type 1 ignores the gear's peak), kp = 5 1/s, ks = 0.5 A·s/rad, Ts = 0.05 s.
  static RobotR3AxisParams oneAxis();
  /// Parameter table of the axis's drive (drive/parameters.hpp): motor.J, motor.k (role torque_constant), c (role
  /// stiffness) and d of a type-1 axis, Rv0 (role coulomb), Rv1, peak.
  std::vector<drive::ParameterInfo> parameters() const;
  /// A copy with `changes` applied by the keys of parameters(). InputError naming `component` and the key.
  RobotR3AxisParams withParameters(const drive::ParameterChanges& changes, const std::string& component) const;
};

struct RobotR3FullSetup {
  std::string name = "robotr3_full_robot";
  multibody::Model arm;                                        ///< the Manutec r3 (config/robots/robotr3.yaml)
  std::vector<RobotR3AxisParams> axes;                         ///< one per joint, base to tip
  Eigen::VectorXd q_begin, q_end, qd_max, qdd_max;             ///< path [rad, rad/s, rad/s²]
  double start_time = 0.0, swing_time = 0.5, stop_time = 2.0;  ///< [s]
  double log_interval = 0.0004;                                ///< [s]
  sim::CvodeOptions solver = DriveChainSetup::defaultSolver();
  /// Friction torque of each axis at t = 0 [N·m], |τ| ≤ peak·Rv0 (undetermined in MSL, docs/validation.md; empty:
  /// 0): the start currents hold it.
  Eigen::VectorXd initial_friction;
  /// Energy bookkeeping: four integrals as ODE states after the others, summed over the axes — the amplifiers' work
  /// on the armature circuits W_el = Σ∫ −amp_gain v_C i dt, the resistor, damper and friction losses Σ∫ Ra i² dt,
  /// Σ∫ d ω_rel² dt, Σ∫ τ_f ω dt (ω the motor speed of a type-1 axis, the joint speed of a type 2) [J] — and the
  /// columns energy.amplifier_work, energy.stored (½ q̇ᵀ M̄ q̇ + potential + type-1 rotors ½ J ω_m² and springs
  /// ½ c φ_rel² + inductances ½ La i²), energy.resistor_loss, energy.damper_loss, energy.friction_loss [J]. The work
  /// of the load-torque inputs is not in them. W_el = ΔE_stored + losses is the balance.
  bool energy = false;
  /// Empty: the column names of [MSL, RobotR3.FullRobot] (axis<j>.…, mechanics.…). Set: a single type-1 axis with
  /// energy bookkeeping on a load, with the column names of [MSL, RobotR3.OneAxis] under this prefix
  /// (<prefix>.controller.PI.x, …, the friction torque, its mode flags and the current reference; robotr3_axis.hpp).
  std::string one_axis_prefix;
  /// Empty: the axes drive the arm's multibody dynamics. Set (one value per joint, > 0) [kg·m²]: each axis drives a
  /// fixed load inertia of its own about a fixed axis (a 1-D shaft: no gravity, no coupling between the joints; the
  /// arm model only names the joints) — M̄ = diag(load_inertia + type-2 rotors' N² J), h = 0.
  Eigen::VectorXd load_inertia;
  void validate() const;
};

class RobotR3Full : public sim::HeldInputPlant {
 public:
  explicit RobotR3Full(RobotR3FullSetup setup);

  /// The run's state: the friction mode of each axis (discrete state, saved) and the workspace of the right-hand
  /// side (sized here: no allocation in derivatives(), roots() or signals()).
  struct State : sim::PlantStateOf<State> {
    explicit State(const RobotR3Full& robot);
    std::vector<FrictionMode> modes;  ///< per axis, base to tip
    sim::HeldInputs inputs;           ///< the input ports' values (saved)
    // Workspace (holds nothing between calls; not saved).
    mutable multibody::Data data;
    mutable Eigen::VectorXd q_ref, qd_ref, qdd_ref, tau, qdd, wm, wm_dot, tau_f, stuck, xdot, iref;
    mutable Eigen::MatrixXd Mbar;
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }

  const RobotR3FullSetup& setup() const { return s_; }
  /// t_end = endTime(), outputs every log_interval (also the max step when the solver sets none).
  sim::SimulateOptions simulateOptions() const;
  double endTime() const;  ///< termination time: path end + swing, capped at the stop time
  /// The friction mode of each axis in `state` (a state of this plant).
  const std::vector<FrictionMode>& modes(const sim::PlantState& state) const;

  /// Input ports (sim::InputPort): per joint `<joint>.current` [A], the current reference held in place of the axis
  /// controller's (its PI frozen; in effect once set), and `<joint>.load_torque` [N·m], an external torque at the
  /// joint (0 until set).
  std::vector<sim::InputPort> inputPorts() const override { return ports_; }
  // setInput, input, inputActive, setInputProfile, releaseInput: sim::HeldInputPlant.
  std::string name() const override;
  int stateSize() const override { return n_states_; }
  Eigen::VectorXd initialState() const override;
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  int rootCount() const override { return 2 * n_; }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  /// The friction modes consistent with y at t (the event iteration with no flags).
  void start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    updateModes(state, t, y, {});
  }
  void updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   const std::vector<int>& fired) const override;
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> row) const override;

 protected:
  /// The path's segment switches (timeEvents() adds the input profiles' jumps: sim::HeldInputPlant).
  std::vector<double> modelTimeEvents(double t_end) const override;
  sim::HeldInputs& heldInputs(sim::PlantState& state) const override { return own<State>(state).inputs; }
  const sim::HeldInputs& heldInputs(const sim::PlantState& state) const override { return own<State>(state).inputs; }
  bool alwaysActive(int port) const override;

 private:
  void solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;  // fills st's workspace
  // The stored energy at y (energy bookkeeping) [J], with st's workspace after solve().
  double storedEnergy(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  RobotR3FullSetup s_;
  int n_ = 0, n_states_ = 0;
  int energy_ = -1;        // index of W_el (E_R, E_d, E_f follow); −1: no energy bookkeeping
  std::vector<int> rel_;   // index of φ_rel per axis (−1 for type 2)
  std::vector<int> ctrl_;  // index of x per axis (v_C, i follow)
  control::KinematicPtpTrajectory path_;
  std::vector<control::JointController> controllers_;  ///< per axis: the TorqueCascade (kp, ks, Ts)
  std::vector<std::string> signals_;
};

}  // namespace jointsim::systems
