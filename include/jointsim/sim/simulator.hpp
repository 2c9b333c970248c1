#pragma once
/// \file
/// A stepping simulator over any sim::Plant, so that a user's own controller can run around the plant at its own rate
/// and change the plant's inputs (command ports) between steps; also the one event engine under sim::simulate()
/// (which steps it from output to output and adds the output grid and the run's budgets).
///
///   systems::RobotSystem robot = systems::loadRobotWithDrives("config/robots/ur5_drives.yaml");
///   sim::Simulator sim(robot, solver);                        // the robot is only read; sim owns the run's state
///   robot.setCommandPort(sim.plantState(), 0, systems::CommandPort::Voltage);
///   for (int k = 0; k < 1000; ++k) {                        // 1 kHz
///     robot.setCommand(sim.plantState(), 0, pd(sim.signal("q_shoulder_pan_joint"), ...));
///     sim.advance(1e-3);
///   }
///
/// Events are handled inside advance()/advanceTo() exactly as in sim::simulate(): root events (the plant's
/// updateModes) and time events (the plant's timeEvents) restart the integrator. At the plant's samples
/// (sample() at k·T_s from the reset time) and at an input change (PlantState::inputRevision(), taken at the start of
/// the next advance) a held input jumps: the integrator goes on with its history (CvodeOptions::input_jump
/// KeepHistory, the default) or restarts (Restart). A change of the state (setState, or applyInputs moving
/// controller states for a bumpless switch) always restarts. Between unchanged inputs CVODE keeps its step-size
/// and order history across calls. An advance ends exactly at its target time: by a CVODE stop time (Landing::Stop,
/// the default), or by interpolation after stepping past it (Landing::Interpolate: sim::simulate's outputs). A
/// sample due exactly at the target time is taken at the start of the next advance, so signals() at the target
/// show the inputs held over the interval that ends there (as sim::simulate's outputs do).
///
/// One call may be as long as wanted: CVODE's per-call cap of internal steps (CvodeOptions::max_num_steps) does
/// not end it, unless those steps covered less than 1 ns each on average (the integration is stuck: flag
/// CV_TOO_MUCH_WORK); the call's own limits (AdvanceLimits: steps, wall-clock time, a bound on the state) do, and
/// so does a stop request (jointsim::requestStop, or the caller's StopPoll, common/interrupt.hpp), checked in the
/// right-hand side.
///
/// Errors: InputError for a bad target time or state (the simulator is unchanged); SolverError (with the
/// simulated time, the CVODE flag and the plant's name) when the integration fails — the simulator then keeps
/// the last state it reached and may be reset(). A call ended by its limits (flags STEP_BUDGET, WALL_TIME_BUDGET,
/// DIVERGED) or by a stop request (sim::Interrupted, flag INTERRUPTED) leaves the simulator at the last internal
/// step it completed, ready for the next call.

#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::sim {

/// Limits of each advance()/advanceTo() call; 0 (the default) means none. A call that exceeds one ends with a
/// SolverError naming the simulated time, the flag and the plant.
struct AdvanceLimits {
  long max_steps = 0;          ///< internal solver steps per call (flag STEP_BUDGET), 0 to 1e15
  double max_wall_time = 0.0;  ///< wall-clock time per call [s] (flag WALL_TIME_BUDGET), >= 0
  /// Bound on the magnitude of every continuous state |y_i| [the state's own unit] (flag DIVERGED, naming the state
  /// and the value it reached), >= 0: a state running away (an unstable controller around the plant) ends the call
  /// at once instead of after minutes of ever smaller steps. States that grow in normal use (angles of joints and
  /// motors that may keep turning: Plant::unboundedState) are not bounded. Non-finite states and derivatives are
  /// always caught (CvodeOptions::check_finite).
  double max_state = 0.0;
  /// Root and time events per call (flag EVENT_CHATTERING): more is chattering (modes switching without end).
  long max_events = 0;
  /// Throws InputError for a negative or non-finite entry.
  void validate() const;
};

