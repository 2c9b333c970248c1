#pragma once
/// \file
/// The one seam between simulated models and the integrator: every model that jointsim simulates (robot with
/// drives, joint rig, drive chain, RobotR3 axis and robot, clamped robot, passive robot, or a user's own)
/// implements sim::Plant, and sim::simulate() (simulate.hpp) runs any of them.
///
/// A plant is a hybrid system
///   ẏ = f(t, y; m, u_held)        continuous states y (stateSize() of them)
///   g(t, y; m) = 0                 root functions (rootCount()), located by CVODE; at a root the plant updates
///                                   its discrete modes m (e.g. MSL stick–slip friction) in updateModes()
///   t_e ∈ timeEvents(t_end)        known input discontinuities (profile breakpoints, path segments); the
///                                   integrator never steps across one and is restarted there
///   t_k = k·T_s                    an optional sampled (discrete-time) part, updated by sample() every
///                                   samplePeriod() seconds (zero-order hold of a digital controller)
/// with named output signals (signalNames(), `name[unit]`, SI units) evaluated by signals().
///
/// Model and state (as mjModel/mjData in MuJoCo, System/Context in Drake): a Plant is constant once built and may
/// be shared between threads and simulators; everything that changes during a run besides the time and the
/// continuous state y — held inputs and command-port choices, sampled controllers' states and sample phase, sensor
/// memory, the random generator, hybrid modes, the faults' applied values — lives in a PlantState made by
/// makeState(), together with the workspace of the right-hand side. A simulator owns one state per run.
///
/// Contract: derivatives(), roots(), jacobian() and signals() are pure functions of (t, y) and of the discrete
/// state in `state`; they may use the state's workspace but must not allocate on the heap, so that CVODE can call
/// and difference them freely. The discrete state changes only in start(), updateModes(), sample() and by a
/// plant's input setters, which the simulators follow by a restart (or a kept history, at an input jump).

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/common/bytes.hpp"
#include "jointsim/control/profile.hpp"
#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

class Plant;

/// One named input of a plant: a value set between steps and held until changed (zero-order hold), e.g. a command
/// port of a drive or a joint rig's command. Set through Plant::setInput() in a run's state; a change restarts the
/// integrator at that time (PlantState::inputsChanged).
struct InputPort {
  std::string name;  ///< unique in the plant, e.g. "elbow_joint.voltage", "elbow_joint.q", "command"
  std::string unit;  ///< SI unit, e.g. "V", "rad/s", "N·m"
  double min = -std::numeric_limits<double>::infinity();  ///< admissible values: min <= value <= max, finite
  double max = std::numeric_limits<double>::infinity();
  std::string description;  ///< one line: what the value is and where it enters
  /// Inputs of one group are alternatives (the command ports of a joint's drive): setting one makes its `mode` the
  /// group's active one (with a bumpless switch where the plant has one). Empty: an independent input.
  std::string group;
  std::string mode;  ///< the mode of its group this input belongs to, e.g. "voltage", "setpoint" (for q, qd, qdd)
};

/// Everything about one run of a plant that changes, apart from the time and the continuous state: made by
/// Plant::makeState(), owned by a simulator, copied (clone) for snapshots, saved as bytes. A plant's own state
/// type derives from PlantStateOf<...> and adds its discrete state (saved by save()/load()) and its workspace
/// (mutable; not saved: it holds nothing between calls).
class PlantState {
 public:
  explicit PlantState(const Plant& owner);
  virtual ~PlantState() = default;
  /// The plant that made this state (it must outlive the state's use); a plant refuses a state of another plant.
  const Plant& owner() const { return *owner_; }
  /// The identity of that plant (Plant::id): unique in the process, also after the plant is gone.
  std::uint64_t ownerId() const { return owner_id_; }
  /// A deep copy: an independent state with the same values.
  virtual std::unique_ptr<PlantState> clone() const = 0;
  /// The discrete state as bytes (ByteWriter, common/bytes.hpp).
  virtual void save(ByteWriter& /*out*/) const {}
  /// Reads what save() wrote; on InputError (bytes of another plant or configuration) the state is unspecified and
  /// the caller discards it (sim::Simulator loads into a copy).
  virtual void load(ByteReader& /*in*/) {}
  /// Counts changes of the inputs set between steps (command ports, held commands, wrenches): a plant's input
  /// setters call inputsChanged() when a value actually changes; the simulator then calls Plant::applyInputs() and
  /// restarts the integrator (the right-hand side jumps there), and only then.
  long inputRevision() const { return revision_; }
  void inputsChanged() { ++revision_; }

 protected:
  PlantState(const PlantState&) = default;
  PlantState& operator=(const PlantState&) = default;

