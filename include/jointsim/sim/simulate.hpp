#pragma once
/// \file
/// A run of any sim::Plant (plant.hpp) from t = 0 to t_end with its outputs on a grid handed to a sink: the stepping
/// sim::Simulator (simulator.hpp, the one event engine: events, samples, restarts, chattering guard, step budgets)
/// stepped from one output to the next with interpolated landings (Landing::Interpolate), plus the run's budgets.
///
/// Event handling. The integrator carries a stop time at the next time event or sample, so no step crosses
/// one. At a located root or a time event the plant updates its modes (updateModes) and CVODE is restarted
/// (its multistep history is discarded: the right-hand side may jump there); outputs at that instant show the
/// state after the update. At a sample t_k the plant's sampled part is updated (sample) and CVODE goes on with
/// its history or is restarted, per CvodeOptions::input_jump; an output due at t_k (within 1e-12 s) is taken before the update, i.e. it shows the inputs held
/// over the interval that ends at t_k, as a sampled-data recorder would.
///
/// Output grid: either a rate (t_k = min(t_end, k / rate), k = 1 .. ⌈t_end·rate − 1e-9⌉, the experiments
/// with `log_rate`) or an interval (t_k = min(t_end, k·interval) until t_end, the Modelica-style experiments
/// with an output interval); plus the row at t = 0. Every row starts with the time [s] followed by
/// plant.signals().

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/common/error.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/sim/plant.hpp"

namespace jointsim::sim {

struct SimulateOptions {
  double t_end = 1.0;            ///< end of the run [s], > 0
  double output_rate = 0.0;      ///< output grid as a rate [Hz] (> 0), or
  double output_interval = 0.0;  ///< output grid as an interval [s] (> 0); exactly one of the two is set
  CvodeOptions solver;           ///< integrator settings (component defaults to plant.name())
  /// Stop exactly at t_end (a stop time there). False lets the last internal step overshoot t_end and the
  /// last outputs be interpolated, which is fine for a smooth right-hand side that is valid beyond t_end.
  bool stop_at_end = true;
  /// More root/time events than this between two outputs is chattering: SolverError EVENT_CHATTERING.
  long max_events_per_output = 100000;
  /// Budgets of one run (0: none): internal CVODE steps over all restarts (SolverError STEP_BUDGET), wall-clock
  /// time [s] (WALL_TIME_BUDGET), output rows (InputError before the run starts: the grid is a setting).
  long max_steps = 0;
  double max_wall_time = 0.0;
  long max_rows = 0;
  /// Throws InputError for a bad end time, grid or event budget.
  void validate() const;

  /// Outputs at `rate` [Hz] up to `t_end` [s] with `solver`, whose max_step defaults (when 0) to one output
  /// interval: a stuck shaft (sticking friction) makes the state nearly constant, the step grows without bound,
  /// and a step whose two ends are both "stuck" could jump over a whole slip phase unseen by the error test.
  static SimulateOptions atRate(double t_end, double rate, const CvodeOptions& solver);
  /// Outputs every `interval` [s] up to `t_end` [s]; max_step defaults to the interval likewise.
  static SimulateOptions everyInterval(double t_end, double interval, const CvodeOptions& solver);
};

/// Wall-clock time of the control periods: from one sample of the plant's sampled part to the next (the integration
/// over the period, the sample itself and everything the caller does in between, outputs included). p50 and p99 come
/// from a logarithmic histogram (100 bins per decade from 0.1 µs to 100 s) and are the upper edge of their bin, so at
/// most 2.3 % above the true quantile; max is exact. All zero without a sampled part.
struct PeriodWallTimes {
  long periods = 0;    ///< periods measured since the simulator's construction (a period spanning a reset or a
                       ///< restore is not one: the first sample after either starts the clock again)
  double p50_s = 0.0;  ///< median [s]
  double p99_s = 0.0;  ///< 99th percentile [s]
  double max_s = 0.0;  ///< longest [s]
};

struct SimulationResult {
  SolverStats stats;         ///< CVODE counters, cumulative over all restarts
  double sim_time_s = 0.0;   ///< simulated time reached [s]
  double wall_time_s = 0.0;  ///< wall-clock time of the run [s]
  long events = 0;           ///< root and time events handled
  long samples = 0;          ///< updates of the sampled part (including the one at t = 0)
  long restarts = 0;         ///< integrator restarts after t = 0 (events; samples under Restart or with a large jump)
  long input_jumps = 0;      ///< samples integrated through with the history kept (input_jump KeepHistory)
  long outputs = 0;          ///< rows handed to the sink (including t = 0)
  double realTimeFactor() const { return wall_time_s > 0.0 ? sim_time_s / wall_time_s : 0.0; }
  PeriodWallTimes period_wall;  ///< wall time per control period (sampled plants only)
};

/// A failed run: the SolverError (time, flag, component) plus what the run had done until then (statistics,
/// wall time), so a failed summary can report them.
class SimulationFailure : public SolverError {
 public:
  SimulationFailure(const SolverError& cause, const SimulationResult& partial)
      : SolverError(cause.what(), cause.time(), cause.flag(), cause.component()), partial_(partial) {}
  const SimulationResult& partial() const noexcept { return partial_; }