/// A complete snapshot of a simulator (Simulator::snapshot): the time, the continuous state, the plant's state
/// (inputs, controllers, sensor memory, random generator, modes, faults) and the sample phase. Copyable (a deep
/// copy); restore() it into the simulator it came from or into any simulator of the same plant object, which must
/// outlive the snapshot's use (toBytes() and loadState() carry a state to another plant object of the same
/// configuration, in this process or another).
class Snapshot {
 public:
  Snapshot() = default;
  Snapshot(const Snapshot& other);
  Snapshot& operator=(const Snapshot& other);
  Snapshot(Snapshot&&) noexcept = default;
  Snapshot& operator=(Snapshot&&) noexcept = default;
  ~Snapshot();
  double time() const { return t_; }                   ///< [s]
  const Eigen::VectorXd& state() const { return y_; }  ///< continuous state
  /// The plant's state in the snapshot (its owner() is the plant it belongs to); empty(): none.
  const PlantState& plantState() const { return *plant_state_; }
  bool empty() const { return plant_state_ == nullptr; }
  /// The snapshot as bytes (ByteWriter format: portable between processes of the same build and plant
  /// configuration); InputError for an empty snapshot.
  std::string toBytes() const;
  /// A snapshot of `plant` from toBytes(); InputError naming what did not match for bytes of another plant or
  /// configuration, of another format version, or truncated ones.
  static Snapshot fromBytes(const Plant& plant, const std::string& bytes);
  static Snapshot fromBytes(const Plant&& plant, const std::string& bytes) = delete;

 private:
  friend class Simulator;
  double t_ = 0.0, t0_ = 0.0;
  Eigen::VectorXd y_;
  std::unique_ptr<PlantState> plant_state_;
  long sample_k_ = 1;
  double t_sample_ = 0.0;
  long seen_revision_ = 0;
};

/// How advanceTo() lands on its target.
enum class Landing {
  /// The integrator stops exactly at the target (a CVODE stop time): the right landing before the inputs change.
  Stop,
  /// The integrator may step past the target (never past a sample, a time event or the run's end) and the state at
  /// the target is interpolated (CVODE's dense output, accurate to the tolerances): the landing of an output grid
  /// (sim::simulate), cheaper where outputs are dense. Inputs must not change between such calls.
  Interpolate,
};

class Simulator {
 public:
  /// Steps `plant`, which must outlive the simulator; reset() to the plant's initial state at t = 0. The plant is
  /// only read: any number of simulators (in any threads) may step one plant, each with its own state.
  explicit Simulator(const Plant& plant, const CvodeOptions& solver = {});
  /// A temporary plant would be gone after the statement: refused at compile time.
  explicit Simulator(const Plant&& plant, const CvodeOptions& solver = {}) = delete;
  /// Shares ownership of the plant (e.g. an aliasing pointer that keeps an experiment alive).
  explicit Simulator(std::shared_ptr<const Plant> plant, const CvodeOptions& solver = {});
  /// An independent copy: the same plant, settings and limits, a copy of the complete state (as snapshot() and
  /// restore()); both then continue alike, bit for bit, and neither sees the other's inputs. Copying takes a
  /// snapshot of `other` (its integrator restarts at its next step), so it is a change of `other`: not const, and not
  /// while another thread uses it.
  Simulator(Simulator& other);
  Simulator& operator=(const Simulator&) = delete;
  ~Simulator();

  /// The integrator's settings (CvodeOptions::max_num_steps caps one CVODE call, not one advance()).
  const CvodeOptions& integratorOptions() const;

  const Plant& plant() const { return *plant_; }
  std::shared_ptr<const Plant> sharedPlant() const { return plant_; }
  /// The plant's state of this run: give it to the plant's input setters (e.g. RobotSystem::setCommand) between
  /// steps. A change of inputs is picked up at the next advance (Plant::applyInputs, then a restart). reset(),
  /// restore() and loadState() replace the state: take the reference anew after them.
  PlantState& plantState() { return *state_; }
  const PlantState& plantState() const { return *state_; }

