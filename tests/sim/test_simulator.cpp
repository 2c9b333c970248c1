// sim::Simulator: stepping with inputs, root events, samples and time events against closed forms, and
// against the one simulate loop on a shipped experiment; snapshots (restore, saved bytes, copies) repeat a run bit
// for bit.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/sim/simulator.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

/// ẏ = −a y + u with an input u set between steps: y(t) = u/a + (y(t0) − u/a) e^{−a (t − t0)}.
class FirstOrder : public sim::Plant {
 public:
  /// The run's input u (held between steps; 0 in a fresh state).
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double u = 0.0;
    void save(ByteWriter& out) const override { out.f64(u); }
    void load(ByteReader& in) override { u = in.f64("u"); }
  };
  double a = 2.0;
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  void setInput(sim::PlantState& state, double u) const {
    State& s = own<State>(state);
    if (u != s.u) {
      s.u = u;
      s.inputsChanged();
    }
  }
  double input(const sim::PlantState& state) const { return own<State>(state).u; }
  std::string name() const override { return "first order"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Constant(1, 1.0); }
  void derivatives(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = -a * y[0] + own<State>(state).u;
  }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
    out[1] = own<State>(state).u;
  }

 private:
  std::vector<std::string> names_{"y[1]", "u[1]"};
};

sim::CvodeOptions tight() {
  sim::CvodeOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  return o;
}

TEST(Simulator, InputStepsFollowTheClosedFormAndRestartOnlyWhenTheInputJumps) {
  FirstOrder p;
  sim::Simulator s(p, tight());
  EXPECT_EQ(s.time(), 0.0);
  // u = 0 until 0.5 s, then u = 3 (two calls with the same value: one jump).
  for (int k = 0; k < 50; ++k) s.advance(0.01);
  const long restarts_before = s.restarts();
  EXPECT_NEAR(s.state()[0], std::exp(-2.0 * 0.5), 1e-9);
  const double y05 = s.state()[0];
  p.setInput(s.plantState(), 3.0);
  p.setInput(s.plantState(), 3.0);
  for (int k = 0; k < 50; ++k) {
    s.advance(0.01);
    p.setInput(s.plantState(), 3.0);  // unchanged: no restart
  }
  EXPECT_EQ(s.restarts(), restarts_before + 1);
  EXPECT_NEAR(s.time(), 1.0, 1e-12);
  EXPECT_NEAR(s.state()[0], 1.5 + (y05 - 1.5) * std::exp(-2.0 * 0.5), 1e-9);
  EXPECT_DOUBLE_EQ(s.signal("u"), 3.0);
  EXPECT_DOUBLE_EQ(s.signal("y[1]"), s.state()[0]);
  // The signals follow an input change before the next step.
  p.setInput(s.plantState(), -1.0);
  EXPECT_DOUBLE_EQ(s.signal("u"), -1.0);
  const double y1 = 1.5 + (y05 - 1.5) * std::exp(-1.0);
  s.advanceTo(1.2);
  EXPECT_NEAR(s.state()[0], -0.5 + (y1 + 0.5) * std::exp(-0.4), 1e-9);
  // reset() goes back to the initial state at t = 0.
  s.reset();
  EXPECT_EQ(s.time(), 0.0);
  EXPECT_EQ(s.state()[0], 1.0);
}

TEST(Simulator, BadTimesAndStatesAreInputErrorsAndLeaveTheSimulatorUnchanged) {
  FirstOrder p;
  sim::Simulator s(p, tight());
  s.advance(0.1);
  const double t = s.time();
  const double y = s.state()[0];
  EXPECT_THROW(s.advance(0.0), InputError);
  EXPECT_THROW(s.advance(-1.0), InputError);
  EXPECT_THROW(s.advance(std::nan("")), InputError);
  EXPECT_THROW(s.advanceTo(0.05), InputError);
  EXPECT_THROW(s.advanceTo(INFINITY), InputError);
  EXPECT_THROW(s.setState(Eigen::VectorXd::Zero(2)), InputError);
  EXPECT_THROW(s.setState(Eigen::VectorXd::Constant(1, std::nan(""))), InputError);
  EXPECT_THROW(s.reset(0.0, Eigen::VectorXd::Zero(3)), InputError);
  EXPECT_THROW(s.signal("nope"), InputError);
  EXPECT_EQ(s.time(), t);
  EXPECT_EQ(s.state()[0], y);
  // setState restarts from the given state: the closed form from there.
  s.setState(Eigen::VectorXd::Constant(1, 4.0));
  s.advance(0.25);
  EXPECT_NEAR(s.state()[0], 4.0 * std::exp(-0.5), 1e-6);
}

/// ẏ = m with a mode m ∈ {+1, −1} switched by root functions at y = ±1: a triangle wave of period 4 s.
class Triangle : public sim::Plant {
 public:
  /// The run's mode m and the number of switches so far.
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double m = 1.0;
    long switches = 0;
    void save(ByteWriter& out) const override {
      out.f64(m);
      out.i64(switches);
    }
    void load(ByteReader& in) override {
      m = in.f64("mode");
      if (m != 1.0 && m != -1.0) in.fail("mode: expected +1 or -1");
      switches = in.i64("switches");
    }
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  std::string name() const override { return "triangle"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Zero(1); }
  void derivatives(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = own<State>(state).m;
  }
  int rootCount() const override { return 2; }
  void roots(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override {
    g[0] = y[0] - 1.0;
    g[1] = y[0] + 1.0;
  }
  void updateModes(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   const std::vector<int>& fired) const override {
    State& s = own<State>(state);
    const double before = s.m;
    if (fired.size() == 2 && fired[0] > 0) s.m = -1.0;  // reaching +1 from below
    if (fired.size() == 2 && fired[1] < 0) s.m = 1.0;   // reaching −1 from above
    s.switches += s.m != before;
  }
  long switches(const sim::PlantState& state) const { return own<State>(state).switches; }
  double mode(const sim::PlantState& state) const { return own<State>(state).m; }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }

 private:
  std::vector<std::string> names_{"y[1]"};
};

