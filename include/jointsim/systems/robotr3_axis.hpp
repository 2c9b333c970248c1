#pragma once
/// \file
/// A Modelica RobotR3 axis driving a 1-D load inertia ([MSL, RobotR3.OneAxis]): op-amp current-controlled motor
/// (drive/opamp_motor.hpp), motor-side bearing friction with the exact MSL stuck/start/sliding logic,
/// motor-side spring–damper, ideal gear, load inertia; the P/PI cascade of [MSL, RobotR3.Utilities.Controller]
/// producing the current set-point; a KinematicPTP2 path; termination at end time + swing time.
/// States (as the Modelica model): q, q̇ (load), φ_rel = ratio·q − φ_m, ω_rel, PI state x, v_C, i; then
/// four energy integrals for bookkeeping: W_el = ∫ −5 v_C i dt (work of the power amplifier on the
/// armature circuit), E_R = ∫ Ra i² dt, E_d = ∫ d ω_rel² dt, E_f = ∫ τ_f ω_m dt [J].
/// Only axis type 1 (elastic gear) is modelled so far.
/// The plant is constant during a run; the bearing friction's mode (the discrete state) is in its State
/// (makeState()).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/joint_controller.hpp"
#include "jointsim/control/kinematic_ptp.hpp"
#include "jointsim/drive/opamp_motor.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/systems/drive_chain.hpp"
#include "jointsim/systems/robotr3_full.hpp"

namespace jointsim::systems {

struct RobotR3AxisSetup {
  std::string name = "one_axis";
  std::string prefix = "axis";  ///< prefix of the reference column names ("axis" for OneAxis)
  /// The axis's drive: a type-1 axis (elastic gear, motor-side friction) with its controller, the same parameters
  /// (and parameter table, through which faults act) as an axis of the FullRobot. Default: [MSL, RobotR3.OneAxis].
  RobotR3AxisParams axis = RobotR3AxisParams::oneAxis();
  double load_inertia = 19.5;                        ///< J_load [kg·m²]
  double q_begin = 0.0, q_end = 2.0943951023931953;  ///< path [rad]
  double qd_max = 3.0, qdd_max = 10.0;               ///< path limits [rad/s], [rad/s²]
  double start_time = 0.0;                           ///< path start [s]
  double swing_time = 0.5;                           ///< run ends at the first t >= path end + swing [s]
  double stop_time = 1.6;                            ///< requested stop time [s]
  double sa0 = 0.0;               ///< friction torque at t = 0 (undetermined in MSL; docs/validation.md) [N·m]
  double log_interval = 0.00032;  ///< output interval [s]
  sim::CvodeOptions solver = DriveChainSetup::defaultSolver();
  void validate() const;
};

class RobotR3Axis : public sim::HeldInputPlant {
 public:
  explicit RobotR3Axis(RobotR3AxisSetup setup);

  /// The run's state: the mode of the motor-side bearing friction (discrete state, saved). No workspace: the
  /// right-hand side works on scalars.
  struct State : sim::PlantStateOf<State> {
    explicit State(const RobotR3Axis& axis);
    FrictionMode mode = FrictionMode::Stuck;
    sim::HeldInputs inputs;  ///< the input ports' values (saved)
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }

  const RobotR3AxisSetup& setup() const { return s_; }
  /// Input ports (sim::InputPort): `<prefix>.current` [A], the current reference held in place of the controller's
  /// (its PI frozen; in effect once set), and `<prefix>.load_torque` [N·m], an external torque on the load (0 until
  /// set; its work is not in the energy columns).
  std::vector<sim::InputPort> inputPorts() const override { return ports_; }
  // setInput, input, inputActive, setInputProfile, releaseInput: sim::HeldInputPlant.
  /// t_end = endTime(), outputs every log_interval (also the max step when the solver sets none).
  sim::SimulateOptions simulateOptions() const;
  static constexpr int kStates = 11;  // q, qd, phi_rel, w_rel, x, v_C, i, W_el, E_R, E_d, E_f
  /// Stored energy at y: ½ J_L q̇² + ½ J ω_m² + ½ c φ_rel² + ½ La i² [J].
  double storedEnergy(const Eigen::Ref<const Eigen::VectorXd>& y) const;
  /// The bearing friction's mode in `state` (a state of this plant).
  FrictionMode mode(const sim::PlantState& state) const;
  double endTime() const;  ///< termination time: path end + swing, capped at the stop time

  std::string name() const override;
  int stateSize() const override { return kStates; }
  Eigen::VectorXd initialState() const override;
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  int rootCount() const override { return 2; }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  /// The path's segment switches.
  std::vector<double> timeEvents(double t_end) const override;
  /// The friction mode consistent with y at t (the event iteration with no flags).
  void start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    updateModes(state, t, y, {});
  }
  /// Event iteration after a located root (or at t = 0 with no flags).
  void updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   const std::vector<int>& fired) const override;
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> row) const override;

  /// Algebraic quantities at (t, y) for the mode in `state`.
  struct Eval {
    double q_ref, qd_ref, xdot, i_ref, tau_s, tau_f, wm, wm_dot, qdd, stuck_torque;  // xdot: the PI state's rate
  };
  Eval evaluate(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;

 protected:
  sim::HeldInputs& heldInputs(sim::PlantState& state) const override { return own<State>(state).inputs; }
  const sim::HeldInputs& heldInputs(const sim::PlantState& state) const override { return own<State>(state).inputs; }
  bool alwaysActive(int port) const override;

 private:
  Eval evaluateIn(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;  // at st.mode
  RobotR3AxisSetup s_;
  drive::OpAmpMotor motor_;
  control::JointController controller_;  ///< the TorqueCascade (kp, ks, Ts), its output the current reference [A]
  control::KinematicPtpTrajectory path_;
  std::vector<std::string> signals_;
};

}  // namespace jointsim::systems
