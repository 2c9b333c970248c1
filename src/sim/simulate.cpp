#include "jointsim/sim/simulate.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::sim {

namespace {
/// An output due within this time after a sample is taken at the sample, before its update [s].
constexpr double kSampleOutputTolerance = 1e-12;
}  // namespace

void SimulateOptions::validate() const {
  if (!(t_end > 0.0) || !std::isfinite(t_end))
    throw InputError("simulate: t_end: expected a finite time > 0 s, got " + formatNumber(t_end));
  const bool rate = output_rate > 0.0, interval = output_interval > 0.0;
  if (rate == interval || !std::isfinite(output_rate) || !std::isfinite(output_interval))
    throw InputError("simulate: give exactly one output grid: output_rate > 0 Hz or output_interval > 0 s");
  if (max_events_per_output < 1) throw InputError("simulate: max_events_per_output: expected at least 1");
  if (max_steps < 0 || max_rows < 0 || !(max_wall_time >= 0.0))
    throw InputError("simulate: budgets (max_steps, max_wall_time, max_rows) must be >= 0 (0: none)");
  // The number of rows, in floating point first: t_end·rate can be far beyond any integer type.
  const double rows = output_rate > 0.0 ? std::ceil(t_end * output_rate - 1e-9) : std::ceil(t_end / output_interval);
  if (!(rows < 9e15) || (max_rows > 0 && rows > static_cast<double>(max_rows)))
    throw InputError("simulate: the output grid has " + formatNumber(rows, 6) + " rows over " + formatNumber(t_end) +
                     " s, more than the limit of " + std::to_string(max_rows) +
                     " rows (limits.log_rows; lower the log rate or raise the limit)");
}

SimulateOptions SimulateOptions::atRate(double t_end, double rate, const CvodeOptions& solver) {
  SimulateOptions o;
  o.t_end = t_end;
  o.output_rate = rate;
  o.solver = solver;
  if (o.solver.max_step == 0.0 && rate > 0.0) o.solver.max_step = 1.0 / rate;
  return o;
}

SimulateOptions SimulateOptions::everyInterval(double t_end, double interval, const CvodeOptions& solver) {
  SimulateOptions o;
  o.t_end = t_end;
  o.output_interval = interval;
  o.solver = solver;
  if (o.solver.max_step == 0.0) o.solver.max_step = interval;
  return o;
}

namespace {
std::uint64_t nextPlantId() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}
}  // namespace

Plant::Plant() : id_(nextPlantId()) {}
Plant::Plant(const Plant&) : id_(nextPlantId()) {}
Plant& Plant::operator=(const Plant&) {
  id_ = nextPlantId();  // the states made so far belong to the plant as it was
  frozen_.store(false, std::memory_order_relaxed);
  return *this;
}

PlantState::PlantState(const Plant& owner) : owner_(&owner), owner_id_(owner.id()) {}

void Plant::foreignState() const {
  // (That plant may be gone: it is not asked for its name.)
  throw InputError(name() + ": given a state made by another plant object; make it with this plant's makeState()");
}

void Plant::checkConfigurable(const char* setter) const {
  if (frozen())
    throw InputError(
        name() + ": " + setter +
        ": the plant is in use by a simulator (it is shared by the simulators made on it, and their states "
        "are sized for its configuration): configure it before simulating it");
}

void Plant::setInput(PlantState& /*state*/, int port, double /*value*/) const {
  throw InputError(name() + ": no input " + std::to_string(port) + " (the plant has no inputs)");
}

double Plant::input(const PlantState& /*state*/, int port) const {
  throw InputError(name() + ": no input " + std::to_string(port) + " (the plant has no inputs)");
}

int inputIndex(const Plant& plant, const std::string& name) {
  const std::vector<InputPort> ports = plant.inputPorts();
  std::vector<std::string> names;
  for (size_t i = 0; i < ports.size(); ++i) {
    if (ports[i].name == name) return static_cast<int>(i);
    names.push_back(ports[i].name);
  }
  throw InputError(plant.name() + ": no input '" + name + "'; " +
                   (names.empty() ? std::string("the plant has no inputs") : "the inputs are: " + join(names, ", ")));
}

int signalIndex(const Plant& plant, const std::string& name) {
  const auto& names = plant.signalNames();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name || columnBaseName(names[i]) == name) return static_cast<int>(i);
  throw InputError(plant.name() + ": no signal '" + name + "'; the signals are: " + join(names, ", "));
}

std::vector<std::string> tableColumns(const Plant& plant) {
  std::vector<std::string> columns{"time[s]"};
  const auto& names = plant.signalNames();
  columns.insert(columns.end(), names.begin(), names.end());
  return columns;
}

namespace {

/// Thrown through CVODE from the right-hand side to stop the run (budget, interruption); simulate() reports the
/// reason it recorded.
struct StopRun {};

}  // namespace