 private:
  const Plant* owner_;
  std::uint64_t owner_id_;
  long revision_ = 0;
};

/// Base of a plant's own state type `Derived` (copyable): clone() by its copy constructor.
template <class Derived>
class PlantStateOf : public PlantState {
 public:
  using PlantState::PlantState;
  std::unique_ptr<PlantState> clone() const override {
    return std::make_unique<Derived>(static_cast<const Derived&>(*this));
  }
};

/// A state without discrete parts (a plant with nothing but continuous states).
class EmptyPlantState final : public PlantStateOf<EmptyPlantState> {
 public:
  using PlantStateOf::PlantStateOf;
};

/// What a plant's Jacobian is made of (Plant::jacobian; CvodeOptions::analytic_jacobian).
enum class JacobianKind {
  /// Difference quotients only (organised by the plant's structure: equal to plain ones to rounding). BDF's default:
  /// the shipped calibrations were made with it, and BDF's results depend on its Jacobian within the tolerances.
  Differences,
  /// Analytic parts where the plant has them (the robot with drives: the multibody's columns from the analytic ABA
  /// derivatives, O(n²) instead of 2n right-hand sides). Always for the fixed-step method.
  Analytic,
};

class Plant {
 public:
  Plant();
  /// A copy is another plant: a new id, not frozen (its states are not the original's).
  Plant(const Plant& other);
  Plant& operator=(const Plant& other);
  virtual ~Plant() = default;

  /// Unique among the plants of the process (a copy gets a new one): a state belongs to the plant of its id, which a
  /// plant made later at the same address does not have.
  std::uint64_t id() const { return id_; }
  /// Called by the simulators when they start using the plant: from then on it is shared by them, and a plant's
  /// configuration setters (e.g. systems::RobotSystem::setTrajectory) refuse to change it (checkConfigurable).
  void freeze() const { frozen_.store(true, std::memory_order_relaxed); }
  bool frozen() const { return frozen_.load(std::memory_order_relaxed); }

  /// Name of the simulated system for messages, e.g. "joint rig 'kr300'" (the component of a SolverError).
  virtual std::string name() const = 0;
  /// Number of continuous states n (> 0).
  virtual int stateSize() const = 0;
  /// Initial state y(0) (size n).
  virtual Eigen::VectorXd initialState() const = 0;
  /// A fresh state for a run (inputs at their defaults); start() then makes it consistent with y at t0.
  virtual std::unique_ptr<PlantState> makeState() const { return std::make_unique<EmptyPlantState>(*this); }
  /// ẏ = f(t, y) for the discrete state in `state`; writes all n entries of `ydot`.
  virtual void derivatives(const PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> ydot) const = 0;

  /// Number of root functions (0: none).
  virtual int rootCount() const { return 0; }
  /// Root functions g(t, y) (size rootCount()); a sign change is an event.
  virtual void roots(const PlantState& /*state*/, double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                     Eigen::Ref<Eigen::VectorXd> /*g*/) const {}
  /// Input discontinuities in (0, t_end) [s] (any order, duplicates allowed).
  virtual std::vector<double> timeEvents(double /*t_end*/) const { return {}; }
  /// Sets the initial discrete state (modes, first controller sample) consistent with y at t0. Keeps the inputs
  /// set in `state` (command ports, held commands).
  virtual void start(PlantState& /*state*/, double /*t0*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/) const {}
  /// Discrete update at a located root (`fired`: CVODE's direction per root function, +1 rising, −1 falling,
  /// 0 none) or at a time event (`fired` empty).
  virtual void updateModes(PlantState& /*state*/, double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                           const std::vector<int>& /*fired*/) const {}
  /// Period of the sampled part [s]; 0: none.
  virtual double samplePeriod() const { return 0.0; }
  /// One update of the sampled part at t = k·samplePeriod() (measure, compute, hold).
  virtual void sample(PlantState& /*state*/, double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/) const {}
  /// Called by sim::Simulator at time t after the state's inputRevision() changed, before the restart: the plant
  /// may set its states for the new inputs (e.g. controller integrators for a bumpless switch of a command port).
  virtual void applyInputs(PlantState& /*state*/, double /*t*/, Eigen::Ref<Eigen::VectorXd> /*y*/) const {}

