#include "jointsim/sim/simulator.hpp"
#include "jointsim/sim/fixed_step_integrator.hpp"
#include "jointsim/sim/simulate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include "common/constants.hpp"
#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::sim {

namespace {
/// A target this close (relative to max(1, |t|)) to a sample or time event is moved onto it.
constexpr double kSnap = 1e-12;
bool near(double a, double b) { return std::abs(a - b) <= kSnap * std::max(1.0, std::abs(b)); }
double clockSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
/// Largest magnitude of a simulator's time [s] (31 years): beyond it the sample and event arithmetic loses its
/// resolution (a sample period below the spacing of doubles would never advance).
constexpr double kMaxTime = 1e9;
/// Thrown through CVODE by the right-hand side's guard: the call ends (Simulator::stopped).
struct StopAdvance {};
/// Largest step limit of a call (far beyond any run; keeps the step arithmetic of the limit far from overflow).
constexpr long kMaxStepsLimit = 1'000'000'000'000'000L;
/// CVODE's cap of steps per call (max_num_steps) ends an advance() only where those steps covered less than this
/// much simulated time each on average: the integration is stuck (chattering, a discontinuity the solver keeps
/// failing on), not merely long [s].
constexpr double kStuckMeanStep = 1e-9;
/// In a stop message, where the simulated time at which the simulator stands is put (Simulator::stopped).
constexpr const char* kAt = "{t}";
}  // namespace

void AdvanceLimits::validate() const {
  if (max_steps < 0 || max_steps > kMaxStepsLimit)
    throw InputError("advance limits: max_steps: expected a number of steps from 0 (none) to 1e15, got " +
                     std::to_string(max_steps));
  if (!(max_wall_time >= 0.0) || !std::isfinite(max_wall_time))
    throw InputError("advance limits: max_wall_time: expected a finite time >= 0 s (0: none), got " +
                     formatNumber(max_wall_time));
  if (!(max_state >= 0.0) || !std::isfinite(max_state))
    throw InputError("advance limits: max_state: expected a finite bound >= 0 (0: none), got " +
                     formatNumber(max_state));
  if (max_events < 0)
    throw InputError("advance limits: max_events: expected a number of events >= 0 (0: none), got " +
                     std::to_string(max_events));
}

namespace {
/// First field of a saved state, and its format version.
constexpr const char* kStateMagic = "jointsim simulator state";
constexpr std::uint64_t kStateVersion = 3;  // 2: the robot's relative-replay anchors; 3: its load torques
}  // namespace

Snapshot::Snapshot(const Snapshot& other)
    : t_(other.t_),
      t0_(other.t0_),
      y_(other.y_),
      plant_state_(other.plant_state_ ? other.plant_state_->clone() : nullptr),
      sample_k_(other.sample_k_),
      t_sample_(other.t_sample_),
      seen_revision_(other.seen_revision_) {}

Snapshot& Snapshot::operator=(const Snapshot& other) {
  if (this != &other) *this = Snapshot(other);
  return *this;
}

Snapshot::~Snapshot() = default;

Simulator::Simulator(const Plant& plant, const CvodeOptions& solver)
    : Simulator(std::shared_ptr<const Plant>(&plant, [](const Plant*) {}), solver) {}

Simulator::Simulator(std::shared_ptr<const Plant> plant, const CvodeOptions& solver) : plant_(std::move(plant)) {
  if (!plant_) throw InputError("Simulator: no plant given");
  build(solver);
  reset();
}

Simulator::Simulator(Simulator& other) : plant_(other.plant_), limits_(other.limits_) {
  build(other.integ_->options());
  end_ = other.end_;
  stop_at_end_ = other.stop_at_end_;
  restore(other.snapshot());
}

Simulator::Simulator(const Plant& plant, const CvodeOptions& solver, PlantState& borrowed, double t_end,
                     bool stop_at_end)
    : plant_(std::shared_ptr<const Plant>(&plant, [](const Plant*) {})) {
  build(solver);
  end_ = t_end;
  stop_at_end_ = stop_at_end;
  owned_.reset();
  state_ = &borrowed;
  begin(0.0, plant.initialState(), nullptr);
}