 private:
  SimulationResult partial_;
};

/// A run stopped by jointsim::requestStop (common/interrupt.hpp), e.g. on SIGINT or SIGTERM; flag "INTERRUPTED".
class Interrupted : public SimulationFailure {
 public:
  Interrupted(const SolverError& cause, const SimulationResult& partial, int signal)
      : SimulationFailure(cause, partial), signal_(signal) {}
  int signal() const noexcept { return signal_; }  ///< the signal that asked for the stop (or -1)

 private:
  int signal_;
};

/// Receives one output row: [t, signals...] (size 1 + plant.signalNames().size()). May throw: the run stops.
using OutputSink = std::function<void(const Eigen::VectorXd& row)>;

/// An input jump whose CvodeIntegrator::jumpError exceeds this restarts the integrator (CvodeOptions::input_jump).
constexpr double kKeepHistoryLimit = 1.0;

/// Gives `integ` the plant's own Jacobian and its block structure when the plant provides them and the
/// integrator's options ask for it (plant_jacobian; BDF or the fixed-step method), and the plant's time invariance
/// (Plant::timeInvariant of `state`, asked at each Jacobian); before integ.initialize(). `plant` and `state` must
/// outlive `integ`.
void installPlantJacobian(const Plant& plant, const PlantState& state, Integrator& integ);

/// The Jacobian the plant is asked for under `options`: analytic parts for the fixed-step method or with
/// analytic_jacobian, difference quotients otherwise.
JacobianKind jacobianKind(const CvodeOptions& options);

/// The step of the fixed-step method (Method::Rosenbrock) for `plant` given solver.step `step` [s]: 0 takes the plant's
/// sample period (the control period); with a sampled plant a step must be that period or an integer fraction of it
/// (returned as T_s / k exactly). InputError naming the plant otherwise.
double fixedStep(const Plant& plant, double step);

/// Runs `plant` from its initialState() at t = 0 to options.t_end. Throws InputError for bad options (also an
/// output grid over max_rows), SimulationFailure (a SolverError with the simulated time, the flag and the plant's
/// name, plus the statistics so far) when the integration fails, events chatter or a budget runs out, and
/// Interrupted when jointsim::requestStop() was called.
SimulationResult simulate(const Plant& plant, const SimulateOptions& options, const OutputSink& sink);
/// The same from a given state of the plant (its inputs set beforehand, e.g. command ports); `state` is the state
/// at the end of the run afterwards (or where it failed).
SimulationResult simulate(const Plant& plant, PlantState& state, const SimulateOptions& options,
                          const OutputSink& sink);

/// Time series of named signals, in memory (what `jointsim run` writes as CSV).
struct SignalTable {
  std::vector<std::string> columns;  ///< "time[s]", then the plant's signals `name[unit]`
  Eigen::MatrixXd values;            ///< one row per output time
  /// Column index by name, with or without its unit ("motor_angle" or "motor_angle[rad]"); throws
  /// InputError listing the columns when absent.
  int column(const std::string& name) const;
  /// The column as a vector.
  Eigen::VectorXd operator[](const std::string& name) const { return values.col(column(name)); }
};

/// Sink that collects rows into a SignalTable (reserve() the expected row count to avoid reallocation).
class TableSink {
 public:
  explicit TableSink(std::vector<std::string> columns);
  void operator()(const Eigen::VectorXd& row);
  SignalTable table() const;
  long rows() const { return rows_; }

 private:
  std::vector<std::string> columns_;
  std::vector<double> data_;
  long rows_ = 0;
};

/// CSV/table column names of a plant: "time[s]" followed by its signal names.
std::vector<std::string> tableColumns(const Plant& plant);

/// simulate() into memory.
SignalTable simulateTable(const Plant& plant, const SimulateOptions& options, SimulationResult* result = nullptr);

}  // namespace jointsim::sim
