#pragma once
/// \file
/// The clamping experiment of [Olsson2017, §3.7–3.12, A.6–A.15, §4.3, Listing 4.1] on a whole robot: the
/// end effector is held by a 6-D spring–damper clamp at its start pose while the axis controllers drive
/// the motors back and forth along ClampingPathPlanning references, so each motor winds up its
/// transmission against the clamped structure. Motor torque against motor angle is the axis's clamping
/// curve.
///
/// Per axis ([Olsson2017, §3.8, Fig. 3.2, A.7–A.9]): controller torque → motor inertia J → bearing friction
/// (table with peak, exact MSL stick–slip logic on the motor shaft) → ElastoBacklash (c, d, b; motor side) →
/// ideal gear r → gear output angle φ_out. An optional coupling matrix G (the wrist) maps gear output angles to
/// joint angles, q = G φ_out, and τ_out = Gᵀ τ_joint ([Olsson2017, eqs. 2.1–2.2]). Joints with c_orth > 0 get
/// two extra rotational degrees of freedom orthogonal to their axis (the bending compliance of
/// [Olsson2017, §3.7, Table 3.3, A.6, A.15], axes from getOrthVectors), each restrained by c_orth and d_orth.
///
/// Clamp ([Olsson2017, §3.9, Table 3.6, A.11]): on the clamp frame, force f = −(c_lin Δp + d_lin v) with Δp the
/// frame origin's displacement from its start position and v its velocity (world frame), and moment
/// m = −(c_rot θ + d_rot ω) with θ the rotation vector of R₀ᵀR and ω the angular velocity, both in the frame's
/// own axes. [Olsson2017] integrates ω for θ; the two agree to second order in the (µrad) rotation, and the rotation
/// vector needs no extra states and makes an isotropic c_rot exactly conservative.
///
/// Controller ([Olsson2017, §2.8, §3.10, Table 3.7, A.12]): u = r_c q̇_ref + k_p (φ_ref − φ_m) − ω_m,
/// τ_m = k_s (u + x), ẋ = u / T_s, with φ_ref = φ_m(0) + r_c q_ref(t): the reference is the axis's
/// ClampingPath scaled by the controller ratio r_c (the wrist controllers ignore the coupling, as in
/// [Olsson2017]) and offset by the start motor angle.
///
/// State vector: [q, q̇] of the arm (joints and orthogonal-compliance angles), then per axis [φ_m, ω_m, x].
/// Units: SI throughout (rad, rad/s, N·m, N, m, kg·m²).

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/clamping_path.hpp"
#include "jointsim/control/joint_controller.hpp"
#include "jointsim/drive/msl_friction.hpp"
#include "jointsim/drive/parameters.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::systems {

using drive::FrictionMode;

struct ClampingAxisParams {
  std::string joint;      ///< joint this axis drives (through G for a coupled wrist)
  double ratio = 1.0;     ///< gear ratio r = φ_motor / φ_out [-], != 0 (wrist axes in [Olsson2017]: 1)
  double inertia = 0.01;  ///< motor (rotor) inertia J [kg·m²], > 0
  double c = 50.0;        ///< ElastoBacklash stiffness, motor side [N·m/rad], > 0
  double d = 10.0;        ///< ElastoBacklash damping, motor side [N·m·s/rad], >= 0
  double b = 0.001;       ///< total backlash, motor side [rad], >= 0
  std::vector<std::array<double, 2>> tau_pos{{0.0, 1.0}, {1.0, 1.1}};  ///< friction table rows [rad/s, N·m]
  double peak = 1.0;                      ///< stiction factor (breakaway = peak · tau_pos(0)) [-], >= 1
  double c_orth = 0.0;                    ///< orthogonal (bending) stiffness [N·m/rad]; 0 = rigid
  double d_orth = 30.0;                   ///< orthogonal damping [N·m·s/rad], >= 0 ([Olsson2017] default 30)
  double kp = 10.0;                       ///< position gain [1/s]
  double ks = 1.0;                        ///< speed PI gain [N·m·s/rad]
  double Ts = 0.01;                       ///< PI time constant [s], > 0
  double controller_ratio = 1.0;          ///< r_c scaling the arm-side reference to the motor [-]
  control::ClampingPathParams path{0.0};  ///< reference swing (q_pos = 0: hold the start angle)
  void validate() const;                  ///< throws InputError naming the axis
  /// Parameter table of the axis's drive (drive/parameters.hpp; keys as in a clamping file's axis mapping): inertia,
  /// c (role stiffness), d, b (role backlash), friction.tau_pos[i][1] (role coulomb), friction.peak.
  std::vector<drive::ParameterInfo> parameters() const;
  /// A copy with `changes` applied (by the keys of parameters()), validated. InputError naming the axis and key.
  ClampingAxisParams withParameters(const drive::ParameterChanges& changes) const;
};