void Simulator::build(const CvodeOptions& solver) {
  CvodeOptions options = solver;
  if (options.component.empty()) options.component = plant_->name();
  if (!options.state_name) {
    const Plant* p = plant_.get();  // owned by this simulator, which owns the integrator
    options.state_name = [p](int i) { return p->stateName(i); };
  }
  component_ = options.component;
  plant_->freeze();  // shared from now on: its configuration must not change under its simulators' states
  keep_history_ = options.input_jump == CvodeOptions::InputJump::KeepHistory;
  const int n = plant_->stateSize();
  owned_ = plant_->makeState();
  state_ = owned_.get();
  const Plant* p = plant_.get();
  // The callbacks read the state through this simulator: restore() may replace it.
  Ts_ = p->samplePeriod();
  if (!(Ts_ >= 0.0) || !std::isfinite(Ts_)) throw InputError(p->name() + ": sample period must be >= 0 s");
  RhsFunction rhs = [this, p](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
    guard(t, y);
    p->derivatives(*state_, t, y, yd);
  };
  if (options.method == Method::Rosenbrock) {
    options.fixed_step = fixedStep(*p, options.fixed_step);
    integ_ = std::make_unique<FixedStepIntegrator>(n, std::move(rhs), options);
  } else {
    integ_ = std::make_unique<CvodeIntegrator>(n, std::move(rhs), options);
  }
  const CvodeOptions& o = integ_->options();
  if (p->providesJacobian() && o.plant_jacobian && o.method != Method::Adams) {
    const JacobianKind kind = jacobianKind(o);
    integ_->setDifferenceJacobian(
        [this, p, kind](double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                        const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                        Eigen::Ref<Eigen::MatrixXd> J) { p->jacobian(*state_, t, y, f, inc, J, kind); });
    JacobianStructure structure = p->jacobianStructure();
    if (!structure.empty() && o.dense_solver == CvodeOptions::DenseSolver::Eigen)
      integ_->setJacobianStructure(std::move(structure));
  }
  integ_->setTimeInvariance([this, p] { return p->timeInvariant(*state_); });
  integ_->setOscillatoryStates(p->oscillatoryStates());
  if (p->rootCount() > 0)
    integ_->setRootFunction(p->rootCount(), [this, p](double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                                                      Eigen::Ref<Eigen::VectorXd> g) { p->roots(*state_, t, y, g); });
  bounded_.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) bounded_[static_cast<size_t>(i)] = !p->unboundedState(i);
  signals_.setZero(static_cast<Eigen::Index>(p->signalNames().size()));
  f_work_.setZero(n);
  f_old_.setZero(n);
}

double fixedStep(const Plant& plant, double step) {
  const double Ts = plant.samplePeriod();
  if (step == 0.0) {
    if (Ts > 0.0) return Ts;
    throw InputError(plant.name() +
                     ": the fixed-step method (rosenbrock) needs its step (solver.step [s]): the plant has no sampled "
                     "controller whose period it could take");
  }
  if (!(step > 0.0) || !std::isfinite(step))
    throw InputError(plant.name() + ": the fixed step: expected a finite step > 0 s, got " + formatNumber(step));
  if (Ts > 0.0) {
    const double ratio = Ts / step, k = std::round(ratio);
    if (k < 1.0 || std::abs(ratio - k) > 1e-9 * ratio)
      throw InputError(plant.name() + ": the fixed step: expected the control period " + formatNumber(Ts) +
                       " s or an integer fraction of it (the fixed steps are locked to the control clock), got " +
                       formatNumber(step) + " s");
    return Ts / k;
  }
  return step;
}

Simulator::~Simulator() = default;

void Simulator::reset() {
  const Eigen::VectorXd y0 = plant_->initialState();
  reset(0.0, y0);
}

