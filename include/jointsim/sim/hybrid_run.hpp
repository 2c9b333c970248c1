#pragma once
/// \file
/// Driver for hybrid systems (continuous states plus discrete modes, e.g. stick–slip friction): CVODE
/// integrates with root functions; at every located root or time event the model updates its modes and
/// the integrator is re-initialised; a stop time keeps every step from crossing a time event; outputs
/// are taken on a grid. Shared by the drive chain and the RobotR3 models.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

struct HybridSystem {
  int n_states = 0;
  int n_roots = 0;
  RhsFunction rhs;
  RootFunction roots;
  /// Discrete update at an event: `fired` are CVODE's root directions (empty for a time event).
  std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, const std::vector<int>& fired)> on_event;
  /// Called at t = 0 and at every output time.
  std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y)> output;
};

struct HybridRunSettings {
  double t_end = 1.0;               ///< end of the run [s]
  std::vector<double> time_events;  ///< input discontinuities [s]; those outside (0, t_end) are ignored
  /// Time of output k >= 1 [s] (the caller clamps it to t_end). When empty, outputs are at
  /// min(t_end, k · output_interval).
  std::function<double(long k)> output_time;
  /// Output grid spacing [s], used when output_time is empty; it is also the default max step
  /// (options.max_step == 0), so that no step jumps over a logged sample.
  double output_interval = 0.0;
  long n_outputs = 0;               ///< outputs after t = 0; 0: until an output time reaches t_end
  long max_events_per_output = 100000;  ///< more events than this between two outputs: chattering error
};

struct HybridRunResult {
  SolverStats stats;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  size_t events = 0;
};

/// Runs from t = 0 with state y0 (the caller has already set the initial modes).
/// Throws SolverError on solver failure or event chattering (flag EVENT_CHATTERING, options.component).
HybridRunResult runHybrid(const HybridSystem& system, const CvodeOptions& options, const Eigen::VectorXd& y0,
                          const HybridRunSettings& settings);

}  // namespace jointsim::sim
