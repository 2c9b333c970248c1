#pragma once
/// \file
/// One-dimensional rotational drive chain (generalises the joint rig): rigid inertias joined by elements —
/// linear spring–damper, elasto-backlash, clutch between two inertias, brake or bearing friction to ground —
/// and driven by torque sources. Friction elements follow the Modelica PartialFriction semantics exactly
/// ([MSL, Rotational.Interfaces.PartialFriction]): modes stuck / start forward / start backward / forward /
/// backward / free; while stuck the relative acceleration is constrained to zero and the friction torque comes
/// from the torque balance of the whole chain (all stuck elements solved together); mode switches are located
/// by CVODE root functions and the integrator is re-initialised at every event.
///
/// Two-flange conventions (MSL): an element joins input node `a` and output node `b` (−1 = ground);
/// φ_rel = φ_b − φ_a, w_rel = ω_b − ω_a; its torque τ acts with +τ on the input body and −τ on the output
/// body. A torque source applies +τ(t) to its node `b`. An ideal gear (MSL IdealGear) couples two inertias
/// by φ_a = ratio·φ_b: it is a kinematic constraint solved together with the stuck friction elements; it
/// exerts τ on the input and −ratio·τ on the output (lossless). Initial states must satisfy it.

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/control/profile.hpp"
#include "jointsim/drive/msl_friction.hpp"
#include "jointsim/drive/parameters.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/sim/held_inputs.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::systems {

using drive::FrictionMode;

struct ChainInertia {
  std::string name;
  double J = 1.0;     ///< inertia [kg·m²], > 0
  double phi0 = 0.0;  ///< initial angle [rad]
  double w0 = 0.0;    ///< initial speed [rad/s]
};

enum class ChainElementType { SpringDamper, ElastoBacklash, Clutch, Brake, BearingFriction, TorqueSource, Gear };

struct ChainElement {
  std::string name;
  ChainElementType type = ChainElementType::SpringDamper;
  int a = -1;  ///< input node: inertia index, −1 = ground
  int b = -1;  ///< output node
  // SpringDamper / ElastoBacklash
  double c = 0.0;         ///< stiffness [N·m/rad]
  double d = 0.0;         ///< damping [N·m·s/rad]
  double backlash = 0.0;  ///< total backlash b [rad]
  // Clutch / Brake: fn = fn_max · normalized(t); sliding torque cgeo·fn·μ(|w|); τ0 = cgeo·fn·μ(0)
  double fn_max = 0.0;                                            ///< maximum normal force [N]
  control::Profile normalized = control::Profile::constant(1.0);  ///< normalised normal force [-]
  double cgeo = 1.0;                                              ///< geometry constant [m]
  // BearingFriction: sliding torque f(v) from the table directly [N·m]
  std::vector<std::array<double, 2>> table{{{0.0, 0.5}}};  ///< μ(v) [-] (clutch, brake) or f(v) [N·m] (bearing)
  double peak = 1.0;                                       ///< stiction factor, τ0max = peak·τ0, >= 1
  // TorqueSource
  control::Profile torque = control::Profile::constant(0.0);  ///< [N·m]
  // Gear: ideal, lossless, φ_a = ratio·φ_b; its torque is the constraint torque on the input flange [N·m]
  double ratio = 1.0;
  bool isFriction() const;
  /// Parameter table (drive/parameters.hpp; keys as in a drive_chain file's element): c (role stiffness) and d of a
  /// spring–damper or elasto-backlash element, its backlash (role backlash), a friction element's table values
  /// (`mu[i][1]` of a clutch or brake, `tau_pos[i][1]` of a bearing: role coulomb), fn_max, peak; empty for a torque
  /// source or gear.
  std::vector<drive::ParameterInfo> parameters() const;
  /// A copy with `changes` applied by the keys of parameters(). InputError naming the element and the key.
  ChainElement withParameters(const drive::ParameterChanges& changes) const;
};

struct DriveChainSetup {
  std::string name = "chain";
  std::vector<ChainInertia> inertias;
  std::vector<ChainElement> elements;
  double duration = 1.0;   ///< [s]
  double log_rate = 1000;  ///< [Hz]
  sim::CvodeOptions solver = defaultSolver();
  static sim::CvodeOptions defaultSolver();  ///< BDF order ≤ 2, rtol 1e-6, atol 1e-8
  void validate() const;
};