  /// Back to the plant's initialState() at t = 0 with a fresh plant state (inputs at their defaults: command
  /// ports, commands and wrenches cleared); the plant's start() is called (first controller sample).
  void reset();
  /// To state `y0` (size stateSize()) at time `t0` [s] (|t0| <= 1e9 s), with a fresh plant state; samples continue
  /// at t0 + k·T_s.
  void reset(double t0, const Eigen::VectorXd& y0);
  /// Integrates over `dt` [s] (> 0, finite); returns the time reached [s]. A target within 1e-12 s (relative)
  /// of a sample or time event is moved onto it, so steps of 1e-3 s meet samples at k·1e-3 s.
  double advance(double dt);
  /// Integrates to `t` [s] (>= time(), finite); returns the time reached. With Landing::Interpolate the target is
  /// not moved onto a nearby sample or event.
  double advanceTo(double t, Landing landing = Landing::Stop);

  double time() const { return t_; }                   ///< [s]
  const Eigen::VectorXd& state() const { return y_; }  ///< continuous state (the plant's layout)
  /// Replaces the continuous state at time() (size stateSize(), finite); the integrator restarts.
  void setState(const Eigen::VectorXd& y);

  /// The complete state now. The integrator restarts at the next advance (as it does after restore()), so that
  /// this simulator and every one restored from the snapshot continue identically, bit for bit (CVODE's step
  /// history is not part of a snapshot; the cost is one restart).
  Snapshot snapshot();
  /// Back to `snapshot` (of this plant; InputError otherwise, the simulator unchanged). Statistics are kept.
  void restore(const Snapshot& snapshot);
  /// The complete state as bytes (a snapshot serialised: portable between processes of the same build and plant
  /// configuration), and back. loadState() refuses bytes of another plant or configuration, or truncated ones, with
  /// an InputError naming what did not match; the simulator is then unchanged.
  std::string saveState();
  void loadState(const std::string& bytes);

  /// Signal names `name[unit]`, the CSV column names of the plant after "time[s]".
  const std::vector<std::string>& signalNames() const { return plant_->signalNames(); }
  /// Values of all signals at time() (in signalNames() order).
  const Eigen::VectorXd& signals() const;
  /// One signal by name, with or without its unit; InputError listing the signals when absent.
  double signal(const std::string& name) const;
  /// Index of a signal for repeated use with signals().
  int signalIndex(const std::string& name) const;

  /// Limits of every following advance()/advanceTo() call (InputError for bad values; the old ones stay).
  void setLimits(const AdvanceLimits& limits);
  const AdvanceLimits& limits() const { return limits_; }

  /// CVODE statistics since construction, over all restarts.
  SolverStats stats() const;
  long events() const { return events_; }      ///< root and time events handled
  long samples() const { return samples_; }    ///< updates of the sampled part (including the one at reset)
  long restarts() const { return restarts_; }  ///< integrator restarts (events, setState, and jumps under Restart)
  /// Input jumps (samples, input changes) integrated through with the history kept (input_jump KeepHistory, where
  /// the jump is small enough: CvodeIntegrator::jumpError ≤ 1; larger ones restart).
  long inputJumps() const { return input_jumps_; }
  /// Wall-clock time per control period since construction (PeriodWallTimes; a period spanning a reset or a restore
  /// is not counted).
  PeriodWallTimes periodWallTimes() const;

