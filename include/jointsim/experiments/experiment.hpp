#pragma once
/// \file
/// Experiments: a YAML file describing a simulated model and how to run it (`jointsim run FILE.yaml`),
/// loaded into an Experiment (its plant, run settings and resolved parameters) through the registry of
/// experiment types (registry.hpp). Everything the CLI does is here as library calls:
///
///   auto e = experiments::loadExperiment("config/experiments/ur5_fall.yaml", {"duration=0.5"});
///   experiments::ExperimentResult r = experiments::runInMemory(*e);      // nothing written
///   double q = r.log.values(r.log.values.rows() - 1, r.log.column("q_shoulder_pan_joint"));
///
///   experiments::runExperimentFile("config/experiments/ur5_fall.yaml", {});   // out/ur5_fall/*.csv, summary.json
///
/// Outputs of runExperimentFile: `<dir>/<name>.csv` (the log), extra tables `<dir>/<name>_<suffix>.csv` (e.g.
/// clamping curves) and `<dir>/summary.json` (status, timing, solver statistics, resolved parameters, the
/// jointsim version and commit, the UTC start time and a content hash of every input file). Each is written
/// to a temporary name and renamed into place; the summary comes last.

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "jointsim/io/input_files.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/joint_limits.hpp"

namespace jointsim::systems {
class RobotSystem;
}  // namespace jointsim::systems

namespace jointsim::experiments {

/// Budgets of one run, from the experiment file's `limits: {steps, wall_time, log_rows}` block (0: none). A run
/// over its step or wall-clock budget fails with a "failed" summary; a log grid over log_rows is an input error.
struct RunLimits {
  long steps = 50'000'000;     ///< internal solver steps over the whole run (~10–30 min of wall time)
  double wall_time = 0.0;      ///< wall-clock time [s]
  long log_rows = 10'000'000;  ///< rows of the log (~a few GB of CSV for a robot)
};

/// A table produced besides the log (e.g. one clamping curve per axis): written as `<name>_<suffix>.csv`.
struct ExtraTable {
  std::string suffix;
  sim::SignalTable table;
};

/// The arm of an experiment as a viewer draws it (`jointsim view`, report/view.hpp): its rigid kinematics and, per
/// joint, the log column that holds the joint's angle.
struct ArmKinematics {
  const multibody::Model* model = nullptr;  ///< the rigid arm (owned by the experiment)
  std::vector<std::string> angle_columns;   ///< (model->nq) base name of each joint's angle column [rad or m]
  int tcp_frame = -1;                       ///< index in model->frames of the tool centre point (clamped frame)
  bool clamped = false;                     ///< the TCP is clamped where it is at `q0`
  Eigen::VectorXd q0;                       ///< start posture [rad] (empty: zeros)
};

/// A loaded experiment, ready to run. Implemented once per experiment type.
class Experiment {
 public:
  virtual ~Experiment() = default;
  /// The simulated model.
  virtual sim::Plant& plant() = 0;
  /// End time, output grid and solver settings of the run.
  virtual sim::SimulateOptions simulateOptions() const = 0;
  /// Resolved parameters, written as "parameters" in summary.json after "config_file" and before "config" (the
  /// document), after the run (`result` holds its statistics, e.g. the number of events).
  virtual void describe(nlohmann::ordered_json& parameters, const sim::SimulationResult& result) const = 0;
  /// Sees every output row during the run (e.g. to collect a maximum or extra tables).
  virtual void observe(const Eigen::VectorXd& /*row*/) {}
  /// Tables to write besides the log after a successful run.
  virtual std::vector<ExtraTable> extraTables() const { return {}; }
  /// The SI unit of the number at `key` of the experiment file (a key path as --set takes it, e.g.
  /// "trajectory.a[0][1]", "drives.elbow_joint.transmission.stiffness"); "1" for a pure number, "" when the type does
  /// not know it. The FMU export offers the file's numbers with a known unit as parameters.
  virtual std::string keyUnit(const std::string& key) const;
  /// The robot with drives of an experiment type that simulates one (tracking; it is plant()), else null: for front
  /// ends that use the robot's own API (its model, drives and motor states) besides the plant interface.
  virtual const systems::RobotSystem* robotSystem() const { return nullptr; }
  /// The arm a viewer draws, for types that simulate one (tracking, passive_robot, clamping, robotr3_full); else none.
  virtual std::optional<ArmKinematics> arm() const { return std::nullopt; }

  const std::string& name() const { return name_; }  ///< experiment.name
  const std::string& type() const { return type_; }  ///< experiment.type
  const std::string& file() const { return file_; }  ///< the experiment file ("" when built in code)
  /// The experiment file's document as JSON (copied into the summary's parameters.config).
  const nlohmann::ordered_json& config() const;
  /// Budgets of the run (from `limits:`; defaults otherwise).
  const RunLimits& limits() const { return limits_; }
  void setLimits(const RunLimits& limits) { limits_ = limits; }
  /// The joint-limit monitor (joint_limits: warn or stop) of experiment types with a robot; disabled for the
  /// others. Fed with every output row of a run; its violations go into the summary ("joint_limits").
  systems::JointLimitMonitor& jointLimits() { return joint_limits_; }
  const systems::JointLimitMonitor& jointLimits() const { return joint_limits_; }
  void setJointLimits(systems::JointLimitMonitor monitor) { joint_limits_ = std::move(monitor); }
  /// Every file read while loading (experiment, robot, drives, CSV inputs) with its content hash.
  const std::vector<io::InputFile>& inputs() const { return inputs_; }
  void setIdentity(std::string name, std::string type, std::string file);
  void setConfig(const nlohmann::ordered_json& config);
  void setInputs(std::vector<io::InputFile> inputs) { inputs_ = std::move(inputs); }