void Simulator::reset(double t0, const Eigen::VectorXd& y0) {
  const int n = plant_->stateSize();
  if (!(std::abs(t0) <= kMaxTime))
    throw InputError(plant_->name() + ": reset: expected a time within ±" + formatNumber(kMaxTime) + " s, got " +
                     formatNumber(t0));
  if (Ts_ > 0.0 && !(t0 + 2.0 * Ts_ > t0 + Ts_))
    throw InputError(plant_->name() + ": reset: at t = " + formatNumber(t0) + " s the sample period " +
                     formatNumber(Ts_) + " s is below the time resolution");
  if (y0.size() != n)
    throw InputError(plant_->name() + ": reset: the state has " + std::to_string(y0.size()) + " entries, expected " +
                     std::to_string(n));
  if (!y0.allFinite()) throw InputError(plant_->name() + ": reset: the state must be finite");
  begin(t0, y0, plant_->makeState());
}

void Simulator::begin(double t0, const Eigen::VectorXd& y0, std::unique_ptr<PlantState> fresh) {
  plant_->start(fresh ? *fresh : *state_, t0, y0);
  if (fresh) {
    owned_ = std::move(fresh);
    state_ = owned_.get();
  }
  t_ = t0_ = t0;
  y_ = y0;
  y_work_ = y0;
  samples_ += Ts_ > 0.0 ? 1 : 0;
  last_sample_clock_ = std::numeric_limits<double>::quiet_NaN();
  sample_k_ = 1;
  t_sample_ = Ts_ > 0.0 ? t0 + Ts_ : kInf;
  events_list_.clear();
  horizon_ = t0;
  next_event_ = 0;
  seen_revision_ = state_->inputRevision();
  restart_ = fresh_jacobian_ = true;
  jump_ = false;
  invalidate();
}

void Simulator::setState(const Eigen::VectorXd& y) {
  if (y.size() != plant_->stateSize())
    throw InputError(plant_->name() + ": setState: the state has " + std::to_string(y.size()) + " entries, expected " +
                     std::to_string(plant_->stateSize()));
  if (!y.allFinite()) throw InputError(plant_->name() + ": setState: the state must be finite");
  y_ = y;
  restart_ = fresh_jacobian_ = true;
  invalidate();
}

Snapshot Simulator::snapshot() {
  Snapshot s;
  s.t_ = t_;
  s.t0_ = t0_;
  s.y_ = y_;
  s.plant_state_ = state_->clone();
  s.sample_k_ = sample_k_;
  s.t_sample_ = t_sample_;
  s.seen_revision_ = seen_revision_;
  // Continue from here as a restored copy would: with a fresh start of the integrator.
  restart_ = fresh_jacobian_ = true;
  return s;
}

void Simulator::checkSnapshot(const Snapshot& snapshot, const char* what) const {
  if (snapshot.empty()) throw InputError(plant_->name() + ": " + what + ": the snapshot is empty");
  if (snapshot.plant_state_->ownerId() != plant_->id())  // (that plant may be gone: it is not asked for its name)
    throw InputError(plant_->name() + ": " + what +
                     ": the snapshot is of another plant object (restore bytes of it, loadState, to move a state "
                     "between plant objects of the same configuration)");
  // The sample phase as reset() and takeSample() make it: the next sample at t0 + k·T_s, not before the time and at
  // most one period after it (none without a sampled part).
  const Snapshot& s = snapshot;
  const double tol = 1e-9 * std::max(1.0, std::abs(s.t_));
  const bool phase_ok = Ts_ > 0.0 ? s.sample_k_ >= 1 && s.sample_k_ < (1L << 52) && std::isfinite(s.t_sample_) &&
                                        s.t_sample_ == s.t0_ + static_cast<double>(s.sample_k_) * Ts_ &&
                                        s.t_sample_ >= s.t_ - tol && s.t_sample_ <= s.t_ + Ts_ + tol &&
                                        s.t_sample_ + Ts_ > s.t_sample_
                                  : s.t_sample_ == kInf;
  if (s.y_.size() != plant_->stateSize() || !s.y_.allFinite() || !(std::abs(s.t_) <= kMaxTime) ||
      !(std::abs(s.t0_) <= kMaxTime) || !(s.t0_ <= s.t_) || !phase_ok)
    throw InputError(plant_->name() + ": " + what + ": an inconsistent snapshot (time " + formatNumber(snapshot.t_) +
                     " s, " + std::to_string(snapshot.y_.size()) + " states, next sample at " +
                     formatNumber(snapshot.t_sample_) + " s)");
}

