// One FMI 2.0 Co-Simulation instance: the state machine of the standard over experiments::loadExperiment and
// sim::Simulator. Nothing throws out of the public methods: errors become Status::Error and a log message.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <nlohmann/json.hpp>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/systems/faults.hpp"

namespace jointsim::fmi {

namespace {
std::string instanceNumber(double v) { return formatNumber(v, 17); }
}  // namespace

// The FMI 2.0 state machine of a Co-Simulation slave (at namespace scope, not in an anonymous namespace: Impl's
// members may not have types of internal linkage when this file is compiled in a unity batch).
enum class Phase { Instantiated, Initialization, StepComplete, Failed, Terminated };

struct Instance::Impl {
  std::string name;
  std::string resources;
  FmuDescription d;
  Logger logger;
  Phase phase = Phase::Instantiated;
  std::vector<double> values;  // inputs and parameters as set; outputs unused
  std::vector<int> input_of;   // per variable: the plant's input port of an input variable (-1: not an input)
  double start_time = 0.0;
  bool stop_defined = false;  // fmi2SetupExperiment: a step past stop_time is an error
  double stop_time = 0.0;
  std::shared_ptr<experiments::Experiment> experiment;
  std::unique_ptr<sim::Simulator> sim;
  bool params_changed = true;  // the experiment must be (re)loaded before use

  void log(Status s, const std::string& msg) {
    if (!logger) return;
    try {
      logger(s,
             s == Status::OK        ? "logInfo"
             : s == Status::Warning ? "logWarning"
                                    : "logError",
             "jointsim FMU '" + name + "': " + msg);
    } catch (...) {
    }
  }
  Status error(const std::string& msg) {
    log(Status::Error, msg);
    return Status::Error;
  }
  Status wrongPhase(const char* call) {
    static const char* names[] = {"instantiated", "initialization mode", "step complete", "failed (after an error)",
                                  "terminated"};
    return error(std::string(call) + " is not allowed in state " + names[static_cast<int>(phase)]);
  }

  /// Loads the experiment with the export's overrides and the changed parameters, builds the simulator, sets the
  /// command ports and the inputs' values.
  void build() {
    std::vector<std::string> overrides = d.overrides;
    std::vector<systems::Fault> faults;
    for (size_t i = 0; i < d.variables.size(); ++i) {
      const Variable& v = d.variables[i];
      if (v.causality != Causality::Parameter || values[i] == v.start) continue;
      if (!v.fault.empty()) {
        systems::Fault f;
        f.type = systems::faultTypeFromString(v.fault);
        f.joint = v.key;  // the joint whose drive
        f.value = values[i];
        faults.push_back(f);
      } else {
        overrides.push_back(v.key + "=" + instanceNumber(values[i]));
      }
    }
    sim.reset();
    experiment = std::shared_ptr<experiments::Experiment>(
        experiments::loadExperiment(resources + "/" + d.experiment_file, overrides, faults));
    if (experiment->type() != d.experiment_type)
      throw InputError("the experiment's type changed to '" + experiment->type() + "'");
    experiments::checkRunSettings(*experiment);  // the checks of jointsim run (e.g. a log rate beyond its limit)
    auto made = experiments::makeSimulator(experiment);
    input_of = checkVariables(made->plant());  // before the simulator is kept: a failed check leaves none to read
    sim = std::move(made);
    // One fmi2DoStep may take at most the solver's max_num_steps internal steps (its meaning in the experiment file:
    // per output interval, here per communication step); a longer one fails with the simulated time and the plant.
    sim::AdvanceLimits limits;
    limits.max_steps = sim->integratorOptions().max_num_steps;
    sim->setLimits(limits);
    applyInputs();
    params_changed = false;
  }