TEST(Simulator, RootEventsInsideASteppedRun) {
  Triangle p;
  sim::Simulator s(p, tight());
  for (int k = 1; k <= 350; ++k) {
    s.advance(0.01);
    const double t = s.time();
    const double ph = std::fmod(t + 1.0, 4.0);  // triangle: 0 at t = 0 rising
    const double expected = ph < 2.0 ? ph - 1.0 : 3.0 - ph;
    ASSERT_NEAR(s.state()[0], expected, 1e-8) << "t = " << t;
  }
  EXPECT_EQ(p.switches(s.plantState()), 2);  // at t = 1 and t = 3
  EXPECT_GE(s.events(), 2);
}

/// A sampled feedback ẏ = u_k, u_k = −y(t_k) held over [t_k, t_k + T): y(t_k) = (1 − T)^k y0, linear in between.
/// A time event at 0.35 s (no effect on the physics) must not disturb it.
class SampledDecay : public sim::Plant {
 public:
  /// The run's held input u_k and the number of time events seen.
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double u = 0.0;
    long events = 0;
    void save(ByteWriter& out) const override {
      out.f64(u);
      out.i64(events);
    }
    void load(ByteReader& in) override {
      u = in.f64("u");
      events = in.i64("events");
    }
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  std::string name() const override { return "sampled decay"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Constant(1, 1.0); }
  void derivatives(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = own<State>(state).u;
  }
  std::vector<double> timeEvents(double t_end) const override {
    return t_end > 0.35 ? std::vector<double>{0.35} : std::vector<double>{};
  }
  void updateModes(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   const std::vector<int>&) const override {
    ++own<State>(state).events;
  }
  void start(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    own<State>(state).u = -y[0];
  }
  double samplePeriod() const override { return 0.1; }
  void sample(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    own<State>(state).u = -y[0];
  }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }
  long events(const sim::PlantState& state) const { return own<State>(state).events; }
  double input(const sim::PlantState& state) const { return own<State>(state).u; }

 private:
  std::vector<std::string> names_{"y[1]"};
};