void Simulator::restore(const Snapshot& snapshot) {
  checkSnapshot(snapshot, "restore");
  owned_ = snapshot.plant_state_->clone();
  state_ = owned_.get();
  t_ = snapshot.t_;
  t0_ = snapshot.t0_;
  y_ = snapshot.y_;
  y_work_ = y_;
  sample_k_ = snapshot.sample_k_;
  t_sample_ = snapshot.t_sample_;
  seen_revision_ = snapshot.seen_revision_;
  last_sample_clock_ = std::numeric_limits<double>::quiet_NaN();
  events_list_.clear();
  horizon_ = t_;
  next_event_ = 0;
  restart_ = fresh_jacobian_ = true;
  jump_ = false;
  invalidate();
}

std::string Snapshot::toBytes() const {
  if (empty()) throw InputError("Snapshot::toBytes: the snapshot is empty");
  const Plant& plant = plant_state_->owner();
  ByteWriter out;
  out.tag(kStateMagic);
  out.u64(kStateVersion);
  out.text(plant.name());
  out.f64(t_);
  out.f64(t0_);
  out.vector(y_);
  out.i64(sample_k_);
  out.f64(t_sample_);
  out.boolean(seen_revision_ != plant_state_->inputRevision());  // an input change not yet applied
  out.tag("plant state");
  plant_state_->save(out);
  out.tag("end");
  return out.release();
}

Snapshot Snapshot::fromBytes(const Plant& plant, const std::string& bytes) {
  ByteReader in(bytes, plant.name() + ": a saved simulator state");
  in.tag(kStateMagic);
  const std::uint64_t version = in.u64("version");
  if (version != kStateVersion)
    in.fail("a state of format version " + std::to_string(version) + ", this build reads version " +
            std::to_string(kStateVersion));
  const std::string name = in.text("plant");
  if (name != plant.name()) in.fail("a state of '" + name.substr(0, 200) + "', not of this plant");
  Snapshot s;
  s.t_ = in.f64("time");
  s.t0_ = in.f64("start time");
  s.y_ = in.vector("continuous state", plant.stateSize());
  s.sample_k_ = in.i64("sample index");
  s.t_sample_ = in.f64("next sample time");
  const bool pending = in.boolean("input change pending");
  in.tag("plant state");
  s.plant_state_ = plant.makeState();
  s.plant_state_->load(in);
  in.tag("end");
  in.finish();
  s.seen_revision_ = s.plant_state_->inputRevision() - (pending ? 1 : 0);
  return s;
}

std::string Simulator::saveState() { return snapshot().toBytes(); }

void Simulator::loadState(const std::string& bytes) { restore(Snapshot::fromBytes(*plant_, bytes)); }

void Simulator::setLimits(const AdvanceLimits& limits) {
  limits.validate();
  limits_ = limits;
}

void Simulator::guard(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (const int sig = stopRequested()) {
    stop_flag_ = "INTERRUPTED";
    stop_signal_ = sig;
    stop_message_ = "interrupted (signal " + std::to_string(sig) + ") at t = " + kAt + " s";
    throw StopAdvance{};
  }
  if (call_deadline_ > 0.0 && (++guard_calls_ & 255) == 0 && clockSeconds() > call_deadline_) {
    stop_flag_ = "WALL_TIME_BUDGET";
    stop_message_ = "more than the call's wall-clock limit of " + formatNumber(limits_.max_wall_time) +
                    " s (max_wall_time); stopped at t = " + kAt + " s";
    throw StopAdvance{};
  }
  if (limits_.max_state > 0.0) {
    for (Eigen::Index i = 0; i < y.size(); ++i) {
      if (!(std::abs(y[i]) > limits_.max_state) || !bounded_[static_cast<size_t>(i)]) continue;
      const std::string what = plant_->stateName(static_cast<int>(i));
      stop_flag_ = "DIVERGED";
      stop_message_ = "the state diverged after t = " + std::string(kAt) + " s: state " + std::to_string(i) +
                      (what.empty() ? std::string() : " (" + what + ")") + " reached " + formatNumber(y[i], 4) +
                      " in the next step, beyond the bound max_state = " + formatNumber(limits_.max_state) +
                      " (an unstable controller or input?)";
      throw StopAdvance{};
    }
  }
}