  /// The description (resources/jointsim_fmu.json) against the plant it was loaded for: every output names a signal
  /// of the plant under the same name, every input one of its input ports. An edited description (the GUID is only a
  /// string in it) is an error here instead of a read out of bounds in fmi2GetReal. Returns the input ports of the
  /// variables (-1 for a variable that is not an input).
  std::vector<int> checkVariables(const sim::Plant& plant) const {
    const auto& signals = plant.signalNames();
    const std::string where = resources + "/jointsim_fmu.json: variable ";
    std::vector<int> ports(d.variables.size(), -1);
    for (size_t i = 0; i < d.variables.size(); ++i) {
      const Variable& v = d.variables[i];
      if (v.causality == Causality::Output) {
        if (v.signal < 0 || static_cast<size_t>(v.signal) >= signals.size())
          throw InputError(where + v.name + ": signal " + std::to_string(v.signal) + " out of range (the plant has " +
                           std::to_string(signals.size()) + " signals); the FMU's resources were edited");
        if (splitColumn(signals[static_cast<size_t>(v.signal)]).first != v.name)
          throw InputError(where + v.name + ": signal " + std::to_string(v.signal) + " is '" +
                           signals[static_cast<size_t>(v.signal)] + "'; the FMU's resources were edited");
      } else if (v.causality == Causality::Input) {
        try {
          ports[i] = sim::inputIndex(plant, v.port);
        } catch (const InputError& e) {
          throw InputError(where + v.name + ": " + e.what() + "; the FMU's resources were edited");
        }
      }
    }
    return ports;
  }

  /// The input variables' values into the plant's input ports, in the order of the description (a port of a group
  /// selects its mode, e.g. the joint's voltage port).
  void applyInputs() {
    const sim::Plant& plant = sim->plant();
    sim::PlantState& state = sim->plantState();
    for (size_t i = 0; i < d.variables.size(); ++i)
      if (input_of[i] >= 0) plant.setInput(state, input_of[i], values[i]);
  }

  /// Runs `f`, turning every exception into a logged error (a solver failure names the time and component).
  /// `fatal`: the instance is failed afterwards (only reset, terminate and free remain).
  template <class F>
  Status guarded(const char* call, F&& f, bool fatal = true) {
    try {
      f();
      return Status::OK;
    } catch (const SolverError& e) {
      if (fatal) phase = Phase::Failed;
      return error(std::string(call) + ": solver failure at t = " + instanceNumber(e.time()) + " s in " +
                   e.component() + ": " + e.what());
    } catch (const std::exception& e) {
      if (fatal) phase = Phase::Failed;
      return error(std::string(call) + ": " + e.what());
    } catch (...) {
      if (fatal) phase = Phase::Failed;
      return error(std::string(call) + ": unknown error");
    }
  }
};

Instance::Instance(std::string instance_name, const std::string& resource_dir, const std::string& guid, Logger logger)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.name = std::move(instance_name);
  m.logger = std::move(logger);
  m.resources = resource_dir;
  const std::string path = resource_dir + "/jointsim_fmu.json";
  const std::string text = io::readBoundedFile(path);
  if (text.empty()) throw InputError(path + ": cannot read the FMU description");
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": " + e.what());
  }
  m.d = FmuDescription::fromJson(j, path);
  if (guid != m.d.guid)
    throw InputError(path + ": GUID '" + guid + "' given by the importer, the FMU's is '" + m.d.guid + "'");
  m.values.resize(m.d.variables.size());
  for (size_t i = 0; i < m.values.size(); ++i) m.values[i] = m.d.variables[i].start;
}

Instance::~Instance() = default;

const FmuDescription& Instance::description() const { return impl_->d; }

double Instance::time() const { return impl_->sim ? impl_->sim->time() : impl_->start_time; }

Status Instance::setupExperiment(bool tolerance_defined, double tolerance, double start_time, bool stop_defined,
                                 double stop_time) {
  Impl& m = *impl_;
  if (m.phase != Phase::Instantiated) return m.wrongPhase("fmi2SetupExperiment");
  // The experiment's trajectory, fault schedules and initial state are defined from t = 0: a run starting elsewhere
  // would start from a state that is not at rest on its reference.
  if (start_time != 0.0)
    return m.error("fmi2SetupExperiment: start time " + instanceNumber(start_time) +
                   " s: this FMU's experiment starts at t = 0 s (its trajectory, faults and initial state are defined "
                   "from there); use startTime 0 and step to where you need it");
  if (stop_defined && !(stop_time > start_time))
    return m.error("fmi2SetupExperiment: stop time " + instanceNumber(stop_time) +
                   " s: expected a time after the start time " + instanceNumber(start_time) + " s");
  m.start_time = start_time;
  m.stop_defined = stop_defined;
  m.stop_time = stop_time;
  if (tolerance_defined)
    m.log(Status::Warning, "fmi2SetupExperiment: tolerance " + instanceNumber(tolerance) +
                               " ignored: the experiment file's solver settings (parameters solver.rtol, "
                               "solver.atol) apply");
  return Status::OK;
}