/// The drive chain as a plant: modes of the friction elements as discrete state (in its State), two root
/// functions per element (friction switching, elasto-backlash contact edges) and one per clutch or brake (its normal
/// force), the torque sources' and normal
/// forces' breakpoints as time events. Constant once built (sim::Plant): the run's modes and the workspace of the
/// right-hand side live in DriveChain::State.
class DriveChain : public sim::HeldInputPlant {
 public:
  /// The run's state: the friction modes (discrete state, saved) and the workspace of the right-hand side.
  struct State : sim::PlantStateOf<State> {
    /// Modes all Stuck (start() sets them from the initial speeds); the workspace sized for `chain`, so that
    /// derivatives(), roots() and signals() allocate nothing.
    explicit State(const DriveChain& chain);
    /// MSL friction mode per element (meaningful for the friction elements only).
    std::vector<FrictionMode> modes;
    // Workspace (mutable: the right-hand side is const; not saved, holds nothing between calls).
    mutable Eigen::VectorXd acc;     ///< angular accelerations of the inertias [rad/s²]
    mutable Eigen::VectorXd tau_el;  ///< element torques [N·m]
    mutable Eigen::VectorXd known;   ///< torque sums on the inertias [N·m]
    mutable Eigen::MatrixXd A;       ///< constraint matrix of the stuck elements and gears
    mutable Eigen::VectorXd rhs;     ///< its right-hand side, then the constraint torques [N·m]
    mutable std::vector<int> stuck;  ///< elements of the active constraints (first n_stuck entries; sized once)
    mutable int n_stuck = 0;
    sim::HeldInputs inputs;  ///< the input ports' values (saved)
    void save(ByteWriter& out) const override;
    void load(ByteReader& in) override;
  };

  explicit DriveChain(DriveChainSetup setup);
  const DriveChainSetup& setup() const { return s_; }
  /// t_end = duration, outputs at log_rate, its solver with max_step = one log interval when 0.
  sim::SimulateOptions simulateOptions() const;
  /// Friction modes of the run `state` (one per element).
  const std::vector<FrictionMode>& modes(const sim::PlantState& state) const;

  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  std::string name() const override;
  int stateSize() const override { return 2 * static_cast<int>(s_.inertias.size()); }
  Eigen::VectorXd initialState() const override;
  /// Initial modes (MSL initialization rules: sliding where the element moves, then the event iteration).
  void start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const override;
  /// Event iteration at time t: `fired[k]` marks root functions that crossed.
  void updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   const std::vector<int>& fired) const override;
  /// ẏ for the modes in `state` (pure given the modes; no heap allocation).
  void derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) const override;
  /// Two per element (friction switching, elasto-backlash contact edges), then one per clutch or brake: its
  /// normal force, so that it goes free where fn crosses zero ([MSL] free = fn <= 0) and engages again there.
  int rootCount() const override { return root_count_; }
  void roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override;
  const std::vector<std::string>& signalNames() const override { return signals_; }
  void signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> row) const override;
  /// Input ports (sim::InputPort): per torque source `<source>` [N·m], its torque held in place of its profile (in
  /// effect once set); per inertia `<inertia>.load_torque` [N·m], an external torque on it (0 until set).
  std::vector<sim::InputPort> inputPorts() const override { return ports_; }
  // setInput, input, inputActive, setInputProfile, releaseInput: sim::HeldInputPlant.

  /// Friction/compliant torque of element e at the modes in `state` [N·m].
  double elementTorque(const sim::PlantState& state, int e, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;

 protected:
  /// The torque sources' and normal forces' breakpoints (timeEvents() adds the input profiles' jumps:
  /// sim::HeldInputPlant).
  std::vector<double> modelTimeEvents(double t_end) const override;
  sim::HeldInputs& heldInputs(sim::PlantState& state) const override { return own<State>(state).inputs; }
  const sim::HeldInputs& heldInputs(const sim::PlantState& state) const override { return own<State>(state).inputs; }
  bool alwaysActive(int port) const override;

 private:
  void solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const;  // fills acc, tau_el
  double tau0(int e, double t) const;
  double normalForce(int e, double t) const;              // fn of a clutch or brake [N]; 1 for a bearing
  double slidingTorque(int e, double t, double w) const;  // signed: opposes w
  double relSpeed(int e, const Eigen::Ref<const Eigen::VectorXd>& y) const;
  double relAccel(const State& st, int e) const;
  DriveChainSetup s_;
  std::vector<std::string> signals_;
  /// Per element: its contact law when it is an elasto-backlash element (made once, not in the right-hand side).
  std::vector<std::shared_ptr<const drive::ElastoBacklash>> backlash_;
  std::vector<int> normal_slot_;  ///< per element: the root slot of its normal force, −1: none
  std::vector<int> source_port_;  ///< per element: its input port when it is a torque source, −1 otherwise
  std::vector<int> load_port_;    ///< per inertia: its load-torque port
  int root_count_ = 0;
};

}  // namespace jointsim::systems