struct ClampSpec {
  std::string frame;                                             ///< clamped frame (empty: the model's tip frame)
  Eigen::Matrix3d c_lin = 9001.0 * Eigen::Matrix3d::Identity();  ///< [N/m] ([Olsson2017, A.11] default)
  Eigen::Matrix3d d_lin = 9001.0 * Eigen::Matrix3d::Identity();  ///< [N·s/m]
  Eigen::Matrix3d c_rot = 9001.0 * Eigen::Matrix3d::Identity();  ///< [N·m/rad]
  Eigen::Matrix3d d_rot = 9001.0 * Eigen::Matrix3d::Identity();  ///< [N·m·s/rad]
};

struct ClampingSetup {
  std::string name = "clamping";
  multibody::Model arm;                  ///< rigid robot (without orthogonal compliance)
  std::vector<ClampingAxisParams> axes;  ///< one per movable joint of `arm`, any order
  /// Coupling between gear outputs and joints, q = G φ_out, over the joints in `coupled_joints` order
  /// (e.g. the IRB140 wrist's 3×3 G). Empty: no coupling.
  Eigen::MatrixXd coupling;
  std::vector<std::string> coupled_joints;
  ClampSpec clamp;
  Eigen::VectorXd q0;           ///< start posture [rad] (empty: zeros); the clamp holds this pose
  double duration = 15.0;       ///< [s]
  double log_interval = 0.001;  ///< [s]
  sim::CvodeOptions solver = defaultSolver();
  /// BDF capped at order 2 (lightly damped clamp/bending modes, docs/design.md), rtol 1e-6, atol 1e-9.
  static sim::CvodeOptions defaultSolver();
  void validate() const;
};

/// The clamped robot as a plant. Constant once built (sim::Plant): the run's friction modes and the workspace of
/// the right-hand side live in ClampedRobot::State.
class ClampedRobot : public sim::HeldInputPlant {
 public:
  /// The run's state: the motors' friction modes (discrete state, saved) and the workspace of the right-hand side.
  struct State : sim::PlantStateOf<State> {
    /// Modes all Stuck (start() makes them consistent with the initial state); the workspace sized for `robot`,
    /// so that derivatives(), roots() and signals() allocate nothing.
    explicit State(const ClampedRobot& robot);
    /// MSL friction mode of each axis's motor bearing.
    std::vector<FrictionMode> modes;
    sim::HeldInputs inputs;  ///< the input ports' values (saved)
    // Workspace (mutable: the right-hand side is const; not saved, holds nothing between calls).
    mutable multibody::Data data;       ///< kinematics and dynamics of model()
    mutable multibody::Matrix6Xd fext;  ///< clamp wrench per joint body [N·m; N]
    mutable Eigen::VectorXd tau;        ///< joint torques of model() [N·m]
    /// Per axis: gear output torque [N·m], joint angle [rad] and speed [rad/s] of the driven joint, gear output angle
    /// [rad] and speed [rad/s], spring, motor and friction torques [N·m], torque on a stuck motor [N·m], motor
    /// acceleration [rad/s²], controller integrator rate ẋ = u/Ts [rad/s²] and reference [rad].
    mutable Eigen::VectorXd tau_out, qa, qda, phi_out, phid_out, tau_s, tau_m, tau_f, stuck, wdot, xdot, ref;
    /// Clamp displacement [m] and rotation vector [rad], force [N] and moment [N·m] (world).
    mutable Eigen::Vector3d dp, theta, f_w, m_w;
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };

  explicit ClampedRobot(ClampingSetup setup);
  const ClampingSetup& setup() const { return s_; }
  /// t_end = duration, outputs every log_interval (also the max step when the solver sets none).
  sim::SimulateOptions simulateOptions() const;
  /// The arm with the orthogonal-compliance joints inserted.
  const multibody::Model& model() const { return model_; }
  int axisCount() const { return n_; }
  /// Index in model() of the joint driven by axis k, and of its two orthogonal joints (-1 if none).
  int jointOfAxis(int k) const { return joint_[static_cast<size_t>(k)]; }
  std::array<int, 2> orthOfAxis(int k) const { return orth_[static_cast<size_t>(k)]; }
  /// State index of axis k's motor angle (ω_m and the controller state x follow).
  int motorState(int k) const { return 2 * model_.nq + 3 * k; }

  /// Friction modes of the run `state` (one per axis).
  const std::vector<FrictionMode>& modes(const sim::PlantState& state) const;
  /// Indices of axis k's motor angle [rad] and motor torque [N·m] in signalNames().
  int motorAngleSignal(int k) const { return 10 * k; }
  int motorTorqueSignal(int k) const { return 10 * k + 2; }

  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  /// Input ports (sim::InputPort): per axis `<joint>.motor_torque` [N·m], the motor torque held in place of the axis
  /// controller's output (its integrator frozen; in effect once set), and `<joint>.load_torque` [N·m], an external
  /// torque at the joint (0 until set).
  std::vector<sim::InputPort> inputPorts() const override { return ports_; }
  // setInput, input, inputActive, setInputProfile, releaseInput: sim::HeldInputPlant.
  std::string name() const override;
  int stateSize() const override { return n_states_; }
  Eigen::VectorXd initialState() const override;
  /// Initial friction modes: from all Stuck, the MSL event iteration at state y and time t.
  void start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override;
  /// Sets the friction modes consistently with state y at time t (MSL event iteration).
  void updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   const std::vector<int>& fired) const override;
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  int rootCount() const override { return 2 * n_; }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override;

  /// Clamp displacement Δp [m] (world) and rotation vector θ [rad] (frame axes) at arm posture q (the kinematics
  /// computed in the workspace of `state`).
  void clampDeflection(const sim::PlantState& state, const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Vector3d& dp,
                       Eigen::Vector3d& theta) const;

 protected:
  /// Time events of the references (segment slots, phase switches) [s] (timeEvents() adds the input profiles' jumps:
  /// sim::HeldInputPlant).
  std::vector<double> modelTimeEvents(double t_end) const override;
  sim::HeldInputs& heldInputs(sim::PlantState& state) const override { return own<State>(state).inputs; }
  const sim::HeldInputs& heldInputs(const sim::PlantState& state) const override { return own<State>(state).inputs; }
  bool alwaysActive(int port) const override;

 private:
  void solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  ClampingSetup s_;
  multibody::Model model_;
  int n_ = 0, n_states_ = 0, clamp_frame_ = -1;
  std::vector<int> joint_;
  std::vector<std::array<int, 2>> orth_;
  std::vector<drive::ElastoBacklash> eb_;
  std::vector<control::JointController> controllers_;  ///< per axis: the TorqueCascade with the axis's gains
  std::vector<control::ClampingPath> paths_;
  Eigen::MatrixXd Gfull_, GfullInv_;  // over the axes, in axis order: q_axis = G φ_out
  bool coupled_ = false;
  Eigen::VectorXd phi_m0_;
  Eigen::Vector3d p0_;
  Eigen::Matrix3d R0_;
  std::vector<std::string> signals_;
};

}  // namespace jointsim::systems