// The wall time per control period counts what happens between two samples, the caller's work included: a caller
// that sleeps 2 ms after every call makes every period at least that long.
TEST(Simulator, WallTimePerControlPeriodIncludesTheCallersWorkBetweenSamples) {
  SampledDecay p;
  sim::Simulator s(p, tight());
  EXPECT_EQ(s.periodWallTimes().periods, 0);
  const auto wall0 = std::chrono::steady_clock::now();
  for (int k = 0; k < 10; ++k) {
    s.advance(0.1);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const sim::PeriodWallTimes w = s.periodWallTimes();
  // Samples at 0 (reset: no clock yet) and at 0.1 … 0.9 (the one due at 1.0 is taken by the next call): the first
  // sample after the reset starts the clock.
  EXPECT_EQ(s.samples(), 10);
  EXPECT_EQ(w.periods, s.samples() - 2);
  EXPECT_GE(w.p50_s, 2e-3);
  EXPECT_LE(w.p50_s, w.p99_s);
  EXPECT_LE(w.p99_s, w.max_s);
  EXPECT_LE(w.max_s * 0.999, wall);
  // A restore breaks the chain: the period across it is not counted.
  const sim::Snapshot snap = s.snapshot();
  s.restore(snap);
  s.advance(0.1);
  EXPECT_EQ(s.periodWallTimes().periods, w.periods);
}

TEST(Simulator, SamplesAndTimeEventsAtTheirInstantsWhateverTheStep) {
  SampledDecay p;
  sim::Simulator s(p, tight());
  for (int k = 0; k < 33; ++k) s.advance(0.03);  // steps that do not meet the samples...
  s.advanceTo(1.0);                              // ...and one that ends on a sample (taken at the next advance)
  EXPECT_NEAR(s.state()[0], std::pow(0.9, 10), 1e-10);
  EXPECT_EQ(s.samples(), 10);  // t = 0, 0.1, ..., 0.9
  EXPECT_EQ(p.events(s.plantState()), 1);
  s.advance(0.05);  // the sample at 1.0 first, then half a period
  EXPECT_NEAR(s.state()[0], std::pow(0.9, 10) * 0.95, 1e-10);
  // 1 kHz steps accumulate rounding in t + dt; samples are still met.
  sim::Simulator s2(p, tight());
  for (int k = 0; k < 1000; ++k) s2.advance(1e-3);
  EXPECT_NEAR(s2.time(), 1.0, 1e-12);
  EXPECT_NEAR(s2.state()[0], std::pow(0.9, 10), 1e-10);
}

TEST(Simulator, SteppingAnExperimentReproducesItsRunOnTheLogGrid) {
  // The UR5 twin through its pick-and-place trajectory (time events at the path's breakpoints): stepping at the
  // log interval gives the log of sim::simulate within the solver tolerance (the step sequences differ).
  std::shared_ptr<experiments::Experiment> e =
      experiments::loadExperiment(test::sourcePath("config/experiments/ur5_pick_and_place.yaml"));
  auto options = e->simulateOptions();
  options.t_end = 1.0;
  sim::SignalTable reference = sim::simulateTable(e->plant(), options);
  auto s = experiments::makeSimulator(e);
  const int q2 = s->signalIndex("q_shoulder_lift_joint"), v2 = s->signalIndex("voltage_shoulder_lift_joint");
  double worst_q = 0.0, worst_v = 0.0;
  for (Eigen::Index r = 1; r < reference.values.rows(); ++r) {
    s->advanceTo(reference.values(r, 0));
    worst_q = std::max(worst_q, std::abs(s->signals()[q2] - reference.values(r, 1 + q2)));
    worst_v = std::max(worst_v, std::abs(s->signals()[v2] - reference.values(r, 1 + v2)));
  }
  EXPECT_NEAR(s->time(), 1.0, 1e-12);
  EXPECT_LT(worst_q, 1e-6) << "rad";
  EXPECT_LT(worst_v, 1e-2) << "V";
  EXPECT_GT(s->events(), 0);  // the path's breakpoints
}

// One event engine: sim::simulate's rows are the stepping simulator's at the grid with interpolated landings, bit for
// bit (samples, a time event, the input jumps' history decisions, the counters); landing by stop times gives the same
// run within the solver tolerance (a different step sequence).
TEST(Simulator, SimulateIsTheSteppingSimulatorOnItsOutputGrid) {
  SampledDecay p;
  const sim::SimulateOptions o = sim::SimulateOptions::atRate(1.0, 100.0, tight());
  sim::SimulationResult result;
  const sim::SignalTable run = sim::simulateTable(p, o, &result);
  ASSERT_EQ(run.values.rows(), 101);
  sim::Simulator interpolating(p, o.solver), stopping(p, o.solver);
  double worst = 0.0;
  for (Eigen::Index r = 1; r < run.values.rows(); ++r) {
    const double t = run.values(r, 0);
    ASSERT_EQ(interpolating.advanceTo(t, sim::Landing::Interpolate), t);
    ASSERT_EQ(interpolating.signals()[0], run.values(r, 1)) << "t = " << t;
    stopping.advanceTo(t);
    worst = std::max(worst, std::abs(stopping.signals()[0] - run.values(r, 1)));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(run.values(100, 1), std::pow(0.9, 10), 1e-10);  // the closed form at t = 1
  EXPECT_EQ(interpolating.stats().steps, result.stats.steps);
  EXPECT_EQ(interpolating.stats().rhs_evals, result.stats.rhs_evals);
  EXPECT_EQ(interpolating.samples(), result.samples);
  EXPECT_EQ(interpolating.events(), result.events);
  EXPECT_EQ(interpolating.restarts() - 1, result.restarts);  // simulate does not count the start
  EXPECT_EQ(interpolating.inputJumps(), result.input_jumps);
  EXPECT_EQ(result.samples, 10);  // t = 0, 0.1, ..., 0.9
  EXPECT_EQ(result.events, 1);    // t = 0.35
}

/// A relay whose switching instants accumulate (Zeno): ẏ = −m, m flipped each time y crosses 0.
class ZenoRelay : public sim::Plant {
 public:
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double m = 1.0;
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  std::string name() const override { return "zeno relay"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Constant(1, 0.5); }
  void derivatives(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = -own<State>(state).m;
  }
  int rootCount() const override { return 1; }
  void roots(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override {
    g[0] = y[0];
  }
  void updateModes(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>&,
                   const std::vector<int>& fired) const override {
    if (!fired.empty() && fired[0] != 0) own<State>(state).m = fired[0] < 0 ? -1.0 : 1.0;
  }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }

 private:
  std::vector<std::string> names_{"y[1]"};
};

// The chattering guard is the simulator's (events per call), and so sim::simulate's per output interval.
TEST(SimulatorLimits, ChatteringEventsEndTheCallOrTheOutputInterval) {
  ZenoRelay p;
  sim::Simulator s(p, tight());
  sim::AdvanceLimits limits;
  limits.max_events = 50;
  s.setLimits(limits);
  try {
    s.advance(1.0);
    FAIL() << "the relay chatters from t = 0.5 s on";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "EVENT_CHATTERING") << e.what();
    EXPECT_THAT(e.what(), ::testing::HasSubstr("more than 50 events in one call"));
    EXPECT_NEAR(e.time(), 0.5, 1e-3);
  }
  EXPECT_EQ(s.events(), 51);
  sim::SimulateOptions o = sim::SimulateOptions::atRate(1.0, 10.0, tight());
  o.max_events_per_output = 50;
  try {
    sim::simulate(p, o, [](const Eigen::VectorXd&) {});
    FAIL() << "the relay chatters";
  } catch (const sim::SimulationFailure& e) {
    EXPECT_EQ(e.flag(), "EVENT_CHATTERING") << e.what();
    EXPECT_THAT(e.what(), ::testing::HasSubstr("more than 50 events in one output interval (chattering)"));
    // The interval that ends at 0.5 s has the first switch; the next one the 51 that end the run.
    EXPECT_EQ(e.partial().events, 52);
  }
}

/// ẏ = −a y + u with a digital P controller u_k = −K y(t_k) held over [t_k, t_k + T_s): the exact recursion
/// y_{k+1} = e^{−a T_s} y_k + (1 − e^{−a T_s}) u_k / a.
class SampledFirstOrder : public sim::Plant {
 public:
  double a = 1.0, K = 0.5, Ts = 1e-3;
  std::string name() const override { return "sampled first order"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Constant(1, 1.0); }
  /// The run's held controller output u_k.
  struct State : sim::PlantStateOf<State> {
    using PlantStateOf::PlantStateOf;
    double u = 0.0;
    void save(ByteWriter& out) const override { out.f64(u); }
    void load(ByteReader& in) override { u = in.f64("u"); }
  };
  std::unique_ptr<sim::PlantState> makeState() const override { return std::make_unique<State>(*this); }
  void derivatives(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = -a * y[0] + own<State>(state).u;
  }
  double samplePeriod() const override { return Ts; }
  void start(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    own<State>(state).u = -K * y[0];
  }
  void sample(sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y) const override {
    own<State>(state).u = -K * y[0];
  }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }
  double exact(int samples) const {
    const double e = std::exp(-a * Ts);
    double y = 1.0;
    for (int k = 0; k < samples; ++k) y = e * y + (1.0 - e) * (-K * y) / a;
    return y;
  }

 private:
  std::vector<std::string> names_{"y[1]"};
};

