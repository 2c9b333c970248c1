#pragma once
// Internal helpers shared by the experiment runners: solver options, profiles, overrides, summaries.
#include <functional>
#include <string>
#include <vector>

#include "io/yaml_reader.hpp"
#include "jointsim/control/profile.hpp"
#include "jointsim/experiments/runner.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::experiments::detail {

/// `solver: {method, rtol, atol, max_step, max_order, stability_limit_detection, max_num_steps}`.
sim::CvodeOptions readSolver(const io::YamlValue& node, sim::CvodeOptions defaults);
/// Required `duration` [s] > 0 and optional `log_rate` [Hz] > 0 (log_rate keeps its value when absent).
void readDurationAndLogRate(const io::YamlValue& root, double& duration, double& log_rate);
/// `{type: constant|step|ramp|triangle|sine|piecewise|csv, ...}`; csv files are relative to the YAML file.
control::Profile readProfile(const io::YamlValue& node, const std::string& unit);
/// Applies `key.path=value` overrides to the document; throws InputError if a key does not exist.
void applyOverrides(YAML::Node root, const std::vector<std::string>& overrides, const std::string& file);
/// Writes a YAML node as JSON (scalars that parse as numbers or booleans become numbers/booleans).
void writeYamlAsJson(io::JsonWriter& w, const YAML::Node& node);
void writeSolverStats(io::JsonWriter& w, const sim::SolverStats& s);
void writeSolverOptions(io::JsonWriter& w, const sim::CvodeOptions& o);

/// Runs `simulate` (which streams rows to the sink and returns its statistics), writing
/// `<dir>/<name>.csv` and `<dir>/summary.json` atomically; on SolverError writes a failed summary and
/// rethrows. `write_parameters` adds the resolved parameters to the summary. `t_end` [s] (0: unknown) is the
/// end of the simulated interval, for the progress display's ETA (RunOptions::progress).
struct SimulationOutcome {
  sim::SolverStats stats;
  double sim_time_s = 0.0, wall_time_s = 0.0;
};
RunReport runAndRecord(const std::string& name, const std::string& type, const RunOptions& options,
                       const std::vector<std::string>& columns,
                       const std::function<SimulationOutcome(const std::function<void(const Eigen::VectorXd&)>&)>& simulate,
                       const std::function<void(io::JsonWriter&)>& write_parameters, double t_end = 0.0);

}  // namespace jointsim::experiments::detail