Status Instance::enterInitializationMode() {
  Impl& m = *impl_;
  if (m.phase != Phase::Instantiated) return m.wrongPhase("fmi2EnterInitializationMode");
  const Status s = m.guarded("fmi2EnterInitializationMode", [&] {
    if (m.params_changed || !m.sim) m.build();
  });
  if (s == Status::OK) m.phase = Phase::Initialization;
  return s;
}

Status Instance::exitInitializationMode() {
  Impl& m = *impl_;
  if (m.phase != Phase::Initialization) return m.wrongPhase("fmi2ExitInitializationMode");
  const Status s = m.guarded("fmi2ExitInitializationMode", [&] {
    if (m.params_changed) m.build();
  });
  if (s == Status::OK) m.phase = Phase::StepComplete;
  return s;
}

Status Instance::terminate() {
  Impl& m = *impl_;
  if (m.phase != Phase::StepComplete && m.phase != Phase::Failed) return m.wrongPhase("fmi2Terminate");
  m.phase = Phase::Terminated;
  return Status::OK;
}

Status Instance::reset() {
  Impl& m = *impl_;
  m.sim.reset();
  m.experiment.reset();
  for (size_t i = 0; i < m.values.size(); ++i) m.values[i] = m.d.variables[i].start;
  m.start_time = 0.0;
  m.stop_defined = false;
  m.params_changed = true;
  m.phase = Phase::Instantiated;
  return Status::OK;
}

Status Instance::getReal(const unsigned* vr, size_t n, double* values) {
  Impl& m = *impl_;
  if (n > 0 && (vr == nullptr || values == nullptr)) return m.error("fmi2GetReal: null array");
  if (m.phase == Phase::Terminated && !m.sim) return m.wrongPhase("fmi2GetReal");
  for (size_t k = 0; k < n; ++k)
    if (vr[k] >= m.d.variables.size()) return m.error("fmi2GetReal: unknown value reference " + std::to_string(vr[k]));
  return m.guarded("fmi2GetReal", [&] {
    const Eigen::VectorXd* sig = nullptr;
    for (size_t k = 0; k < n; ++k) {
      const Variable& v = m.d.variables[vr[k]];
      if (v.causality == Causality::Output) {
        if (!m.sim) throw Error("output " + v.name + " is not available before fmi2EnterInitializationMode");
        if (sig == nullptr) sig = &m.sim->signals();
        values[k] = (*sig)[v.signal];
      } else {
        values[k] = m.values[vr[k]];
      }
    }
  });
}

Status Instance::setReal(const unsigned* vr, size_t n, const double* values) {
  Impl& m = *impl_;
  if (n > 0 && (vr == nullptr || values == nullptr)) return m.error("fmi2SetReal: null array");
  if (m.phase == Phase::Failed || m.phase == Phase::Terminated) return m.wrongPhase("fmi2SetReal");
  for (size_t k = 0; k < n; ++k) {  // check everything first: nothing is changed by a rejected call
    if (vr[k] >= m.d.variables.size()) return m.error("fmi2SetReal: unknown value reference " + std::to_string(vr[k]));
    const Variable& v = m.d.variables[vr[k]];
    if (v.causality == Causality::Output) return m.error("fmi2SetReal: " + v.name + " is an output");
    if (v.causality == Causality::Parameter && m.phase == Phase::StepComplete)
      return m.error("fmi2SetReal: parameter " + v.name +
                     " is fixed: it may be set only before fmi2ExitInitializationMode (then fmi2Reset)");
    if (!std::isfinite(values[k]))
      return m.error("fmi2SetReal: " + v.name + " = " + instanceNumber(values[k]) + " is not finite");
  }
  const std::vector<double> before = m.values;
  bool params = false;
  for (size_t k = 0; k < n; ++k) {
    const Variable& v = m.d.variables[vr[k]];
    if (v.causality == Causality::Parameter && m.values[vr[k]] != values[k]) params = true;
    m.values[vr[k]] = values[k];
  }
  if (params) {
    // Load the experiment with the new parameters now, so that a bad value is rejected by this call with the
    // loader's message (as --set would be) and outputs in initialization mode reflect it.
    m.params_changed = true;
    if (m.guarded(
            "fmi2SetReal", [&] { m.build(); }, false) != Status::OK) {
      m.values = before;  // rejected: back to the previous values and experiment
      m.guarded(
          "fmi2SetReal", [&] { m.build(); }, false);
      return Status::Error;
    }
    return Status::OK;
  }
  if (m.sim && m.phase == Phase::Initialization)
    return m.guarded(
        "fmi2SetReal", [&] { m.applyInputs(); }, false);
  return Status::OK;
}