double Simulator::integrate(double stop) {
  double chunk_start = t_;
  for (;;) {
    try {
      return integ_->advance(stop, y_work_);
    } catch (const SolverError& e) {
      if (!stop_flag_.empty()) stopped();
      if (e.flag() == "STEP_BUDGET") {
        stop_flag_ = "STEP_BUDGET";
        stop_message_ = "more than the call's " + std::to_string(limits_.max_steps) +
                        " internal steps (max_steps); stopped at t = " + kAt + " s";
        stopped();
      }
      if (e.flag() != "CV_TOO_MUCH_WORK") throw;
      if (std::string(e.what()).find("the step size collapsed") != std::string::npos) {
        // The integrator's collapse check (CvodeOptions::collapse_mean_step): stuck, with the time and the limiting
        // state in its message.
        stop_flag_ = "CV_TOO_MUCH_WORK";
        stop_message_ = e.what();
        stopped();
      }
      // CVODE's cap of steps per CVode call (CvodeOptions::max_num_steps), not a failure: one advance() may be as
      // long as wanted (its own limits end it). CVODE goes on from its last step; the simulator's state follows.
      // Unless those steps hardly moved: then the integration is stuck, and going on would never end.
      const double tn = integ_->lastStep(y_work_);
      const long cap = integ_->options().max_num_steps;
      if (!std::isfinite(tn) || tn - chunk_start < static_cast<double>(cap) * kStuckMeanStep) {
        stop_flag_ = "CV_TOO_MUCH_WORK";
        stop_message_ = std::to_string(cap) + " internal steps covered only " +
                        formatNumber(std::isfinite(tn) ? tn - chunk_start : 0.0, 3) + " s up to t = " + kAt +
                        " s: the integration is stuck (chattering modes, or a discontinuity the solver keeps "
                        "failing on; see the solver settings)";
        stopped();
      }
      t_ = tn;
      y_ = y_work_;
      invalidate();
      chunk_start = tn;
    }
  }
}

void Simulator::stopped() {
  // Go on from the last completed internal step at the next call (a restart: the interrupted step left CVODE's
  // history in an unknown state).
  const double tn = integ_->lastStep(y_work_);
  if (std::isfinite(tn) && tn > t_ && y_work_.allFinite()) {
    t_ = tn;
    y_ = y_work_;
  }
  restart_ = fresh_jacobian_ = true;
  invalidate();
  std::string text = stop_message_;
  const std::string at = formatNumber(t_);
  for (size_t k = text.find(kAt); k != std::string::npos; k = text.find(kAt, k + at.size()))
    text.replace(k, std::char_traits<char>::length(kAt), at);
  const std::string flag = stop_flag_, message = plant_->name() + ": " + text;
  const int signal = stop_signal_;
  stop_flag_.clear();
  if (flag == "INTERRUPTED") {
    SimulationResult partial;
    partial.sim_time_s = t_;
    partial.stats = integ_->stats();
    throw Interrupted(SolverError(message, t_, flag, component_), partial, signal);
  }
  throw SolverError(message, t_, flag, component_);
}

void Simulator::refreshEvents(double t_target) {
  if (t_target <= horizon_ && horizon_ > t0_) return;
  // The plant lists its events in (0, t_end): ask for a horizon well beyond the target, so that a loop of small
  // steps asks rarely.
  // A run with an end (sim::simulate) asks once, for all its events before the end.
  const double horizon = std::isfinite(end_) ? end_ : std::max(t_target, t_ + std::max(1.0, 2.0 * (horizon_ - t0_)));
  events_list_.clear();
  for (double e : plant_->timeEvents(horizon))
    if (e > t_ && !near(t_, e) && e < end_ && std::isfinite(e)) events_list_.push_back(e);
  std::sort(events_list_.begin(), events_list_.end());
  events_list_.erase(std::unique(events_list_.begin(), events_list_.end()), events_list_.end());
  horizon_ = horizon;
  next_event_ = 0;
}