  /// A Jacobian of its own (jacobian(), jacobianStructure()) that the simulators use for BDF (unless
  /// CvodeOptions::plant_jacobian is false).
  virtual bool providesJacobian() const { return false; }
  /// J = ∂f/∂y at (t, y) with f = f(t, y), J zero on entry (inside jacobianStructure(); outside it never read);
  /// `inc` holds the difference increment CVODE would use per state (DifferenceJacobianFunction); `kind` says whether
  /// analytic parts may replace differences (a plant without any ignores it). Pure like derivatives(); must respect
  /// jacobianStructure().
  virtual void jacobian(const PlantState& /*state*/, double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*f*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*inc*/, Eigen::Ref<Eigen::MatrixXd> /*J*/,
                        JacobianKind /*kind*/) const {}
  /// Block structure of the Jacobian (empty: dense).
  virtual JacobianStructure jacobianStructure() const { return {}; }
  /// True when derivatives() does not depend on t itself for this state, between its time events and samples (f is
  /// f(y) there: held inputs, no reference or profile of time): the fixed-step method then takes ∂f/∂t = 0 instead of
  /// differencing it (one right-hand side per Jacobian). False, the default, is always safe.
  virtual bool timeInvariant(const PlantState& /*state*/) const { return false; }
  /// The states whose rows the fixed-step method takes with γ = 1 − 1/√2 under `oscillations: resolve`
  /// (CvodeOptions::resolve_oscillations): those of lightly damped oscillatory modes that a step should follow rather
  /// than damp (a drive train's motor, current and gear states, the joint angles), not those where stiff real modes
  /// and growing modes act (friction bristles, the joint velocities that friction and the gear torques drive).
  /// Default: none (the fixed step then refuses the option). CVODE ignores them.
  virtual std::vector<int> oscillatoryStates() const { return {}; }

  /// What continuous state `i` is, for messages ("q_elbow_joint [rad]"); empty when the plant does not say.
  virtual std::string stateName(int /*i*/) const { return {}; }
  /// True for a state that may grow without bound in normal use (the angle of a joint or motor that keeps turning),
  /// which a divergence bound (sim::AdvanceLimits::max_state) must therefore not apply to.
  virtual bool unboundedState(int /*i*/) const { return false; }

  /// The inputs a user may set between steps (InputPort); empty for a plant without inputs.
  virtual std::vector<InputPort> inputPorts() const { return {}; }
  /// Sets input `port` (index in inputPorts()) in `state` to `value` and makes its mode the active one of its group.
  /// \throws InputError (nothing changed) for a port out of range, a value outside [min, max] or not finite.
  virtual void setInput(PlantState& state, int port, double value) const;
  /// The value of input `port` in `state`: the last one set, else the plant's default (0 unless documented).
  virtual double input(const PlantState& state, int port) const;
  /// Whether input `port` is in effect in `state`: its mode is its group's active one (an independent input: true).
  virtual bool inputActive(const PlantState& /*state*/, int /*port*/) const { return true; }
  /// Drives input `port` by a profile of time [the port's unit] from the start of every run, until a value set at the
  /// port holds it instead (a disturbance torque over time, a current reference from a file: the experiment files'
  /// `inputs:` key). A configuration of the plant: only before a simulator uses it. The profile's breakpoints become
  /// time events. \throws InputError for a plant whose ports take no profiles (the default), a port out of range or
  /// one of a group.
  virtual void setInputProfile(int port, const control::Profile& profile);
  /// Input `port` no longer held in `state`: back to the model's own source (its profile, controller or 0).
  /// \throws InputError for a port out of range or one that cannot be released (the default).
  virtual void releaseInput(PlantState& state, int port) const;

  /// Output signals as `name[unit]` (the CSV column names after "time[s]").
  virtual const std::vector<std::string>& signalNames() const = 0;
  /// Values of the output signals at (t, y), in signalNames() order (size signalNames().size()).
  virtual void signals(const PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       Eigen::Ref<Eigen::VectorXd> out) const = 0;

 protected:
  /// `state` as this plant's own state type S (InputError when it was made by another plant).
  template <class S>
  const S& own(const PlantState& state) const {
    if (state.ownerId() != id_) foreignState();
    return static_cast<const S&>(state);
  }
  template <class S>
  S& own(PlantState& state) const {
    if (state.ownerId() != id_) foreignState();
    return static_cast<S&>(state);
  }
  /// InputError naming `setter` once the plant is frozen (in use by a simulator).
  void checkConfigurable(const char* setter) const;

 private:
  [[noreturn]] void foreignState() const;
  std::uint64_t id_;
  mutable std::atomic<bool> frozen_{false};
};

/// Index of the input called `name` in plant.inputPorts(); throws InputError naming the plant and listing its inputs
/// when absent.
int inputIndex(const Plant& plant, const std::string& name);

/// Index of the signal called `name` (without or with its `[unit]`) in plant.signalNames(); throws InputError
/// naming the plant and listing the signals when absent.
int signalIndex(const Plant& plant, const std::string& name);

}  // namespace jointsim::sim
