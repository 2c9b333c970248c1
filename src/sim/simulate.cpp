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
#include "jointsim/sim/simulator.hpp"

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

void Plant::releaseInput(PlantState& /*state*/, int port) const {
  throw InputError(name() + ": input " + std::to_string(port) + ": this model's inputs cannot be released");
}

void Plant::setInputProfile(int port, const control::Profile& /*profile*/) {
  throw InputError(name() + ": input " + std::to_string(port) + ": this model takes no input profiles");
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

JacobianKind jacobianKind(const CvodeOptions& o) {
  return o.analytic_jacobian || o.method == Method::Rosenbrock ? JacobianKind::Analytic : JacobianKind::Differences;
}

void installPlantJacobian(const Plant& plant, const PlantState& state, Integrator& integ) {
  const CvodeOptions& o = integ.options();
  integ.setTimeInvariance([&plant, &state] { return plant.timeInvariant(state); });
  integ.setOscillatoryStates(plant.oscillatoryStates());
  if (!plant.providesJacobian() || !o.plant_jacobian || o.method == Method::Adams) return;
  const JacobianKind kind = jacobianKind(o);
  integ.setDifferenceJacobian(
      [&plant, &state, kind](double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                             const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                             Eigen::Ref<Eigen::MatrixXd> J) { plant.jacobian(state, t, y, f, inc, J, kind); });
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
  // The stepping simulator (simulator.hpp) on the caller's state, with the run's end, stepped from one output of the
  // grid to the next with interpolated landings; the events, samples, restarts and the per-call chattering guard and
  // step budget are the simulator's. Here: the output grid and the run's budgets (steps, wall time, interruption).
  options.validate();
  if (state.ownerId() != plant.id())
    throw InputError(plant.name() + ": simulate: given a state made by another plant object");
  const std::string component = options.solver.component.empty() ? plant.name() : options.solver.component;
  const double t_end = options.t_end;
  const auto wall_start = std::chrono::steady_clock::now();
  auto wall = [&wall_start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  {
    const Eigen::Index n0 = plant.initialState().size();
    if (n0 != plant.stateSize())
      throw InputError(plant.name() + ": initial state has " + std::to_string(n0) + " entries, expected " +
                       std::to_string(plant.stateSize()));
  }

  // Output grid (its row count is bounded by validate()).
  const bool by_rate = options.output_rate > 0.0;
  const long n_outputs = by_rate ? static_cast<long>(std::ceil(t_end * options.output_rate - 1e-9)) : 0;
  auto outputTime = [&](long k) {
    return by_rate ? std::min(t_end, static_cast<double>(k) / options.output_rate)
                   : std::min(t_end, static_cast<double>(k) * options.output_interval);
  };

  SimulationResult result;
  std::unique_ptr<Simulator> sim;
  double t = 0.0;
  auto fill = [&](double t_reached) {
    if (!sim) return;
    result.stats = sim->stats();
    result.events = sim->events();
    result.samples = sim->samples();
    result.restarts = std::max(0L, sim->restarts() - 1);  // not the start
    result.input_jumps = sim->inputJumps();
    result.period_wall = sim->periodWallTimes();
    result.sim_time_s = t_reached;
    result.wall_time_s = wall();
  };
  // Why the run is being stopped from outside its physics (checked after every output interval; inside one by the
  // simulator's guard in the right-hand side): an interruption or the wall-clock budget.
  auto wallMessage = [&] {
    return "more than its wall-clock budget of " + formatNumber(options.max_wall_time) + " s (limits.wall_time)";
  };
  auto stopIfAsked = [&](double t_now) {
    if (const int sig = stopRequested()) {
      fill(t_now);
      throw Interrupted(SolverError(component + ": interrupted (signal " + std::to_string(sig) +
                                        ") at t = " + formatNumber(t_now) + " s",
                                    t_now, "INTERRUPTED", component),
                        result, sig);
    }
    if (options.max_wall_time > 0.0 && wall() > options.max_wall_time) {
      fill(t_now);
      throw SimulationFailure(SolverError(component + ": " + wallMessage() + " at t = " + formatNumber(t_now) + " s",
                                          t_now, "WALL_TIME_BUDGET", component),
                              result);
    }
  };
  // Each output interval is one call of the simulator, with the budgets left: the solver's max_num_steps per output
  // interval, the run's steps and wall-clock time.
  const long per_interval = options.solver.max_num_steps;
  auto callLimits = [&] {
    AdvanceLimits l;
    l.max_events = options.max_events_per_output;
    l.max_steps = per_interval;
    if (options.max_steps > 0) {
      const long left = std::max(1L, options.max_steps - sim->integ_->steps());
      l.max_steps = l.max_steps > 0 ? std::min(l.max_steps, left) : left;
    }
    if (options.max_wall_time > 0.0) l.max_wall_time = std::max(1e-9, options.max_wall_time - wall());
    return l;
  };
  Eigen::VectorXd row(1 + static_cast<Eigen::Index>(plant.signalNames().size()));
  auto emit = [&](double t_now) {
    row[0] = t_now;
    row.tail(row.size() - 1) = sim->signals();
    sink(row);
    ++result.outputs;
  };
  try {
    sim.reset(new Simulator(plant, options.solver, state, t_end, options.stop_at_end));
    emit(0.0);
    for (long k = 1;; ++k) {
      const double t_out = outputTime(k);
      // An output due just after a sample (rounding of k / rate against k·T_s) is taken at the sample.
      const double t_sample = sim->t_sample_ < t_end ? sim->t_sample_ : kInf;
      const double target = (t_out > t_sample && t_out <= t_sample + kSampleOutputTolerance) ? t_sample : t_out;
      if (target > t) {
        sim->setLimits(callLimits());
        t = sim->advanceTo(target, Landing::Interpolate);
      }
      stopIfAsked(t);
      emit(t);
      if (by_rate ? k >= n_outputs : t_out >= t_end) break;
    }
  } catch (const Interrupted& e) {
    fill(e.time());
    throw Interrupted(SolverError(component + ": interrupted (signal " + std::to_string(e.signal()) +
                                      ") at t = " + formatNumber(e.time()) + " s",
                                  e.time(), "INTERRUPTED", component),
                      result, e.signal());
  } catch (const SimulationFailure&) {
    throw;  // stopIfAsked's, complete
  } catch (const SolverError& e) {
    // What the run had done; a budget's reason in the terms of the run's settings.
    fill(e.time());
    const std::string at = " at t = " + formatNumber(e.time()) + " s";
    if (e.flag() == "WALL_TIME_BUDGET")
      throw SimulationFailure(SolverError(component + ": " + wallMessage() + at, e.time(), e.flag(), component),
                              result);
    if (e.flag() == "STEP_BUDGET") {
      if (options.max_steps > 0 && result.stats.steps > options.max_steps)
        throw SimulationFailure(SolverError(component + ": more than " + std::to_string(options.max_steps) +
                                                " solver steps (limits.steps)" + at,
                                            e.time(), "STEP_BUDGET", component),
                                result);
      throw SimulationFailure(SolverError(component + ": more than max_num_steps = " + std::to_string(per_interval) +
                                              " solver steps in one output interval (CV_TOO_MUCH_WORK)" + at,
                                          e.time(), "CV_TOO_MUCH_WORK", component),
                              result);
    }
    if (e.flag() == "EVENT_CHATTERING")
      throw SimulationFailure(SolverError(component + ": more than " + std::to_string(options.max_events_per_output) +
                                              " events in one output interval (chattering)" + at,
                                          e.time(), e.flag(), component),
                              result);
    throw SimulationFailure(e, result);
  }
  fill(t);
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
