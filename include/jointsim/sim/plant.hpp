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
/// Contract: derivatives(), roots() and signals() are pure functions of (t, y) and of the discrete state the
/// plant holds (modes, held inputs); they may use mutable workspace but must not allocate on the heap, so
/// that CVODE can call and difference them freely. The discrete state changes only in start(),
/// updateModes() and sample(), which sim::simulate() calls at the event times and follows by a restart of
/// the integrator.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

class Plant {
 public:
  virtual ~Plant() = default;

  /// Name of the simulated system for messages, e.g. "joint rig 'kr300'" (the component of a SolverError).
  virtual std::string name() const = 0;
  /// Number of continuous states n (> 0).
  virtual int stateSize() const = 0;
  /// Initial state y(0) (size n).
  virtual Eigen::VectorXd initialState() const = 0;
  /// ẏ = f(t, y) for the current discrete state; writes all n entries of `ydot`.
  virtual void derivatives(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> ydot) const = 0;

  /// Number of root functions (0: none).
  virtual int rootCount() const { return 0; }
  /// Root functions g(t, y) (size rootCount()); a sign change is an event.
  virtual void roots(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                     Eigen::Ref<Eigen::VectorXd> /*g*/) const {}
  /// Input discontinuities in (0, t_end) [s] (any order, duplicates allowed).
  virtual std::vector<double> timeEvents(double /*t_end*/) const { return {}; }
  /// Sets the initial discrete state (modes, first controller sample) consistent with y at t0.
  virtual void start(double /*t0*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/) {}
  /// Discrete update at a located root (`fired`: CVODE's direction per root function, +1 rising, −1 falling,
  /// 0 none) or at a time event (`fired` empty).
  virtual void updateModes(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                           const std::vector<int>& /*fired*/) {}
  /// Period of the sampled part [s]; 0: none.
  virtual double samplePeriod() const { return 0.0; }
  /// One update of the sampled part at t = k·samplePeriod() (measure, compute, hold).
  virtual void sample(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/) {}

  /// Inputs set between steps (command ports; sim::Simulator). A plant with such inputs increments this counter
  /// whenever an input value actually changes; the simulator then calls applyInputs() and restarts the
  /// integrator (the right-hand side jumps there), and only then.
  virtual long inputRevision() const { return 0; }
  /// Called by sim::Simulator at time t after inputRevision() changed, before the restart: the plant may set its
  /// states for the new inputs (e.g. controller integrators for a bumpless switch of a command port).
  virtual void applyInputs(double /*t*/, Eigen::Ref<Eigen::VectorXd> /*y*/) {}

  /// A Jacobian of its own (jacobian(), jacobianStructure()) that the simulators use for BDF (unless
  /// CvodeOptions::plant_jacobian is false).
  virtual bool providesJacobian() const { return false; }
  /// J = ∂f/∂y at (t, y) with f = f(t, y), J zero on entry; `inc` holds the difference increment CVODE would use
  /// per state (DifferenceJacobianFunction). Pure like derivatives(); must respect jacobianStructure().
  virtual void jacobian(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*f*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*inc*/, Eigen::Ref<Eigen::MatrixXd> /*J*/) const {}
  /// Block structure of the Jacobian (empty: dense).
  virtual JacobianStructure jacobianStructure() const { return {}; }

  /// What continuous state `i` is, for messages ("q_elbow_joint [rad]"); empty when the plant does not say.
  virtual std::string stateName(int /*i*/) const { return {}; }
  /// True for a state that may grow without bound in normal use (the angle of a joint or motor that keeps turning),
  /// which a divergence bound (sim::AdvanceLimits::max_state) must therefore not apply to.
  virtual bool unboundedState(int /*i*/) const { return false; }

  /// Output signals as `name[unit]` (the CSV column names after "time[s]").
  virtual const std::vector<std::string>& signalNames() const = 0;
  /// Values of the output signals at (t, y), in signalNames() order (size signalNames().size()).
  virtual void signals(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> out) const = 0;
};

/// Index of the signal called `name` (without or with its `[unit]`) in plant.signalNames(); throws InputError
/// naming the plant and listing the signals when absent.
int signalIndex(const Plant& plant, const std::string& name);

}  // namespace jointsim::sim
