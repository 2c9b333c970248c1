#pragma once
/// \file
/// Passive robot: a rigid robot moving under gravity with no actuation (optionally with viscous joint
/// damping and end stops at the joint limits, systems/joint_limits.hpp). The main demo job ("the UR5 falling")
/// and the energy-conservation check of the multibody core with CVODE. State y = [q, q̇];
/// ẏ = [q̇, ABA(q, q̇, −b q̇ + τ_stop(q, q̇))].
/// No discrete state: the plant's State (makeState()) holds only the workspace of the right-hand side.

#include <memory>
#include <string>
#include <vector>

#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/systems/joint_limits.hpp"

namespace jointsim::systems {

struct PassiveRobotParams {
  std::string name = "passive_robot";          ///< experiment name (output file names)
  Eigen::VectorXd q0;                          ///< (nq) initial joint positions [rad or m]; empty = zeros
  Eigen::VectorXd qd0;                         ///< (nq) initial joint velocities [rad/s or m/s]; empty = zeros
  Eigen::VectorXd damping;                     ///< (nq) viscous joint damping [N·m·s/rad or N·s/m]; empty = zeros
  double duration = 1.0;                       ///< simulated time [s], > 0
  double log_rate = 1000.0;                    ///< log samples per second [Hz], > 0
  sim::CvodeOptions solver = defaultSolver();  ///< integrator settings
  JointLimitSettings joint_limits;             ///< ignore, warn (default) or stop (end stops)

  /// Adams (non-stiff: a rigid robot has no fast modes) with tight tolerances.
  static sim::CvodeOptions defaultSolver();
  /// Throws InputError when a value is out of range or a vector has the wrong size for `model`.
  void validate(const multibody::Model& model) const;
};

class PassiveRobot : public sim::HeldInputPlant {
 public:
  /// Validates `params` against `model` (InputError).
  PassiveRobot(multibody::Model model, PassiveRobotParams params);

  /// The run's state: workspace only (mutable, holds nothing between calls, nothing to save), sized here so that
  /// derivatives() and signals() do not allocate.
  struct State : sim::PlantStateOf<State> {
    explicit State(const PassiveRobot& robot);
    mutable multibody::Data data, log_data;  // right-hand side; signals()
    mutable Eigen::VectorXd tau, tau_stop;   // joint torques, end-stop torques [N·m or N]
    sim::HeldInputs inputs;                  ///< the joint torques set at the input ports (saved)
    void save(ByteWriter& out) const override { inputs.save(out); }
    void load(ByteReader& in) override { inputs.load(in); }
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }

  const multibody::Model& model() const { return model_; }
  const PassiveRobotParams& params() const { return p_; }
  /// t_end = duration, outputs at log_rate, the solver as given (no step limit: the right-hand side is smooth
  /// and valid beyond the end, so the last step may overshoot and the last rows are interpolated).
  sim::SimulateOptions simulateOptions() const;

  std::string name() const override;
  int stateSize() const override { return 2 * model_.nq; }
  Eigen::VectorXd initialState() const override;
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  /// End stops (mode stop): q − q_upper and q_lower − q per limited joint.
  int rootCount() const override { return stops_.rootCount(); }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  const EndStops& endStops() const { return stops_; }
  /// Input ports (sim::InputPort): per joint `<joint>.torque` [N·m, or N for a prismatic joint], a torque applied at
  /// the joint (0 until set; its work is not in the logged energies).
  std::vector<sim::InputPort> inputPorts() const override { return ports_; }
  // setInput, input, inputActive, setInputProfile, releaseInput, timeEvents (the profiles' jumps): sim::HeldInputPlant.
  /// q_i, qd_i per joint (joint names), kinetic, potential and total energy [J], tip frame position [m]; with
  /// end stops also the energy stored in them (end_stop_energy [J], included in total_energy) and the torque
  /// of each stop (end_stop_torque_<joint> [N·m or N]).
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override;

 protected:
  sim::HeldInputs& heldInputs(sim::PlantState& state) const override { return own<State>(state).inputs; }
  const sim::HeldInputs& heldInputs(const sim::PlantState& state) const override { return own<State>(state).inputs; }

 private:
  multibody::Model model_;
  PassiveRobotParams p_;
  Eigen::VectorXd damping_;
  EndStops stops_;
  int tip_ = 0;
  std::vector<std::string> signals_;
};

}  // namespace jointsim::systems