void installPlantJacobian(const Plant& plant, const PlantState& state, CvodeIntegrator& integ) {
  const CvodeOptions& o = integ.options();
  if (!plant.providesJacobian() || !o.plant_jacobian || o.method != Method::BDF) return;
  integ.setDifferenceJacobian(
      [&plant, &state](double t, const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                       const Eigen::Ref<const Eigen::VectorXd>& inc,
                       Eigen::Ref<Eigen::MatrixXd> J) { plant.jacobian(state, t, y, f, inc, J); });
  JacobianStructure structure = plant.jacobianStructure();
  if (!structure.empty() && o.dense_solver == CvodeOptions::DenseSolver::Eigen)
    integ.setJacobianStructure(std::move(structure));
}

SimulationResult simulate(const Plant& plant, const SimulateOptions& options, const OutputSink& sink) {
  const std::unique_ptr<PlantState> state = plant.makeState();
  return simulate(plant, *state, options, sink);
}

SimulationResult simulate(const Plant& plant, PlantState& state, const SimulateOptions& options,
                          const OutputSink& sink) {
  options.validate();
  if (state.ownerId() != plant.id())
    throw InputError(plant.name() + ": simulate: given a state made by another plant object");
  plant.freeze();
  CvodeOptions solver = options.solver;
  if (solver.component.empty()) solver.component = plant.name();
  if (!solver.state_name) solver.state_name = [&plant](int i) { return plant.stateName(i); };
  const int n = plant.stateSize();
  const double t_end = options.t_end;
  const bool keep_history = solver.input_jump == CvodeOptions::InputJump::KeepHistory;
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall = [&wall_start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };

  // Why the run is being stopped from outside its physics: an interruption (requestStop) or the wall-clock
  // budget. Checked after every advance() and, since one advance() may take many steps, in the right-hand side
  // (the stop flag at every call, the clock every 256 calls).
  std::string stop_flag, stop_message;
  auto stopNow = [&]() {
    if (const int sig = stopRequested()) {
      stop_flag = "INTERRUPTED";
      stop_message = "interrupted (signal " + std::to_string(sig) + ")";
      return true;
    }
    if (options.max_wall_time > 0.0 && wall() > options.max_wall_time) {
      stop_flag = "WALL_TIME_BUDGET";
      stop_message =
          "more than its wall-clock budget of " + formatNumber(options.max_wall_time) + " s (limits.wall_time)";
      return true;
    }
    return false;
  };
  long rhs_calls = 0;
  CvodeIntegrator integ(
      n,
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        if ((stopRequested() || (options.max_wall_time > 0.0 && (++rhs_calls & 255) == 0)) && stopNow())
          throw StopRun{};
        plant.derivatives(state, t, y, yd);
      },
      solver);
  installPlantJacobian(plant, state, integ);
  integ.setStepLimit(options.max_steps);  // enforced inside advance(): one output interval cannot overspend
  if (plant.rootCount() > 0)
    integ.setRootFunction(plant.rootCount(),
                          [&plant, &state](double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                                           Eigen::Ref<Eigen::VectorXd> g) { plant.roots(state, t, y, g); });

  // Time events inside (0, t_end), then the end itself.
  std::vector<double> breaks;
  for (double b : plant.timeEvents(t_end))
    if (b > 0.0 && b < t_end) breaks.push_back(b);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  breaks.push_back(t_end);
  size_t next_break = 0;

  // Sampled part: samples at k·T_s for k >= 1 while before t_end (the one at t = 0 is part of the start).
  const double Ts = plant.samplePeriod();
  if (!(Ts >= 0.0) || !std::isfinite(Ts)) throw InputError(plant.name() + ": sample period must be >= 0 s");
  long sample_k = 1;
  auto sampleTime = [&](long k) { return Ts > 0.0 ? std::min(t_end, static_cast<double>(k) * Ts) : kInf; };
  double t_sample = sampleTime(sample_k);

  // Output grid (its row count is bounded by validate()).
  const bool by_rate = options.output_rate > 0.0;
  const long n_outputs = by_rate ? static_cast<long>(std::ceil(t_end * options.output_rate - 1e-9)) : 0;
  auto outputTime = [&](long k) {
    return by_rate ? std::min(t_end, static_cast<double>(k) / options.output_rate)
                   : std::min(t_end, static_cast<double>(k) * options.output_interval);
  };

  Eigen::VectorXd row(1 + static_cast<Eigen::Index>(plant.signalNames().size()));
  SimulationResult result;
  Eigen::VectorXd y = plant.initialState();
  if (y.size() != n)
    throw InputError(plant.name() + ": initial state has " + std::to_string(y.size()) + " entries, expected " +
                     std::to_string(n));
  auto emit = [&](double t) {
    row[0] = t;
    plant.signals(state, t, y, row.tail(row.size() - 1));
    sink(row);
    ++result.outputs;
  };
  // The stop time at the next event or sample; at t_end only when asked to stop there.
  auto setStop = [&]() {
    const double stop = std::min(t_sample, breaks[next_break]);
    if (options.stop_at_end || stop < t_end) integ.setStopTime(stop);
  };
  // At a sample: keep CVODE's history when asked to and the jump of the held inputs is small enough for the next
  // step's error test (CvodeIntegrator::jumpError ≤ 1); otherwise restart. f_old: before the sample's update.
  Eigen::VectorXd f_old(n), f_new(n);
  auto sampleAt = [&](double t_now) {
    if (keep_history) plant.derivatives(state, t_now, y, f_old);
    plant.sample(state, t_now, y);
    ++result.samples;
    t_sample = sampleTime(++sample_k);
  };
  auto keepHistory = [&](double t_now) {
    if (!keep_history) return false;
    plant.derivatives(state, t_now, y, f_new);
    return integ.jumpError(f_old, f_new, std::min(t_sample, breaks[next_break]) - t_now) <= kKeepHistoryLimit;
  };
  // After an event (`restart`: the right-hand side may jump anywhere) or a sample: restart, or go on with the
  // history; then the stop time at the next event or sample.
  // A restart at a sample alone (the state is continuous, the held inputs jumped) starts with the last Jacobian.
  auto goOn = [&](double t_now, bool restart) {
    if (restart || !keepHistory(t_now)) {
      integ.initialize(t_now, y, !restart);
      ++result.restarts;
    } else {
      ++result.input_jumps;  // CVODE stopped exactly at the sample and goes on with the new held inputs
    }
    setStop();
  };
  auto budgets = [&](double t) {
    if (stopNow()) throw SolverError(solver.component + ": " + stop_message, t, stop_flag, solver.component);
  };

  double t = 0.0;
  try {
    plant.start(state, 0.0, y);
    if (Ts > 0.0) ++result.samples;  // the plant's start includes the sample at t = 0
    integ.initialize(0.0, y);
    setStop();
    emit(0.0);
    for (long k = 1;; ++k) {
      const double t_out = outputTime(k);
      // An output due just after a sample (rounding of k / rate against k·T_s) is taken at the sample.
      const double target = (t_out > t_sample && t_out <= t_sample + kSampleOutputTolerance) ? t_sample : t_out;
      long events_here = 0;
      while (t < target) {
        t = integ.advance(std::min(target, std::min(t_sample, breaks[next_break])), y);
        budgets(t);
        const bool root = integ.rootFound();
        const bool at_break = t >= breaks[next_break] && next_break + 1 < breaks.size();
        const bool at_sample = t >= t_sample && t < target && t_sample < t_end;
        if (root || at_break) {
          if (at_break) ++next_break;
          plant.updateModes(state, t, y, root ? integ.rootDirections() : std::vector<int>{});
          ++result.events;
          if (++events_here > options.max_events_per_output)
            throw SolverError(solver.component + ": more than " + std::to_string(options.max_events_per_output) +
                                  " events in one output interval (chattering) at t = " + std::to_string(t) + " s",
                              t, "EVENT_CHATTERING", solver.component);
        }
        if (at_sample) sampleAt(t);
        if (root || at_break || at_sample) goOn(t, root || at_break);
      }
      emit(t);
      const bool done = by_rate ? k >= n_outputs : t_out >= t_end;
      if (done) break;
      if (t >= t_sample && t_sample < t_end) {  // the output was due at a sample: update after it
        sampleAt(t);
        goOn(t, false);
      }
    }
  } catch (const SolverError& e) {
    // What the run had done; the reason of a stop from outside replaces CVODE's report of the aborted step.
    result.stats = integ.stats();
    result.sim_time_s = e.time();
    result.wall_time_s = wall();
    if (e.flag() == "STEP_BUDGET" && stop_flag.empty()) {
      stop_flag = "STEP_BUDGET";
      stop_message = "more than " + std::to_string(options.max_steps) + " solver steps (limits.steps)";
    }
    if (stop_flag.empty()) throw SimulationFailure(e, result);
    const SolverError why(solver.component + ": " + stop_message + " at t = " + formatNumber(e.time()) + " s", e.time(),
                          stop_flag, solver.component);
    if (stop_flag == "INTERRUPTED") throw Interrupted(why, result, stopRequested());
    throw SimulationFailure(why, result);
  }
  result.sim_time_s = t;
  result.wall_time_s = wall();
  result.stats = integ.stats();
  return result;
}

TableSink::TableSink(std::vector<std::string> columns) : columns_(std::move(columns)) {}

void TableSink::operator()(const Eigen::VectorXd& row) {
  if (static_cast<size_t>(row.size()) != columns_.size())
    throw Error("TableSink: row of " + std::to_string(row.size()) + " values for " + std::to_string(columns_.size()) +
                " columns");
  data_.insert(data_.end(), row.data(), row.data() + row.size());
  ++rows_;
}

SignalTable TableSink::table() const {
  SignalTable t;
  t.columns = columns_;
  t.values = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      data_.data(), rows_, static_cast<Eigen::Index>(columns_.size()));
  return t;
}

int SignalTable::column(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name || columnBaseName(columns[i]) == name) return static_cast<int>(i);
  throw InputError("no column '" + name + "'; the columns are: " + join(columns, ", "));
}

SignalTable simulateTable(const Plant& plant, const SimulateOptions& options, SimulationResult* result) {
  TableSink sink(tableColumns(plant));
  const SimulationResult r = simulate(plant, options, [&sink](const Eigen::VectorXd& row) { sink(row); });
  if (result) *result = r;
  return sink.table();
}

}  // namespace jointsim::sim