 private:
  // sim::simulate is this simulator with an output grid and the run's budgets: it runs on the caller's plant state,
  // with an end time (no sample or event at or after it; optionally a stop time there).
  friend SimulationResult simulate(const Plant& plant, PlantState& state, const SimulateOptions& options,
                                   const OutputSink& sink);
  Simulator(const Plant& plant, const CvodeOptions& solver, PlantState& borrowed, double t_end, bool stop_at_end);
  void begin(double t0, const Eigen::VectorXd& y0, std::unique_ptr<PlantState> fresh);  // reset()'s work
  // The next time the integrator must not step past (sample, event, the end with stop_at_end_, the target under
  // Landing::Stop); `horizon`: the end always (the reach of the next step, for an input jump's error estimate).
  double nextStop(double t_target, Landing landing, bool horizon) const;
  void prepare(double t_target);       // input changes and a pending sample at t_, then the restart if needed
  void takeSample();                   // the plant's sampled part at t_, next sample time, input jump pending
  void inputJumped();                  // a held input jumped at t_: a restart or a kept history, per the options
  void restartIfNeeded(double h_max);  // CVODE re-initialised at (t_, y_) when needed; h_max: to the next stop
  void refreshEvents(double t_target);
  void invalidate() { signals_valid_ = false; }
  double integrate(double stop);  // one CVODE advance towards `stop`, through its per-call step cap
  [[noreturn]] void stopped();    // the call ended by a limit or a stop request
  /// Checked in the right-hand side: a stop request, the wall-clock limit (every 256 calls), the state bound.
  void guard(double t, const Eigen::Ref<const Eigen::VectorXd>& y);

  void build(const CvodeOptions& solver);  // the integrator and the plant's constants (constructors)
  void checkSnapshot(const Snapshot& snapshot, const char* what) const;

  std::shared_ptr<const Plant> plant_;
  PlantState* state_ = nullptr;        // the run's plant state: owned_, or the one sim::simulate runs on
  std::unique_ptr<PlantState> owned_;  // the state when this simulator owns it (always, but inside sim::simulate)
  // The run's end (sim::simulate; infinite for stepping): no sample or time event at or after it is taken; a stop
  // time there when stop_at_end_.
  double end_ = std::numeric_limits<double>::infinity();
  bool stop_at_end_ = false;
  Landing landing_ = Landing::Stop;  // of the current call
  std::unique_ptr<Integrator> integ_;
  std::string component_;
  double t_ = 0.0, t0_ = 0.0;
  Eigen::VectorXd y_, y_work_, f_work_;
  Eigen::VectorXd f_old_;  // ẏ at (t_, y_) with the inputs before a jump (KeepHistory)
  bool restart_ = true;
  bool jump_ = false;  // an input jumped at t_ (counted once, when the integration goes on)
  // The pending restart has a cause other than an input jump (start, event, state change, solver failure): the
  // Jacobian is then evaluated afresh; after an input jump alone the restart starts with the last one.
  bool fresh_jacobian_ = true;
  bool keep_history_ = true;
  long seen_revision_ = 0;
  // Sampled part: next sample at t0 + k·T_s.
  double Ts_ = 0.0;
  long sample_k_ = 1;
  double t_sample_ = 0.0;
  // Time events of the plant up to horizon_, sorted; next_event_ indexes the first one after t_.
  std::vector<double> events_list_;
  double horizon_ = 0.0;
  size_t next_event_ = 0;
  long events_ = 0, samples_ = 0, restarts_ = 0, input_jumps_ = 0;
  // Wall time per control period: a histogram of 100 bins per decade from 1e-7 s (bin 0 holds shorter ones, the
  // last longer ones), the longest, and the clock at the last sample (NaN: none since a reset/setState/restore).
  static constexpr int kPeriodBins = 900;
  std::array<long, kPeriodBins> period_hist_{};
  long periods_ = 0;
  double period_max_ = 0.0;
  double last_sample_clock_ = std::numeric_limits<double>::quiet_NaN();
  // The call's limits and why the right-hand side ended it (empty: it did not).
  AdvanceLimits limits_;
  std::vector<char> bounded_;   // per state: subject to max_state (not Plant::unboundedState)
  double call_deadline_ = 0.0;  // steady-clock seconds at which the call's wall-clock limit runs out (0: none)
  long guard_calls_ = 0;
  std::string stop_flag_, stop_message_;
  int stop_signal_ = 0;
  mutable Eigen::VectorXd signals_;
  mutable bool signals_valid_ = false;
  mutable long signals_revision_ = 0;
};

}  // namespace jointsim::sim
