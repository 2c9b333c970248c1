// Loading experiment files through the registry, running them in memory or into files (experiment.hpp).
#include "jointsim/experiments/experiment.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/common/version.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/output.hpp"

namespace jointsim::experiments {

namespace fs = std::filesystem;
using io::YamlValue;

const nlohmann::ordered_json& Experiment::config() const {
  static const nlohmann::ordered_json empty = nlohmann::ordered_json::object();
  return config_ ? *config_ : empty;
}

void Experiment::setIdentity(std::string name, std::string type, std::string file) {
  name_ = std::move(name);
  type_ = std::move(type);
  file_ = std::move(file);
}

void Experiment::setConfig(const nlohmann::ordered_json& config) {
  config_ = std::make_shared<nlohmann::ordered_json>(config);
}

namespace {

// An error about a value an override set (or a key it added) names the override, not a line of the file that no
// longer holds that value ("ur5_fall.yaml:13: duration: expected a time in s, got 'abc'" came from --set).
void blameOverride(const InputError& e, const std::string& file, const std::vector<std::string>& overrides) {
  if (e.file() != file || e.keyPath().empty()) return;
  const std::vector<std::string> at = detail::keyParts(e.keyPath());
  for (const std::string& o : overrides) {
    const std::string spec = !o.empty() && o[0] == '+' ? o.substr(1) : o;
    const std::vector<std::string> set = detail::keyParts(spec.substr(0, spec.find('=')));
    const size_t common = std::min(at.size(), set.size());
    if (common == 0 || !std::equal(at.begin(), at.begin() + static_cast<std::ptrdiff_t>(common), set.begin())) continue;
    throw InputError(e.file(), 0, e.keyPath(), e.message() + " (from the override --set " + o + ")");
  }
}

std::unique_ptr<Experiment> buildExperiment(const YamlValue& root, const std::string& path,
                                            const std::vector<systems::Fault>& faults, io::InputRecord& inputs);

}  // namespace

std::string Experiment::keyUnit(const std::string& key) const { return detail::commonKeyUnit(key); }

std::unique_ptr<Experiment> loadExperiment(const std::string& path, const std::vector<std::string>& overrides,
                                           const std::vector<systems::Fault>& faults) {
  io::InputRecord inputs;  // every file read from here on, the experiment file first
  const YamlValue root = YamlValue::loadFile(path);
  detail::applyOverrides(root, overrides);
  try {
    return buildExperiment(root, path, faults, inputs);
  } catch (const InputError& e) {
    blameOverride(e, root.file(), overrides);
    throw;
  }
}

std::unique_ptr<Experiment> loadExperimentText(const std::string& text, const std::string& path) {
  io::InputRecord inputs;
  const YamlValue root = YamlValue::loadString(text, path);
  return buildExperiment(root, path, {}, inputs);
}

namespace {

std::unique_ptr<Experiment> buildExperiment(const YamlValue& root, const std::string& path,
                                            const std::vector<systems::Fault>& faults, io::InputRecord& inputs) {
  root.expectMap("an experiment description mapping");
  const YamlValue exp = root.required("experiment", "mapping {name, type}");
  exp.expectMap("a mapping {name, type}");
  exp.allowKeys({"name", "type", "description"});
  const std::string name = exp.required("name", "experiment name").asString("a name");
  if (!isSafeName(name))
    exp["name"].failExpected("a name of 1 to 128 letters, digits, '.', '-', '_', not starting with '.' or '-' "
                             "(it names the output files)");
  const YamlValue type_node = exp.required("type", "experiment type");
  const std::string t = type_node.asString("an experiment type");
  const ExperimentType* type = findExperimentType(t);
  if (!type) type_node.failExpected("an experiment type (known: " + experimentTypeNames() + ")");
  if (!faults.empty() && !type->accepts_faults)
    type_node.fail("faults (" + systems::describe(faults.front()) + ", ...) apply to experiment types " +
                   experimentTypeNames(true) + ", not to type '" + t + "'");
  // The run's budgets (common to every type): read, then taken out of the document the type's loader sees.
  RunLimits limits;
  const nlohmann::ordered_json config = detail::yamlToJson(root);
  if (const YamlValue l = root["limits"]; l.defined()) {
    l.expectMap("a mapping {steps, wall_time, log_rows} (0: no limit)");
    l.allowKeys({"steps", "wall_time", "log_rows"});
    auto count = [&](const char* key, long fallback) {
      if (!l.has(key)) return fallback;
      const long v = l[key].asInt("a whole number >= 0 (0: no limit)");
      if (v < 0) l[key].failExpected("a whole number >= 0 (0: no limit)");
      return v;
    };
    limits.steps = count("steps", limits.steps);
    limits.log_rows = count("log_rows", limits.log_rows);
    limits.wall_time = l["wall_time"].asDouble(limits.wall_time, "a time in s (0: no limit)");
    if (limits.wall_time < 0) l["wall_time"].failExpected("a time >= 0 s (0: no limit)");
    detail::removeKey(root, "limits");
  }
  // Input profiles (common to every type): `inputs: {PORT: PROFILE}` drives the plant's input ports over time; read
  // here, taken out of the document the type's loader sees, applied to the plant it builds.
  struct InputProfile {
    std::string port;
    YamlValue node;
    control::Profile profile;
  };
  std::vector<InputProfile> input_profiles;
  if (const YamlValue in = root["inputs"]; in.defined()) {
    in.expectMap("a mapping {PORT: PROFILE} of the model's input ports (see its inputs) to profiles of time");
    for (const std::string& k : in.keys()) input_profiles.push_back({k, in[k], readProfile(in[k], "the port's unit")});
    detail::removeKey(root, "inputs");
  }
  std::unique_ptr<Experiment> e = type->load(root, LoadContext{name, path, faults});
  for (const InputProfile& p : input_profiles) {
    try {
      e->plant().setInputProfile(sim::inputIndex(e->plant(), p.port), p.profile);
    } catch (const InputError& err) {
      p.node.fail(err.what());
    }
  }
  // The fixed-step method's step against the plant's control period, known once the plant is built.
  if (const sim::SimulateOptions o = e->simulateOptions(); o.solver.method == sim::Method::Rosenbrock) {
    try {
      sim::fixedStep(e->plant(), o.solver.fixed_step);
    } catch (const InputError& err) {
      const YamlValue solver = root["solver"];
      (solver.has("step") ? solver["step"] : solver["method"]).fail(err.what());
    }
  }
  e->setIdentity(name, t, path);
  e->setConfig(config);
  e->setInputs(inputs.files());
  e->setLimits(limits);
  return e;
}

/// The run settings of an experiment with its budgets, checked; InputError naming the experiment file (an
/// output grid beyond limits.log_rows, a bad budget).
sim::SimulateOptions runOptions(Experiment& e) {
  sim::SimulateOptions options = e.simulateOptions();
  options.max_steps = e.limits().steps;
  options.max_wall_time = e.limits().wall_time;
  options.max_rows = e.limits().log_rows;
  try {
    options.validate();
  } catch (const InputError& err) {
    throw InputError((e.file().empty() ? "experiment '" + e.name() + "'" : e.file()) + ": " + err.what());
  }
  return options;
}

/// Runs the experiment, handing every row to `sink` and to the experiment's observer; progress on stderr.
sim::SimulationResult execute(Experiment& e, const std::function<void(const Eigen::VectorXd&)>& sink, bool progress) {
  const sim::SimulateOptions options = runOptions(e);
  e.jointLimits().reset();
  // Progress (set by the CLI when stderr is a terminal): from 2 s of wall time on, at most 4 updates per second.
  const auto start = std::chrono::steady_clock::now();
  auto last = start;
  bool shown = false;
  const sim::SimulationResult r = sim::simulate(e.plant(), options, [&](const Eigen::VectorXd& row) {
    sink(row);
    e.observe(row);
    e.jointLimits().observe(row);
    if (!progress) return;
    const auto now = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double>(now - start).count();
    if (wall < 2.0 || std::chrono::duration<double>(now - last).count() < 0.25) return;
    last = now;
    shown = true;
    const double t = row[0], rtf = t / wall, t_end = options.t_end;
    if (rtf > 0.0)
      std::fprintf(stderr, "\r  %s: t = %.4g / %.4g s (%3.0f %%), real-time factor %.3g, ETA %.1f s   ",
                   e.name().c_str(), t, t_end, 100.0 * t / t_end, rtf, (t_end - t) / rtf);
    else
      std::fprintf(stderr, "\r  %s: t = %.4g s   ", e.name().c_str(), t);
    std::fflush(stderr);
  });
  if (shown) std::fprintf(stderr, "\n");
  return r;
}

struct SummaryFields {
  std::string status, reason, csv;
  double failed_at = 0.0;
  std::vector<std::string> extra_files;
  std::vector<std::pair<std::string, std::uintmax_t>> outputs;  ///< file name (in the summary's folder), bytes
};

std::string summaryJson(Experiment& e, const std::string& started, const SummaryFields& f,
                        const sim::SimulationResult& r) {
  nlohmann::ordered_json s;
  s["experiment"] = e.name();
  s["type"] = e.type();
  s["status"] = f.status;
  if (!f.reason.empty()) {
    s["reason"] = f.reason;
    s["failed_at_time_s"] = f.failed_at;
  }
  s["jointsim_version"] = version();
  s["git_commit"] = gitCommit();
  s["started_utc"] = started;
  s["sim_time_s"] = r.sim_time_s;
  s["wall_time_s"] = r.wall_time_s;
  s["real_time_factor"] = r.realTimeFactor();
  solverStatsJson(s["solver_stats"], r.stats);
  if (r.period_wall.periods > 0)
    s["control_period_wall_time_s"] = {{"periods", r.period_wall.periods},
                                       {"p50", r.period_wall.p50_s},
                                       {"p99", r.period_wall.p99_s},
                                       {"max", r.period_wall.max_s}};
  if (const systems::JointLimitMonitor& m = e.jointLimits(); m.enabled()) {
    auto& j = s["joint_limits"] = nlohmann::ordered_json::object();
    j["mode"] = systems::jointLimitModeName(m.settings().mode);
    if (m.settings().mode == systems::JointLimitMode::Stop) {
      j["stiffness"] = m.settings().stiffness;
      j["damping"] = m.settings().damping;
    }
    auto& list = j["violations"] = nlohmann::ordered_json::array();
    for (const auto& v : m.violations())
      list.push_back({{"joint", v.joint},
                      {"lower", v.lower},
                      {"upper", v.upper},
                      {"first_time_s", v.first_time},
                      {"max_excursion", v.max_excursion},
                      {"max_time_s", v.max_time},
                      {"max_position", v.max_position}});
  }
  s["csv"] = f.csv;
  if (!f.extra_files.empty()) s["extra_csv"] = f.extra_files;
  if (f.status == "ok") {
    // What resume checks before it reuses the run: each output still there with the size it was written with.
    auto& outputs = s["outputs"] = nlohmann::ordered_json::array();
    for (const auto& [file, bytes] : f.outputs) outputs.push_back({{"file", file}, {"bytes", bytes}});
  }
  s["columns"] = sim::tableColumns(e.plant());
  auto& inputs = s["inputs"] = nlohmann::ordered_json::array();
  for (const auto& in : e.inputs()) inputs.push_back({{"path", in.path}, {"hash", in.hash}, {"bytes", in.size}});
  auto& params = s["parameters"] = nlohmann::ordered_json::object();
  params["config_file"] = e.file();
  e.describe(params, r);
  params["config"] = e.config();
  // Text from the input (descriptions, names, paths) need not be valid UTF-8: bytes that are not are
  // written as U+FFFD rather than failing the run at its last step.
  return s.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace

void checkRunSettings(Experiment& experiment) {
  const sim::SimulateOptions options = runOptions(experiment);
  try {
    experiment.plant().timeEvents(options.t_end);  // e.g. the episodes of an intermittent fault, bounded
  } catch (const InputError& err) {
    throw InputError((experiment.file().empty() ? "experiment '" + experiment.name() + "'" : experiment.file()) + ": " +
                     err.what());
  }
}

std::unique_ptr<sim::Simulator> makeSimulator(std::shared_ptr<Experiment> experiment) {
  if (!experiment) throw InputError("makeSimulator: no experiment given");
  const sim::SimulateOptions options = experiment->simulateOptions();
  sim::Plant* plant = &experiment->plant();
  return std::make_unique<sim::Simulator>(std::shared_ptr<sim::Plant>(std::move(experiment), plant), options.solver);
}

ExperimentResult runInMemory(Experiment& experiment) {
  const std::string started = utcNow();
  sim::TableSink sink(sim::tableColumns(experiment.plant()));
  ExperimentResult out;
  out.result = execute(
      experiment, [&sink](const Eigen::VectorXd& row) { sink(row); }, false);
  out.log = sink.table();
  out.extras = experiment.extraTables();
  SummaryFields f;
  f.status = "ok";
  out.summary_json = summaryJson(experiment, started, f, out.result);
  return out;
}

namespace {

/// Removes the outputs an earlier run of `name` left in `dir` (and their temporary files), so that a failed run
/// never stands beside the log of an earlier good one.
void removeStaleOutputs(const std::string& dir, const std::string& name) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string f = entry.path().filename().string();
    const bool ours = f == "summary.json" || f == name + ".csv" ||
                      (f.rfind(name + "_", 0) == 0 && f.size() > 4 && f.compare(f.size() - 4, 4, ".csv") == 0);
    const size_t tmp = f.find(".tmp.");
    const bool our_tmp = tmp != std::string::npos && (f.rfind("summary.json", 0) == 0 ||
                                                      f.rfind(name + ".csv", 0) == 0 || f.rfind(name + "_", 0) == 0);
    if ((ours || our_tmp) && entry.is_regular_file(ec)) fs::remove(entry.path(), ec);
  }
}

}  // namespace

RunReport runAndRecord(Experiment& experiment, const RunOptions& options) {
  const std::string started = utcNow();
  const std::string& name = experiment.name();
  RunLimits limits = experiment.limits();
  if (options.max_steps >= 0) limits.steps = options.max_steps;
  if (options.max_wall_time >= 0.0) limits.wall_time = options.max_wall_time;
  experiment.setLimits(limits);
  checkRunSettings(experiment);  // bad settings: InputError before anything is touched
  RunReport report;
  report.experiment = name;
  const std::string dir = options.output_dir.empty() ? "out/" + name : options.output_dir;
  io::createDirectories(dir);
  // One run at a time into a folder: a second one would remove the first one's outputs under its feet.
  const io::FileLock lock = io::FileLock::onFolder(
      dir, dir + ": another jointsim run is writing into this folder; wait for it to end, or give this one another "
                 "output folder (-o)");
  removeStaleOutputs(dir, name);
  const std::string csv_path = (fs::path(dir) / (name + ".csv")).string();
  report.summary_path = (fs::path(dir) / "summary.json").string();

  SummaryFields f;
  sim::SimulationResult r;
  const auto wall_start = std::chrono::steady_clock::now();
  // Everything under temporary names first; renamed into place together at the end, the summary last. Any
  // failure leaves only a summary saying why (the writers' destructors remove their temporary files).
  auto failed = [&](const std::string& status, const std::string& reason, double at) {
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    f = SummaryFields{};
    f.status = report.status = status;
    f.reason = reason;
    f.failed_at = at;
    report.sim_time_s = r.sim_time_s = at;
    report.wall_time_s = r.wall_time_s;
    report.stats = r.stats;
    io::writeFileAtomically(report.summary_path, summaryJson(experiment, started, f, r));
  };
  std::vector<std::unique_ptr<io::CsvWriter>> writers;
  try {
    writers.push_back(std::make_unique<io::CsvWriter>(csv_path, sim::tableColumns(experiment.plant())));
    io::CsvWriter& csv = *writers.front();
    r = execute(
        experiment, [&csv](const Eigen::VectorXd& row) { csv.writeRow(row); }, options.progress);
    for (const ExtraTable& t : experiment.extraTables()) {
      const std::string path = (fs::path(dir) / (name + "_" + t.suffix + ".csv")).string();
      writers.push_back(std::make_unique<io::CsvWriter>(path, t.table.columns));
      for (Eigen::Index k = 0; k < t.table.values.rows(); ++k)
        writers.back()->writeRow(t.table.values.row(k).transpose());
      f.extra_files.push_back(path);
    }
    for (auto& w : writers) w->finish();
    for (auto& w : writers) w->commit();
  } catch (const sim::Interrupted& e) {
    r = e.partial();
    failed("interrupted", e.what(), e.time());
    throw;
  } catch (const sim::SimulationFailure& e) {
    r = e.partial();
    failed("failed", e.what(), e.time());
    throw;
  } catch (const SolverError& e) {
    failed("failed", e.what(), e.time());
    throw;
  } catch (const InputError&) {
    throw;  // bad input found while running (e.g. an output grid over its limit): nothing written
  } catch (const std::exception& e) {
    // Output errors after the simulation (a full disk): remove what was already renamed into place.
    std::error_code ec;
    for (auto& w : writers) fs::remove(w->path(), ec);
    failed("failed", e.what(), r.sim_time_s);
    throw;
  }
  report.csv_path = f.csv = csv_path;
  f.status = report.status = "ok";
  for (const auto& w : writers) {
    std::error_code ec;
    const std::uintmax_t bytes = fs::file_size(w->path(), ec);
    f.outputs.emplace_back(fs::path(w->path()).filename().string(), ec ? 0 : bytes);
  }
  report.stats = r.stats;
  report.sim_time_s = r.sim_time_s;
  report.wall_time_s = r.wall_time_s;
  report.real_time_factor = r.realTimeFactor();
  report.period_wall = r.period_wall;
  if (experiment.jointLimits().settings().mode == systems::JointLimitMode::Warn)
    report.warnings = experiment.jointLimits().describe();
  io::writeFileAtomically(report.summary_path, summaryJson(experiment, started, f, r));
  return report;
}

RunReport runExperimentFile(const std::string& config_path, const RunOptions& options) {
  std::unique_ptr<Experiment> e = loadExperiment(config_path, options.overrides, options.faults);
  return runAndRecord(*e, options);
}

}  // namespace jointsim::experiments