TEST(Simulator, SmallInputJumpsKeepTheHistoryAndLargeOnesRestart) {
  // Held inputs jump at every sample. With input_jump KeepHistory the integrator goes on through the small jumps of
  // this slow loop (no restarts, fewer steps); both policies follow the exact recursion to what the tolerance
  // allows over 500 samples (a global error of a few 1e-5 at rtol 1e-6), KeepHistory no worse than Restart.
  double error[2] = {0, 0};
  long steps[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    const auto policy = i == 0 ? sim::CvodeOptions::InputJump::KeepHistory : sim::CvodeOptions::InputJump::Restart;
    SampledFirstOrder p;
    sim::CvodeOptions o;
    o.rtol = 1e-6;
    o.atol = 1e-9;
    o.input_jump = policy;
    sim::Simulator s(p, o);
    s.advanceTo(0.5);
    error[i] = std::abs(s.state()[0] - p.exact(500));
    steps[i] = s.stats().steps;
    EXPECT_LT(error[i], 1e-4);
    // simulate() likewise.
    sim::SimulationResult r;
    const sim::SignalTable t = sim::simulateTable(p, sim::SimulateOptions::atRate(0.5, 100.0, o), &r);
    EXPECT_LT(std::abs(t["y"][t.values.rows() - 1] - p.exact(500)), 1e-4);
    EXPECT_EQ(r.samples, 500);
    if (policy == sim::CvodeOptions::InputJump::KeepHistory) {
      EXPECT_GT(s.inputJumps(), 450);
      EXPECT_LT(s.restarts(), 50);
      EXPECT_GT(r.input_jumps, 450);
    } else {
      EXPECT_EQ(s.inputJumps(), 0);
      EXPECT_GE(s.restarts(), 499);
      EXPECT_EQ(r.input_jumps, 0);
    }
  }
  EXPECT_LE(error[0], 2.0 * error[1] + 1e-6);
  EXPECT_LT(steps[0], steps[1]);
  // A jump far beyond the tolerance restarts even under KeepHistory: the step to 3 on a tight tolerance.
  FirstOrder p;
  sim::Simulator s(p, tight());
  s.advanceTo(0.5);
  const long restarts = s.restarts(), kept = s.inputJumps();
  p.setInput(s.plantState(), 3.0);
  s.advanceTo(0.6);
  EXPECT_EQ(s.restarts(), restarts + 1);
  EXPECT_EQ(s.inputJumps(), kept);
  // A jump of 1e-13 on that tolerance keeps the history, and the closed form still holds.
  const double y06 = s.state()[0];
  p.setInput(s.plantState(), 3.0 + 1e-13);
  s.advanceTo(0.7);
  EXPECT_EQ(s.restarts(), restarts + 1);
  EXPECT_EQ(s.inputJumps(), kept + 1);
  const double u = 3.0 + 1e-13;
  EXPECT_NEAR(s.state()[0], u / 2 + (y06 - u / 2) * std::exp(-0.2), 1e-9);
}

/// ẍ = −ω² x from x = 1, ẋ = 0: x(t) = cos ωt, ẋ = −ω sin ωt (many steps per simulated second).
class Oscillator : public sim::Plant {
 public:
  double w = 2.0 * M_PI * 10.0;
  std::string name() const override { return "oscillator"; }
  int stateSize() const override { return 2; }
  Eigen::VectorXd initialState() const override { return Eigen::Vector2d(1.0, 0.0); }
  void derivatives(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = y[1];
    yd[1] = -w * w * y[0];
  }
  std::string stateName(int i) const override { return i == 0 ? "x [m]" : "v [m/s]"; }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }

 private:
  std::vector<std::string> names_{"x[m]"};
};

sim::CvodeOptions oscillatorSolver(long max_num_steps) {
  sim::CvodeOptions o;
  o.method = sim::Method::Adams;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.max_num_steps = max_num_steps;
  return o;
}

TEST(SimulatorLimits, OneAdvanceGoesOnThroughCvodesCapOfStepsPerCall) {
  Oscillator p;
  sim::Simulator s(p, oscillatorSolver(50));  // CVODE stops every 50 steps: not an error for a Simulator
  EXPECT_EQ(s.advance(10.0), 10.0);
  EXPECT_GT(s.stats().steps, 2000);
  EXPECT_NEAR(s.state()[0], std::cos(p.w * 10.0), 1e-6);
  EXPECT_NEAR(s.state()[1], -p.w * std::sin(p.w * 10.0), 1e-4);
}

TEST(SimulatorLimits, AStepLimitEndsTheCallAtItsLastStepAndTheNextCallGoesOn) {
  Oscillator p;
  sim::Simulator s(p, oscillatorSolver(500000));
  sim::AdvanceLimits limits;
  limits.max_steps = 100;
  s.setLimits(limits);
  try {
    s.advance(5.0);
    FAIL() << "a 5 s advance needs more than 100 steps";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "STEP_BUDGET");
    EXPECT_EQ(e.component(), "oscillator");
    EXPECT_EQ(e.time(), s.time());
  }
  // The simulator stands on a point of the solution (the last accepted step), inside the interval.
  const double t = s.time();
  EXPECT_GT(t, 0.0);
  EXPECT_LT(t, 5.0);
  EXPECT_NEAR(s.state()[0], std::cos(p.w * t), 1e-7);
  // The limit is per call: 100 more steps go further; without a limit the call reaches its target.
  EXPECT_THROW(s.advanceTo(5.0), SolverError);
  EXPECT_GT(s.time(), t);
  s.setLimits(sim::AdvanceLimits{});
  EXPECT_EQ(s.advanceTo(5.0), 5.0);
  EXPECT_NEAR(s.state()[0], std::cos(p.w * 5.0), 1e-6);
  limits.max_steps = -1;
  EXPECT_THROW(s.setLimits(limits), InputError);
  limits = sim::AdvanceLimits{};
  limits.max_wall_time = std::nan("");
  EXPECT_THROW(s.setLimits(limits), InputError);
}

TEST(SimulatorLimits, AStateBeyondItsBoundEndsTheCallAsDiverged) {
  FirstOrder p;
  p.a = -5.0;  // ẏ = 5 y from y = 1: y = e^{5t} reaches 1e6 at t = ln(1e6)/5 = 2.763 s
  sim::Simulator s(p, tight());
  sim::AdvanceLimits limits;
  limits.max_state = 1e6;
  s.setLimits(limits);
  try {
    s.advance(100.0);
    FAIL() << "y = e^{5t} exceeds 1e6";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "DIVERGED");
    EXPECT_NE(std::string(e.what()).find("state 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_state = 1000000"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("after t = " + formatNumber(e.time()) + " s"), std::string::npos) << e.what();
    EXPECT_EQ(e.time(), s.time());
  }
  EXPECT_LE(s.time(), std::log(1e6) / 5.0 + 1e-9);
  EXPECT_GT(s.time(), std::log(1e5) / 5.0);
  EXPECT_NEAR(s.state()[0], std::exp(5.0 * s.time()), 1e-6 * s.state()[0]);
}