Status Instance::doStep(double t, double h) {
  Impl& m = *impl_;
  if (m.phase != Phase::StepComplete) return m.wrongPhase("fmi2DoStep");
  if (!std::isfinite(t) || !std::isfinite(h) || !(h > 0.0))
    return m.error("fmi2DoStep: communication step size " + instanceNumber(h) + " at " + instanceNumber(t) +
                   " s (expected a finite step > 0)");
  const double now = m.sim->time();
  // A step that hardly moves the clock (1e-300 s) is refused like a negative one, not handed to CVODE (which fails
  // the instance with CV_ILL_INPUT for an output time within rounding of its own).
  const double resolution = 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(now));
  if (h < resolution)
    return m.error("fmi2DoStep: communication step size " + instanceNumber(h) + " s is below the time resolution " +
                   instanceNumber(resolution) + " s at " + instanceNumber(now) + " s");
  if (std::abs(t - now) > 1e-9 * std::max(1.0, std::abs(now)))
    return m.error("fmi2DoStep: communication point " + instanceNumber(t) + " s, but the FMU is at " +
                   instanceNumber(now) + " s");
  if (m.stop_defined && now + h > m.stop_time + 1e-12 * std::max(1.0, std::abs(m.stop_time)))
    return m.error("fmi2DoStep: a step of " + instanceNumber(h) + " s from " + instanceNumber(now) +
                   " s goes past the stop time " + instanceNumber(m.stop_time) + " s set by fmi2SetupExperiment");
  return m.guarded("fmi2DoStep", [&] {
    m.applyInputs();
    m.sim->advanceTo(now + h);
  });
}

// ------------------------------------------------------------------------------------------------ FMU states
struct Instance::State {
  Phase phase = Phase::StepComplete;
  std::vector<double> values;                           // inputs and parameters
  std::shared_ptr<experiments::Experiment> experiment;  // keeps the snapshot's plant alive (null: from bytes)
  sim::Snapshot snapshot;                               // in memory (empty: from bytes)
  std::string snapshot_bytes;                           // from bytes, or serialised on demand
};

namespace {
constexpr const char* kFmuStateMagic = "jointsim FMU state";
}  // namespace

/// The serialised form of an FMU state: the FMU's GUID, the phase, the variables' values, the simulator's state.
static std::string fmuStateBytes(const std::string& guid, const Instance::State& state) {
  ByteWriter out;
  out.tag(kFmuStateMagic);
  out.text(guid);
  out.u64(static_cast<std::uint64_t>(state.phase));
  out.doubles(state.values);
  out.text(state.snapshot.empty() ? state.snapshot_bytes : state.snapshot.toBytes());
  return out.release();
}

Status Instance::getState(State** state) {
  Impl& m = *impl_;
  if (state == nullptr) return m.error("fmi2GetFMUstate: null pointer");
  if ((m.phase != Phase::Initialization && m.phase != Phase::StepComplete) || !m.sim)
    return m.wrongPhase("fmi2GetFMUstate");
  return m.guarded(
      "fmi2GetFMUstate",
      [&] {
        auto s = std::make_unique<State>();
        s->phase = m.phase;
        s->values = m.values;
        s->experiment = m.experiment;
        s->snapshot = m.sim->snapshot();
        if (*state != nullptr)
          **state = std::move(*s);
        else
          *state = s.release();
      },
      false);
}

