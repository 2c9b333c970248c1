#pragma once
/// \file
/// Runs an experiment described by a YAML file (the library side of `jointsim run`): dispatches on
/// `experiment.type`, writes `<output_dir>/<name>.csv` and `<output_dir>/summary.json`.
/// Experiment types: `passive_robot` (passive_robot.hpp) and `joint_rig` (joint_rig.hpp); the file
/// formats are described in docs/experiments.md.

#include <string>
#include <vector>

#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/sim/faults.hpp"

namespace jointsim::experiments {

struct RunOptions {
  std::string output_dir;              ///< empty: out/<experiment name>/ relative to the working directory
  std::vector<std::string> overrides;  ///< "key.path=value" (e.g. "load.inertia=2", "input.profile.values[1]=3")
  /// Faults injected into the drives (sim/faults.hpp); only experiments with a robot with drives
  /// (`tracking`) accept them, the others reject a non-empty list with InputError.
  std::vector<sim::Fault> faults;
  /// Progress on stderr (simulated time, real-time factor, ETA) for runs longer than ~2 s; the CLI sets it
  /// when stderr is a terminal.
  bool progress = false;
};

struct RunReport {
  std::string experiment;         ///< experiment name
  std::string status;             ///< "ok" or "failed"
  std::string csv_path;           ///< log file written (empty when failed)
  std::string summary_path;       ///< summary.json written
  double sim_time_s = 0.0;        ///< simulated time [s]
  double wall_time_s = 0.0;       ///< wall-clock time [s]
  double real_time_factor = 0.0;  ///< sim_time_s / wall_time_s
  sim::SolverStats stats;
};

/// Loads, validates and runs the experiment. Bad input: InputError (nothing written). Solver failure:
/// summary.json with status "failed" and the reason is written, no CSV, and the SolverError rethrown.
RunReport runExperimentFile(const std::string& config_path, const RunOptions& options = {});

}  // namespace jointsim::experiments