TEST(SimulatorLimits, AWallClockLimitEndsACallThatWouldTakeLong) {
  Oscillator p;
  p.w = 2.0 * M_PI * 1000.0;
  sim::Simulator s(p, oscillatorSolver(500000));
  sim::AdvanceLimits limits;
  limits.max_wall_time = 0.05;
  s.setLimits(limits);
  const auto start = std::chrono::steady_clock::now();
  try {
    s.advance(1e6);  // about 1e11 steps
    FAIL();
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "WALL_TIME_BUDGET");
  }
  // Checked every 256 right-hand sides: well within a second of the limit even on a loaded machine.
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
  EXPECT_GT(s.time(), 0.0);
}

int stopAfter1000Polls(void* calls) noexcept { return ++*static_cast<int*>(calls) >= 1000 ? SIGINT : 0; }

TEST(SimulatorLimits, ACallersStopPollEndsTheCallAsInterruptedAndOnlyWhileItLives) {
  Oscillator p;
  sim::Simulator s(p, oscillatorSolver(500000));
  int calls = 0;
  {
    StopPoll poll(&stopAfter1000Polls, &calls, 0.0);  // asked at every right-hand side
    try {
      s.advance(10.0);
      FAIL();
    } catch (const sim::Interrupted& e) {
      EXPECT_EQ(e.flag(), "INTERRUPTED");
      EXPECT_EQ(e.signal(), SIGINT);
      EXPECT_EQ(poll.tripped(), SIGINT);
    }
    EXPECT_EQ(calls, 1000);
    EXPECT_EQ(stopRequested(), SIGINT);  // sticky while the poll lives
  }
  EXPECT_EQ(stopRequested(), 0);
  // It stands at the last step it completed: a point of the solution inside the interval.
  const double t = s.time();
  EXPECT_GT(t, 0.0);
  EXPECT_LT(t, 1.0);
  EXPECT_NEAR(s.state()[0], std::cos(p.w * t), 1e-7);
  EXPECT_EQ(s.advanceTo(1.0), 1.0);
  EXPECT_NEAR(s.state()[0], std::cos(p.w * 1.0), 1e-6);
}

/// ẏ = −sign(y) (a relay around 0): from y = 1 it reaches 0 at t = 1 s and then chatters, every step crossing it.
class Chatter : public sim::Plant {
 public:
  std::string name() const override { return "chatter"; }
  int stateSize() const override { return 1; }
  Eigen::VectorXd initialState() const override { return Eigen::VectorXd::Constant(1, 1.0); }
  void derivatives(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> yd) const override {
    yd[0] = y[0] > 0.0 ? -1.0 : 1.0;
  }
  const std::vector<std::string>& signalNames() const override { return names_; }
  void signals(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
               Eigen::Ref<Eigen::VectorXd> out) const override {
    out[0] = y[0];
  }

 private:
  std::vector<std::string> names_{"y[1]"};
};

TEST(SimulatorLimits, AnIntegrationThatNoLongerMovesEndsInsteadOfRunningForever) {
  Chatter p;
  sim::CvodeOptions o = tight();
  o.max_num_steps = 2000;
  sim::Simulator s(p, o);
  try {
    s.advance(10.0);
    FAIL() << "the relay chatters at y = 0 with ever smaller steps";
  } catch (const SolverError& e) {
    std::printf("%s\n", e.what());
    // Either CVODE gives up on the discontinuity itself, or 2000 steps cover less than 2 µs: stuck.
    EXPECT_TRUE(e.flag() == "CV_TOO_MUCH_WORK" || e.flag() == "CV_ERR_FAILURE" || e.flag() == "CV_CONV_FAILURE")
        << e.flag() << ": " << e.what();
    if (e.flag() == "CV_TOO_MUCH_WORK") {  // the chunk's check, or the integrator's collapse check (with the state)
      const std::string what = e.what();
      EXPECT_TRUE(what.find("stuck") != std::string::npos ||
                  (what.find("the step size collapsed") != std::string::npos &&
                   what.find("limiting state: y[0]") != std::string::npos))
          << what;
    }
  }
  EXPECT_GT(s.time(), 0.99);
  EXPECT_LT(s.time(), 10.0);
}

/// The relay with a named state, for messages.
class NamedChatter : public Chatter {
 public:
  std::string stateName(int) const override { return "relay output y"; }
};

// The run loop (sim::simulate) with the library's default solver budget (500,000 steps per output interval): the
// chattering relay ends after one window of CvodeOptions::collapse_window steps, as a collapsed step size naming the
// time and the state that limited the step, not after the whole budget (issue 26: an absurd gain crawled for 40 s).
TEST(SimulatorLimits, ACollapsedStepSizeEndsTheRunAfterOneWindowNamingTheState) {
  NamedChatter p;
  sim::SimulateOptions o = sim::SimulateOptions::atRate(3.0, 10.0, tight());
  try {
    sim::simulate(p, o, [](const Eigen::VectorXd&) {});
    FAIL() << "the relay chatters at y = 0 with ever smaller steps";
  } catch (const sim::SimulationFailure& e) {
    std::printf("%s\n", e.what());
    EXPECT_EQ(e.flag(), "CV_TOO_MUCH_WORK") << e.what();
    EXPECT_THAT(e.what(), ::testing::HasSubstr("the step size collapsed at t = "));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("limiting state: relay output y"));
    EXPECT_EQ(e.component(), "chatter");
    EXPECT_GT(e.time(), 0.99);
    EXPECT_LT(e.time(), 1.01);
    // At most the steps to reach the relay plus one window, not the 500,000 of the budget.
    EXPECT_LE(e.partial().stats.steps, 2 * o.solver.collapse_window + 5000);
  }
  // The stepping simulator (and so the FMU and Python's Simulator) reports the same, and stands at its last step.
  {
    sim::Simulator stepping(p, tight());
    try {
      stepping.advance(3.0);
      FAIL() << "the relay chatters";
    } catch (const SolverError& e) {
      EXPECT_EQ(e.flag(), "CV_TOO_MUCH_WORK");
      EXPECT_THAT(e.what(), ::testing::HasSubstr("limiting state: relay output y")) << e.what();
    }
    EXPECT_GT(stepping.time(), 0.99);
  }
  // The check switched off: the same run spends the whole budget of its output interval, and fails otherwise.
  o.solver.collapse_mean_step = 0.0;
  o.solver.max_num_steps = 3 * o.solver.collapse_window;
  try {
    sim::simulate(p, o, [](const Eigen::VectorXd&) {});
    FAIL();
  } catch (const sim::SimulationFailure& e) {
    EXPECT_THAT(e.what(), ::testing::Not(::testing::HasSubstr("collapsed"))) << e.what();
  }
}