Status Instance::setState(const State* state) {
  Impl& m = *impl_;
  if (state == nullptr) return m.error("fmi2SetFMUstate: null state");
  if (m.phase == Phase::Terminated) return m.wrongPhase("fmi2SetFMUstate");
  // All or nothing: the instance's experiment, simulator and values change only once the state has been applied.
  auto values = m.values;
  auto experiment = m.experiment;
  std::unique_ptr<sim::Simulator> simulator = std::move(m.sim);
  const bool params_changed = m.params_changed;
  const Status s = m.guarded(
      "fmi2SetFMUstate",
      [&] {
        m.values = state->values;
        if (state->experiment && !state->snapshot.empty()) {
          // The loaded experiment (its parameters) of when the state was taken, with a simulator of its own.
          if (experiment == state->experiment && simulator) {
            m.sim = std::make_unique<sim::Simulator>(*simulator);
          } else {
            m.experiment = state->experiment;
            m.sim = experiments::makeSimulator(m.experiment);
            sim::AdvanceLimits limits;
            limits.max_steps = m.sim->integratorOptions().max_num_steps;
            m.sim->setLimits(limits);
          }
          m.sim->restore(state->snapshot);
        } else {
          m.build();  // the experiment with the state's parameter values
          m.sim->loadState(state->snapshot_bytes);
        }
      },
      false);
  if (s != Status::OK) {
    m.values = std::move(values);
    m.experiment = std::move(experiment);
    m.sim = std::move(simulator);
    m.params_changed = params_changed;
    return s;
  }
  m.params_changed = false;
  m.phase = state->phase;
  return s;
}

void Instance::freeState(State* state) { delete state; }

Status Instance::serializedSize(const State* state, size_t* size) {
  Impl& m = *impl_;
  if (state == nullptr || size == nullptr) return m.error("fmi2SerializedFMUstateSize: null pointer");
  return m.guarded(
      "fmi2SerializedFMUstateSize", [&] { *size = fmuStateBytes(m.d.guid, *state).size(); }, false);
}

Status Instance::serialize(const State* state, char* bytes, size_t size) {
  Impl& m = *impl_;
  if (state == nullptr) return m.error("fmi2SerializeFMUstate: null state");
  if (bytes == nullptr && size > 0) return m.error("fmi2SerializeFMUstate: null buffer");
  return m.guarded(
      "fmi2SerializeFMUstate",
      [&] {
        const std::string data = fmuStateBytes(m.d.guid, *state);
        if (data.size() != size)
          throw InputError("the buffer has " + std::to_string(size) + " bytes, the state " +
                           std::to_string(data.size()) + " (fmi2SerializedFMUstateSize)");
        std::copy(data.begin(), data.end(), bytes);
      },
      false);
}

Status Instance::deserialize(const char* bytes, size_t size, State** state) {
  Impl& m = *impl_;
  if ((bytes == nullptr && size > 0) || state == nullptr) return m.error("fmi2DeSerializeFMUstate: null pointer");
  return m.guarded(
      "fmi2DeSerializeFMUstate",
      [&] {
        const std::string data(bytes == nullptr ? "" : std::string(bytes, size));
        ByteReader in(data, "an FMU state");
        in.tag(kFmuStateMagic);
        const std::string guid = in.text("GUID");
        if (guid != m.d.guid) in.fail("the state of another FMU (GUID " + guid.substr(0, 80) + ")");
        auto s = std::make_unique<State>();
        const std::uint64_t phase = in.u64("phase");
        if (phase != static_cast<std::uint64_t>(Phase::Initialization) &&
            phase != static_cast<std::uint64_t>(Phase::StepComplete))
          in.fail("bad phase " + std::to_string(phase));
        s->phase = static_cast<Phase>(phase);
        s->values = in.doubles("values", static_cast<long>(m.d.variables.size()));
        for (double v : s->values)
          if (!std::isfinite(v)) in.fail("a value that is not finite");
        s->snapshot_bytes = in.text("simulator state");
        in.finish();
        *state = s.release();
      },
      false);
}

}  // namespace jointsim::fmi
