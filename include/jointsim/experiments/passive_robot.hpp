#pragma once
/// \file
/// Passive robot experiment: a rigid robot moving under gravity with no actuation (optionally with
/// viscous joint damping). The main demo job ("the UR5 falling") and the energy-conservation check of
/// the multibody core with CVODE.

#include <functional>
#include <string>
#include <vector>

#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::experiments {

struct PassiveRobotParams {
  std::string name = "passive_robot";  ///< experiment name (output file names)
  Eigen::VectorXd q0;                  ///< (nq) initial joint positions [rad or m]; empty = zeros
  Eigen::VectorXd qd0;                 ///< (nq) initial joint velocities [rad/s or m/s]; empty = zeros
  Eigen::VectorXd damping;             ///< (nq) viscous joint damping [N·m·s/rad or N·s/m]; empty = zeros
  double duration = 1.0;               ///< simulated time [s], > 0
  double log_rate = 1000.0;            ///< log samples per second [Hz], > 0
  sim::CvodeOptions solver = defaultSolver();  ///< integrator settings

  /// Adams (non-stiff: a rigid robot has no fast modes) with tight tolerances.
  static sim::CvodeOptions defaultSolver();
  /// Throws InputError when a value is out of range or a vector has the wrong size for `model`.
  void validate(const multibody::Model& model) const;
};

/// Names of the logged columns, `name[unit]`: time, q_i, qd_i per joint (joint names), kinetic,
/// potential and total energy, and the tip frame position.
std::vector<std::string> passiveRobotColumns(const multibody::Model& model);

struct PassiveRobotResult {
  sim::SolverStats stats;
  double sim_time_s = 0.0;   ///< simulated time reached [s]
  double wall_time_s = 0.0;  ///< wall-clock time of the integration [s]
  size_t samples = 0;        ///< rows given to the sink
};

/// Simulates and hands every log row (in passiveRobotColumns order, first row at t = 0) to `sink`.
/// Throws SolverError (with the simulated time) if CVODE fails.
PassiveRobotResult simulatePassiveRobot(const multibody::Model& model, const PassiveRobotParams& params,
                                        const std::function<void(const Eigen::VectorXd& row)>& sink);

}  // namespace jointsim::experiments