/// The oscillator, its position marked as a state that may grow without bound (an angle that keeps turning).
class OscillatorWithFreePosition : public Oscillator {
 public:
  bool unboundedState(int i) const override { return i == 0; }
};

TEST(SimulatorLimits, TheStateBoundLeavesStatesThatMayGrowAlone) {
  OscillatorWithFreePosition p;  // |x| <= 1, |v| <= w = 62.8
  sim::Simulator s(p, oscillatorSolver(500000));
  sim::AdvanceLimits limits;
  limits.max_state = 0.5;  // below the amplitude of x, which is exempt; above it for v: DIVERGED names v
  s.setLimits(limits);
  try {
    s.advance(1.0);
    FAIL();
  } catch (const SolverError& e) {
    EXPECT_EQ(e.flag(), "DIVERGED");
    EXPECT_NE(std::string(e.what()).find("state 1 (v [m/s])"), std::string::npos) << e.what();
  }
  limits.max_state = 100.0;
  s.setLimits(limits);
  EXPECT_EQ(s.advanceTo(1.0), 1.0);
}

// ------------------------------------------------------------------------------------------ snapshots
// Simulator::snapshot/restore, saveState/loadState and the copy constructor on the small plants above: a run taken
// up again from a snapshot repeats the original continuation bit for bit (both restart the integrator there).

/// Advances in steps of `dt` to exactly `t_end` (the same sequence of calls for the same start time).
void runTo(sim::Simulator& s, double t_end, double dt) {
  while (s.time() < t_end) s.advanceTo(std::min(t_end, s.time() + dt));
}

/// Where a run ended: time, continuous state and signals.
struct RunEnd {
  double t = 0.0;
  Eigen::VectorXd y, signals;
};

RunEnd endOf(const sim::Simulator& s) { return {s.time(), s.state(), s.signals()}; }

/// Bit for bit: EXPECT_EQ on the time and on every entry.
void expectSameBits(const RunEnd& a, const RunEnd& b, const std::string& what) {
  EXPECT_EQ(a.t, b.t) << what;
  ASSERT_EQ(a.y.size(), b.y.size()) << what;
  for (Eigen::Index i = 0; i < a.y.size(); ++i) EXPECT_EQ(a.y[i], b.y[i]) << what << ": state " << i;
  ASSERT_EQ(a.signals.size(), b.signals.size()) << what;
  for (Eigen::Index i = 0; i < a.signals.size(); ++i) EXPECT_EQ(a.signals[i], b.signals[i]) << what << ": signal " << i;
}

/// Snapshot of `s` at its time, on to `t_end` (the reference), restore, on to `t_end` again: the same bits.
RunEnd expectRestoreRepeats(sim::Simulator& s, double t_end, double dt, const std::string& what) {
  const sim::Snapshot snap = s.snapshot();
  EXPECT_FALSE(snap.empty());
  EXPECT_EQ(&snap.plantState().owner(), &s.plant());
  EXPECT_EQ(snap.time(), s.time());
  EXPECT_EQ(snap.state(), s.state());
  runTo(s, t_end, dt);
  const RunEnd first = endOf(s);
  s.restore(snap);
  EXPECT_EQ(s.time(), snap.time()) << what;
  EXPECT_EQ(s.state(), snap.state()) << what;
  runTo(s, t_end, dt);
  expectSameBits(first, endOf(s), what + ", restored");
  // The snapshot is a copy: the run did not change it, and it restores once more alike.
  s.restore(snap);
  runTo(s, t_end, dt);
  expectSameBits(first, endOf(s), what + ", restored twice");
  return first;
}

TEST(SimulatorSnapshot, RestoringAMidRunSnapshotRepeatsTheRestBitForBit) {
  {  // A sampled part and a time event after the snapshot (taken between two samples).
    SampledDecay p;
    sim::Simulator s(p, tight());
    runTo(s, 0.23, 0.03);
    const double u = p.input(s.plantState());
    EXPECT_NEAR(u, -std::pow(0.9, 2), 1e-10);  // held since the sample at 0.2 s
    const sim::Snapshot snap = s.snapshot();
    EXPECT_EQ(p.input(snap.plantState()), u);
    EXPECT_EQ(p.events(snap.plantState()), 0);
    const RunEnd end = expectRestoreRepeats(s, 1.05, 0.03, "sampled decay");
    EXPECT_NEAR(end.y[0], std::pow(0.9, 10) * 0.95, 1e-10);  // and it is the right run
    EXPECT_EQ(p.events(s.plantState()), 1);                  // the time event at 0.35 s, once per run
  }
  {  // Root events after the snapshot: the mode switches at t = 1 and t = 3.
    Triangle p;
    sim::Simulator s(p, tight());
    runTo(s, 0.5, 0.07);
    const RunEnd end = expectRestoreRepeats(s, 3.5, 0.07, "triangle");
    EXPECT_NEAR(end.y[0], -0.5, 1e-8);
    EXPECT_EQ(p.switches(s.plantState()), 2);
    EXPECT_EQ(p.mode(s.plantState()), 1.0);
  }
  {  // An input change set just before the snapshot and not yet applied is part of it.
    FirstOrder p;
    sim::Simulator s(p, tight());
    runTo(s, 0.3, 0.1);
    const double y03 = s.state()[0];
    p.setInput(s.plantState(), 3.0);
    const RunEnd end = expectRestoreRepeats(s, 1.0, 0.1, "first order, input pending");
    EXPECT_NEAR(end.y[0], 1.5 + (y03 - 1.5) * std::exp(-2.0 * 0.7), 1e-8);
    EXPECT_EQ(end.signals[1], 3.0);
  }
}