void Simulator::takeSample() {
  const double now = clockSeconds();
  if (!std::isnan(last_sample_clock_)) {
    const double dt = now - last_sample_clock_;
    const int bin = dt > 1e-7 ? std::min(kPeriodBins - 1, static_cast<int>(100.0 * std::log10(dt / 1e-7))) : 0;
    ++period_hist_[static_cast<size_t>(bin)];
    ++periods_;
    period_max_ = std::max(period_max_, dt);
  }
  last_sample_clock_ = now;
  // f before the held inputs jump, for the jump's error estimate (none for a fixed-step method: it keeps no history).
  if (keep_history_ && !jump_ && !integ_->jumpErrorIsZero()) plant_->derivatives(*state_, t_, y_, f_old_);
  plant_->sample(*state_, t_, y_);
  ++samples_;
  t_sample_ = t0_ + static_cast<double>(++sample_k_) * Ts_;
  inputJumped();
  invalidate();
}

PeriodWallTimes Simulator::periodWallTimes() const {
  PeriodWallTimes w;
  w.periods = periods_;
  w.max_s = period_max_;
  if (periods_ == 0) return w;
  auto quantile = [&](double q) {  // the upper edge of the bin holding the ⌈q·n⌉-th shortest period
    const auto rank = static_cast<long>(std::ceil(q * static_cast<double>(periods_)));
    long seen = 0;
    for (int b = 0; b < kPeriodBins; ++b) {
      seen += period_hist_[static_cast<size_t>(b)];
      if (seen >= rank)  // (the last bin holds everything longer than 100 s: its quantile is the maximum)
        return b == kPeriodBins - 1 ? period_max_ : std::min(period_max_, 1e-7 * std::pow(10.0, (b + 1) / 100.0));
    }
    return period_max_;
  };
  w.p50_s = quantile(0.5);
  w.p99_s = quantile(0.99);
  return w;
}

void Simulator::inputJumped() {
  if (keep_history_)
    jump_ = true;
  else
    restart_ = true;
}

void Simulator::restartIfNeeded(double h_max) {
  if (jump_ && !restart_) {
    // Keep the history only where the jump leaves the next step within the error test (CvodeOptions::input_jump);
    // a fixed-step method keeps none, so there is nothing to estimate.
    bool keep = integ_->jumpErrorIsZero();
    if (!keep) {
      plant_->derivatives(*state_, t_, y_, f_work_);
      keep = integ_->jumpError(f_old_, f_work_, h_max) <= kKeepHistoryLimit;
    }
    if (keep)
      ++input_jumps_;  // CVODE stopped exactly here (a stop time) and goes on with the new right-hand side
    else
      restart_ = true;
  }
  if (restart_) {
    integ_->initialize(t_, y_, !fresh_jacobian_);
    ++restarts_;
  }
  restart_ = jump_ = fresh_jacobian_ = false;
}

void Simulator::prepare(double t_target) {
  const long revision = state_->inputRevision();
  if (revision != seen_revision_) {
    seen_revision_ = revision;
    y_work_ = y_;
    plant_->applyInputs(*state_, t_, y_);
    if (y_ != y_work_)
      restart_ = fresh_jacobian_ =
          true;  // the plant moved states (bumpless transfer): CVODE's history no longer matches
    else
      inputJumped();
    invalidate();
  }
  // A sample due at the end of the last advance (a step landing within the snap distance of it counts).
  if (Ts_ > 0.0 && t_sample_ < end_ && (t_ >= t_sample_ || (landing_ == Landing::Stop && near(t_, t_sample_))))
    takeSample();
  restartIfNeeded(nextStop(t_target, landing_, true) - t_);
}

double Simulator::nextStop(double t_target, Landing landing, bool horizon) const {
  const double t_event = next_event_ < events_list_.size() ? events_list_[next_event_] : kInf;
  double stop = std::min(t_event, t_sample_ < end_ ? t_sample_ : kInf);
  if (landing == Landing::Stop) stop = std::min(stop, t_target);
  // The end bounds the next step as a stop time, and always the horizon of an input jump's error estimate.
  if (stop_at_end_ || horizon) stop = std::min(stop, end_);
  return stop;
}

double Simulator::advance(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw InputError(plant_->name() + ": advance: expected a finite time step > 0 s, got " + formatNumber(dt));
  return advanceTo(t_ + dt);
}