 private:
  std::string name_, type_, file_;
  std::shared_ptr<nlohmann::ordered_json> config_;
  std::vector<io::InputFile> inputs_;
  RunLimits limits_;
  systems::JointLimitMonitor joint_limits_;
};

/// An Experiment around one plant of type P that knows its own run settings (P::simulateOptions()).
template <class P>
class PlantExperiment : public Experiment {
 public:
  template <class... Args>
  explicit PlantExperiment(Args&&... args) : plant_(std::forward<Args>(args)...) {}
  sim::Plant& plant() override { return plant_; }
  sim::SimulateOptions simulateOptions() const override { return plant_.simulateOptions(); }

 protected:
  P plant_;
};

struct RunOptions {
  std::string output_dir;              ///< empty: out/<experiment name>/ relative to the working directory
  std::vector<std::string> overrides;  ///< "key.path=value" (e.g. "load.inertia=2", "input.profile.values[1]=3")
  /// Faults injected into the drives (systems/faults.hpp); only experiment types with a robot with drives
  /// (`tracking`) accept them, the others reject a non-empty list with InputError.
  std::vector<systems::Fault> faults;
  /// Progress on stderr (simulated time, real-time factor, ETA) for runs longer than ~2 s; the CLI sets it
  /// when stderr is a terminal.
  bool progress = false;
  /// Budgets that replace the file's (negative: keep the file's or the default).
  long max_steps = -1;
  double max_wall_time = -1.0;
};

struct RunReport {
  std::string experiment;         ///< experiment name
  std::string status;             ///< "ok", "failed" or "interrupted"
  std::string csv_path;           ///< log file written (empty when failed)
  std::string summary_path;       ///< summary.json written
  double sim_time_s = 0.0;        ///< simulated time [s]
  double wall_time_s = 0.0;       ///< wall-clock time [s]
  double real_time_factor = 0.0;  ///< sim_time_s / wall_time_s
  sim::SolverStats stats;
  std::vector<std::string> warnings;  ///< e.g. joints that left their range (joint_limits: warn), one line each
  sim::PeriodWallTimes period_wall;   ///< wall time per control period (sampled plants; zero otherwise)
};

/// The outcome of a run in memory.
struct ExperimentResult {
  sim::SignalTable log;            ///< the log (the CSV's content)
  std::vector<ExtraTable> extras;  ///< extra tables (e.g. clamping curves)
  sim::SimulationResult result;    ///< statistics
  std::string summary_json;        ///< summary.json's content (status "ok")
};

/// Loads an experiment file: parses it, applies `overrides` ("key.path=value"; InputError for a key the file
/// lacks) and builds the experiment of its `experiment.type` through the registry. Bad input: InputError
/// naming the file, line and key path.
std::unique_ptr<Experiment> loadExperiment(const std::string& path, const std::vector<std::string>& overrides = {},
                                           const std::vector<systems::Fault>& faults = {});
/// Builds an experiment from a document given as text (YAML, or JSON such as a summary's parameters.config) as if it
/// were the file `path`: relative paths in it resolve against the folder of `path` and errors name `path`.
std::unique_ptr<Experiment> loadExperimentText(const std::string& text, const std::string& path);
/// A stepping simulator (sim/simulator.hpp) over a loaded experiment's plant with the experiment's solver settings
/// (e.g. max_step of one log interval); the simulator keeps the experiment alive. The plant is reachable as
/// simulator->plant() (for `tracking`, a systems::RobotSystem with its command ports).
std::unique_ptr<sim::Simulator> makeSimulator(std::shared_ptr<Experiment> experiment);
/// The checks of the run settings that running makes before it starts (the output grid against limits.log_rows,
/// the budgets): InputError naming the experiment file. `jointsim validate`, `jointsim fmu` and the FMU make them too.
void checkRunSettings(Experiment& experiment);
/// Runs a loaded experiment in memory: nothing is written. SolverError on failure.
ExperimentResult runInMemory(Experiment& experiment);
/// Loads and runs an experiment file, writing the log, extra tables and summary.json (see the file comment).
/// Bad input: InputError (nothing written). Solver failure or a budget run out: summary.json with status
/// "failed", the reason, the wall time and solver statistics so far (no log), and the sim::SimulationFailure
/// rethrown. A stop request (SIGINT/SIGTERM): status "interrupted", sim::Interrupted rethrown. The run first
/// removes its own earlier outputs from the folder (`<name>.csv`, `<name>_*.csv`, `summary.json` and temporary
/// files of those), writes every output under a temporary name and renames them at the end, the summary last.
RunReport runExperimentFile(const std::string& config_path, const RunOptions& options = {});
/// Runs a loaded experiment and writes its outputs into `options.output_dir` (overrides and faults of
/// `options` are ignored: they belong to loading).
RunReport runAndRecord(Experiment& experiment, const RunOptions& options);

}  // namespace jointsim::experiments