/// saveState() of `s` at its time, loaded into `other` (the same plant's configuration); both on to `t_end`: the
/// same bits.
void expectLoadRepeats(sim::Simulator& s, sim::Simulator& other, double t_end, double dt, const std::string& what) {
  const std::string bytes = s.saveState();
  other.loadState(bytes);
  EXPECT_EQ(other.time(), s.time()) << what;
  EXPECT_EQ(other.state(), s.state()) << what;
  runTo(s, t_end, dt);
  runTo(other, t_end, dt);
  expectSameBits(endOf(s), endOf(other), what);
}

TEST(SimulatorSnapshot, SavedBytesLoadIntoASecondSimulatorThatContinuesBitForBit) {
  {
    SampledDecay p, q;  // q: another object of the same configuration (the bytes carry no object identity)
    sim::Simulator s(p, tight()), s2(p, tight()), s3(q, tight());
    s2.advanceTo(0.7);  // somewhere else: loading replaces everything
    runTo(s, 0.23, 0.03);
    sim::Simulator reference(s);
    expectLoadRepeats(s, s2, 1.05, 0.03, "sampled decay, same plant");
    EXPECT_EQ(p.events(s2.plantState()), 1);
    EXPECT_EQ(p.input(s2.plantState()), p.input(s.plantState()));
    expectLoadRepeats(reference, s3, 1.05, 0.03, "sampled decay, a second plant object");
    expectSameBits(endOf(s), endOf(s3), "sampled decay, a second plant object against the first");
    EXPECT_EQ(q.events(s3.plantState()), 1);
  }
  {
    Triangle p;
    sim::Simulator s(p, tight()), s2(p, tight());
    runTo(s, 1.5, 0.07);  // after the first switch: the mode −1 travels in the bytes
    EXPECT_EQ(p.mode(s.plantState()), -1.0);
    expectLoadRepeats(s, s2, 3.5, 0.07, "triangle");
    EXPECT_EQ(p.switches(s2.plantState()), 2);
    EXPECT_NEAR(s2.state()[0], -0.5, 1e-8);
  }
  {
    FirstOrder p;
    sim::Simulator s(p, tight()), s2(p, tight());
    runTo(s, 0.3, 0.1);
    const double y03 = s.state()[0];
    p.setInput(s.plantState(), 3.0);  // pending at the save
    expectLoadRepeats(s, s2, 1.0, 0.1, "first order, input pending");
    EXPECT_EQ(p.input(s2.plantState()), 3.0);
    EXPECT_NEAR(s2.state()[0], 1.5 + (y03 - 1.5) * std::exp(-2.0 * 0.7), 1e-8);
  }
}

TEST(SimulatorSnapshot, ACopyContinuesIdenticallyAndIndependently) {
  {
    SampledDecay p;
    sim::Simulator s(p, tight());
    runTo(s, 0.23, 0.03);
    sim::Simulator c(s);
    EXPECT_EQ(&c.plant(), &p);
    EXPECT_EQ(c.time(), s.time());
    EXPECT_EQ(c.state(), s.state());
    EXPECT_NE(&c.plantState(), &s.plantState());
    runTo(s, 1.05, 0.03);
    runTo(c, 1.05, 0.03);
    expectSameBits(endOf(s), endOf(c), "sampled decay, copy");
    EXPECT_EQ(p.events(c.plantState()), 1);
  }
  {
    Triangle p;
    sim::Simulator s(p, tight());
    runTo(s, 0.5, 0.07);
    sim::Simulator c(s);
    runTo(c, 3.5, 0.07);  // the copy first: the original does not follow it
    EXPECT_EQ(s.time(), 0.5);
    EXPECT_EQ(p.switches(s.plantState()), 0);
    runTo(s, 3.5, 0.07);
    expectSameBits(endOf(s), endOf(c), "triangle, copy");
    EXPECT_EQ(p.switches(c.plantState()), 2);
  }
  {  // Inputs set on the copy stay with the copy, and the other way round.
    FirstOrder p;
    sim::Simulator s(p, tight());
    p.setInput(s.plantState(), 1.0);
    runTo(s, 0.5, 0.1);
    const double y05 = s.state()[0];
    sim::Simulator reference(s), c(s);
    p.setInput(c.plantState(), 3.0);
    EXPECT_EQ(p.input(s.plantState()), 1.0);
    EXPECT_EQ(s.signal("u"), 1.0);
    EXPECT_EQ(c.signal("u"), 3.0);
    runTo(s, 1.0, 0.1);
    runTo(c, 1.0, 0.1);
    runTo(reference, 1.0, 0.1);
    expectSameBits(endOf(reference), endOf(s), "first order: the original, untouched by the copy's input");
    EXPECT_NEAR(s.state()[0], 0.5 + (y05 - 0.5) * std::exp(-1.0), 1e-8);
    EXPECT_NEAR(c.state()[0], 1.5 + (y05 - 1.5) * std::exp(-1.0), 1e-8);
    p.setInput(s.plantState(), -2.0);
    EXPECT_EQ(p.input(c.plantState()), 3.0);
    EXPECT_EQ(c.signal("u"), 3.0);
  }
}