double Simulator::advanceTo(double t_target, Landing landing) {
  if (!std::isfinite(t_target) || t_target < t_)
    throw InputError(plant_->name() + ": advanceTo: expected a finite time >= the current time " + formatNumber(t_) +
                     " s, got " + formatNumber(t_target));
  if (t_target == t_) return t_;
  landing_ = landing;
  refreshEvents(t_target);
  if (landing == Landing::Stop) {
    // Snap the target onto a sample or event it nearly meets (accumulated rounding of t + dt).
    if (Ts_ > 0.0 && near(t_target, t_sample_)) t_target = t_sample_;
    if (next_event_ < events_list_.size() && near(t_target, events_list_[next_event_]))
      t_target = events_list_[next_event_];
    refreshEvents(t_target);  // a no-op unless the snap moved the target past the horizon
  }
  // The call's limits: a step budget over all segments from here, a wall-clock deadline for the guard.
  stop_flag_.clear();
  guard_calls_ = 0;
  call_deadline_ = limits_.max_wall_time > 0.0 ? clockSeconds() + limits_.max_wall_time : 0.0;
  integ_->setStepLimit(limits_.max_steps > 0 ? integ_->steps() + limits_.max_steps : 0);
  long events_here = 0;
  try {
    prepare(t_target);
    while (t_ < t_target) {
      const double t_event = next_event_ < events_list_.size() ? events_list_[next_event_] : kInf;
      // The integrator never steps past the next stop (sample, event, the end, and the target when landing there);
      // it returns at the target, interpolating when it stepped past it.
      const double stop = nextStop(t_target, landing, false);
      if (std::isfinite(stop)) integ_->setStopTime(stop);
      const double t = integrate(std::min(t_target, std::min(t_sample_, t_event)));
      t_ = t;
      y_ = y_work_;
      invalidate();
      const bool root = integ_->rootFound();
      const bool at_event = t_ >= t_event;
      const bool at_sample = t_ >= t_sample_ && t_ < t_target;  // a sample at the target waits for prepare()
      if (root || at_event) {
        if (at_event)
          while (next_event_ < events_list_.size() &&
                 (events_list_[next_event_] <= t_ || near(t_, events_list_[next_event_])))
            ++next_event_;
        plant_->updateModes(*state_, t_, y_, root ? integ_->rootDirections() : std::vector<int>{});
        ++events_;
        restart_ = fresh_jacobian_ = true;
        if (limits_.max_events > 0 && ++events_here > limits_.max_events)
          throw SolverError(plant_->name() + ": more than " + std::to_string(limits_.max_events) +
                                " events in one call (chattering) at t = " + formatNumber(t_) + " s",
                            t_, "EVENT_CHATTERING", component_);
      }
      if (at_sample) takeSample();
      // At the target: the next advance restarts or goes on (after its inputs).
      if (t_ < t_target) restartIfNeeded(nextStop(t_target, landing, true) - t_);
    }
  } catch (const SolverError&) {
    restart_ = fresh_jacobian_ = true;  // the integrator's history is unusable; y_ is the last state reached
    throw;
  }
  // The derivative with the inputs in force now: the reference for an input change before the next advance (none
  // between the calls of an output grid).
  if (keep_history_ && landing == Landing::Stop && !integ_->jumpErrorIsZero())
    plant_->derivatives(*state_, t_, y_, f_old_);
  return t_;
}

const Eigen::VectorXd& Simulator::signals() const {
  // The signals depend on the inputs too (e.g. a voltage command): recomputed after either changed.
  if (!signals_valid_ || signals_revision_ != state_->inputRevision()) {
    plant_->signals(*state_, t_, y_, signals_);
    signals_valid_ = true;
    signals_revision_ = state_->inputRevision();
  }
  return signals_;
}

int Simulator::signalIndex(const std::string& name) const { return sim::signalIndex(*plant_, name); }

double Simulator::signal(const std::string& name) const { return signals()[signalIndex(name)]; }

SolverStats Simulator::stats() const { return integ_->stats(); }

const CvodeOptions& Simulator::integratorOptions() const { return integ_->options(); }

}  // namespace jointsim::sim