TEST(SimulatorSnapshot, LoadStateRefusesTruncatedForeignAndGarbageBytesAndLeavesTheSimulatorUnchanged) {
  FirstOrder p;
  sim::Simulator s(p, tight());
  p.setInput(s.plantState(), 2.0);
  runTo(s, 0.4, 0.1);
  const std::string good = s.saveState();
  runTo(s, 0.7, 0.1);  // on beyond the saved state, with an input change pending
  p.setInput(s.plantState(), -1.0);
  const double t = s.time();
  const Eigen::VectorXd y = s.state();
  sim::Simulator reference(s);  // how s continues when nothing changed it

  Triangle other;
  sim::Simulator so(other, tight());
  so.advanceTo(0.5);
  const std::string foreign = so.saveState();
  // The triangle's bytes with a mode other than ±1: refused by the plant's own State::load.
  std::string bad_mode = foreign;
  {
    const size_t at = bad_mode.find("plant state");
    ASSERT_NE(at, std::string::npos);
    ByteWriter half;
    half.f64(0.5);
    bad_mode.replace(at + 11, 8, half.bytes());
  }
  sim::Simulator so2(other, tight());
  EXPECT_THROW(so2.loadState(bad_mode), InputError);
  EXPECT_EQ(so2.time(), 0.0);
  EXPECT_EQ(other.mode(so2.plantState()), 1.0);

  std::vector<std::pair<std::string, std::string>> bad = {
      {"no bytes", ""},
      {"text", "not a saved simulator state"},
      {"0xff bytes", std::string(64, '\xff')},
      {"zero bytes", std::string(200, '\0')},
      {"another plant", foreign},
      {"another plant with a bad mode", bad_mode},
      {"a byte too many", good + 'x'},
  };
  for (size_t n = 0; n < good.size(); ++n)
    bad.emplace_back("truncated to " + std::to_string(n) + " bytes", good.substr(0, n));
  for (const auto& [what, bytes] : bad) {
    EXPECT_THROW(s.loadState(bytes), InputError) << what;
    EXPECT_EQ(s.time(), t) << what;
    EXPECT_EQ(s.state(), y) << what;
    EXPECT_EQ(p.input(s.plantState()), -1.0) << what;
  }
  try {
    s.loadState(foreign);
    FAIL() << "the triangle's state loaded into the first-order plant";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("'triangle'"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("first order"));
  }
  // Unchanged, the pending input change included: it continues as its copy made before the refused loads.
  runTo(s, 1.0, 0.1);
  runTo(reference, 1.0, 0.1);
  expectSameBits(endOf(reference), endOf(s), "after the refused loads");
  // The good bytes still load: back to 0.4 s with u = 2.
  s.loadState(good);
  EXPECT_EQ(s.time(), 0.4);
  EXPECT_EQ(p.input(s.plantState()), 2.0);
}

TEST(SimulatorSnapshot, ASnapshotOfAnotherPlantObjectIsRefused) {
  FirstOrder p, q;  // the same type, name and configuration, but two objects
  sim::Simulator sp(p, tight()), sq(q, tight());
  p.setInput(sp.plantState(), 3.0);
  sp.advanceTo(0.5);
  q.setInput(sq.plantState(), 1.0);
  sq.advanceTo(0.2);
  const double y = sq.state()[0];
  const sim::Snapshot snap = sp.snapshot();
  EXPECT_THROW(sq.restore(snap), InputError);
  EXPECT_THROW(sq.restore(sim::Snapshot{}), InputError);  // an empty one
  Triangle other;
  sim::Simulator so(other, tight());
  EXPECT_THROW(sq.restore(so.snapshot()), InputError);  // another type of plant
  EXPECT_EQ(sq.time(), 0.2);
  EXPECT_EQ(sq.state()[0], y);
  EXPECT_EQ(q.input(sq.plantState()), 1.0);
  // A plant refuses another plant object's state in its own methods too.
  EXPECT_THROW(q.setInput(sp.plantState(), 1.0), InputError);
  EXPECT_THROW(q.input(sp.plantState()), InputError);
  EXPECT_EQ(p.input(sp.plantState()), 3.0);
  // The bytes of the snapshot load (they name the plant, not the object); the simulator of p restores it.
  sq.loadState(snap.toBytes());
  EXPECT_EQ(sq.time(), 0.5);
  EXPECT_EQ(q.input(sq.plantState()), 3.0);
  sp.advanceTo(0.8);
  sp.restore(snap);
  EXPECT_EQ(sp.time(), 0.5);
}

TEST(SimulatorSnapshot, ResetClearsTheInputsSetInTheState) {
  FirstOrder p;
  sim::Simulator s(p, tight());
  p.setInput(s.plantState(), 3.0);
  s.advanceTo(0.5);
  EXPECT_EQ(s.signal("u"), 3.0);
  s.reset();  // a fresh state (the one before is gone: take plantState() anew)
  EXPECT_EQ(s.time(), 0.0);
  EXPECT_EQ(p.input(s.plantState()), 0.0);
  EXPECT_EQ(s.signal("u"), 0.0);
  s.advanceTo(0.5);
  EXPECT_NEAR(s.state()[0], std::exp(-1.0), 1e-8);  // u = 0 again
  p.setInput(s.plantState(), -1.0);                 // pending, not yet applied
  s.reset(2.0, Eigen::VectorXd::Constant(1, 4.0));
  EXPECT_EQ(p.input(s.plantState()), 0.0);
  s.advanceTo(2.5);
  EXPECT_NEAR(s.state()[0], 4.0 * std::exp(-1.0), 1e-8);
  // The discrete state of the other plants goes back to its start too.
  Triangle tri;
  sim::Simulator st(tri, tight());
  st.advanceTo(1.5);
  EXPECT_EQ(tri.mode(st.plantState()), -1.0);
  st.reset();
  EXPECT_EQ(tri.mode(st.plantState()), 1.0);
  EXPECT_EQ(tri.switches(st.plantState()), 0);
  SampledDecay dec;
  sim::Simulator sd(dec, tight());
  sd.advanceTo(0.5);
  EXPECT_EQ(dec.events(sd.plantState()), 1);
  sd.reset();
  EXPECT_EQ(dec.events(sd.plantState()), 0);
  EXPECT_EQ(dec.input(sd.plantState()), -1.0);  // start(): u = −y(0)
}

}  // namespace
}  // namespace jointsim
