#include "jointsim/systems/robotr3_axis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::systems {

namespace {
Eigen::VectorXd one(double v) { return Eigen::VectorXd::Constant(1, v); }
}  // namespace

void RobotR3AxisSetup::validate() const {
  // Keys as in a robotr3_axis experiment file.
  const char* const a = "RobotR3 axis";
  try {
    axis.motor.validate();
  } catch (const InputError& e) {
    throw InputError::parameter(a, "motor." + e.keyPath(), e.message());
  }
  check::that(axis.type == 1, a, "gear.type", "expected 1 (the rigid type 2 is not modelled on a 1-D load)");
  check::nonZero(a, "gear.ratio", axis.ratio, "(-)");
  check::positive(a, "gear.c", axis.c, "N·m/rad");
  check::nonNegative(a, "gear.d", axis.d, "N·m·s/rad");
  check::nonNegative(a, "gear.Rv0", axis.Rv0, "N·m");
  check::nonNegative(a, "gear.Rv1", axis.Rv1, "N·m·s/rad");
  check::atLeast(a, "gear.peak", axis.peak, 1.0, "(-)");
  check::nonNegative(a, "controller.kp", axis.kp, "1/s");
  check::nonNegative(a, "controller.ks", axis.ks, "A·s/rad");
  check::positive(a, "controller.Ts", axis.Ts, "s");
  check::positive(a, "load.inertia", load_inertia, "kg·m²");
  check::positive(a, "stop_time", stop_time, "s");
  check::positive(a, "log_interval", log_interval, "s");
  check::that(std::abs(sa0) <= axis.peak * axis.Rv0, a, "initial_friction_torque",
              "expected a torque within ±peak·Rv0 = ±" + formatNumber(axis.peak * axis.Rv0) + " N·m, got " +
                  formatNumber(sa0));
}

RobotR3Axis::RobotR3Axis(RobotR3AxisSetup setup)
    : s_((setup.validate(), std::move(setup))),
      motor_(s_.axis.motor),
      controller_(control::JointController::torqueCascade(s_.axis.kp, s_.axis.ks, s_.axis.Ts)),
      path_(one(s_.q_begin), one(s_.q_end), one(s_.qd_max), one(s_.qdd_max), s_.start_time) {
  const std::string& p = s_.prefix;
  signals_ = {p + ".controller.PI.x[rad/s]",
              p + ".gear.spring.phi_rel[rad]",
              p + ".gear.spring.w_rel[rad/s]",
              p + ".initializeFlange.phi_flange[rad]",
              p + ".initializeFlange.w_flange[rad/s]",
              p + ".motor.C.v[V]",
              p + ".motor.La.i[A]",
              p + ".gear.bearingFriction.mode[-]",
              p + ".gear.bearingFriction.startBackward[-]",
              p + ".gear.bearingFriction.startForward[-]",
              p + ".gear.bearingFriction.tau[N·m]",
              p + ".motor.i_ref[A]",
              "energy.amplifier_work[J]",
              "energy.stored[J]",
              "energy.resistor_loss[J]",
              "energy.damper_loss[J]",
              "energy.friction_loss[J]"};
  sim::InputPort c;
  c.name = p + ".current";
  c.unit = "A";
  c.description = "current reference of the axis (held in place of its controller's)";
  sim::InputPort l;
  l.name = p + ".load_torque";
  l.unit = "N·m";
  l.description = "external torque on the load";
  ports_ = {c, l};
  profiles_.resize(ports_.size());
}

RobotR3Axis::State::State(const RobotR3Axis& axis) : PlantStateOf(axis) { inputs.resize(axis.ports_.size()); }

void RobotR3Axis::State::save(ByteWriter& out) const {
  drive::saveModes(out, {mode});
  inputs.save(out);
}

void RobotR3Axis::State::load(ByteReader& in) {
  std::vector<FrictionMode> modes(1);
  drive::loadModes(in, modes);
  mode = modes[0];
  inputs.load(in);
}

FrictionMode RobotR3Axis::mode(const sim::PlantState& state) const { return own<State>(state).mode; }

std::string RobotR3Axis::name() const { return "RobotR3 axis '" + s_.name + "'"; }

sim::SimulateOptions RobotR3Axis::simulateOptions() const {
  return sim::SimulateOptions::everyInterval(endTime(), s_.log_interval, s_.solver);
}

std::vector<double> RobotR3Axis::timeEvents(double t_end) const {
  return withProfileBreakpoints(path_.breakpoints(), t_end);
}

double RobotR3Axis::endTime() const { return std::min(s_.stop_time, path_.endTime() + s_.swing_time); }

Eigen::VectorXd RobotR3Axis::initialState() const {
  // [MSL, Rotational.Components.InitializeFlange] and the Motor's steady-state initial equations, with the load
  // static torque G = 0 (no gravity on a 1-D load): q = q_begin, q̇ = 0, ω_rel = 0, φ_rel = −G/(ratio c) = 0,
  // ω_m = 0; the rotor balance k i = τ_f(0) − τ_s with τ_f(0) = sa0 (undetermined in MSL; docs/validation.md);
  // electrical steady state v_C = −(Ra i + k ω_m)/5; PI steady state x = i/ks − e(0).
  Eigen::VectorXd y = Eigen::VectorXd::Zero(kStates);
  const auto& m = s_.axis.motor;
  y[0] = s_.q_begin;
  const double phi_rel = 0.0, tau_s = s_.axis.c * phi_rel;
  const double i = (s_.sa0 - tau_s) / m.k;
  const double e0 = s_.axis.kp * phi_rel;
  y[2] = phi_rel;
  y[4] = s_.axis.ks > 0.0 ? i / s_.axis.ks - e0 : 0.0;
  y[5] = -(m.Ra * i) / m.amp_gain;
  y[6] = i;
  return y;
}

RobotR3Axis::Eval RobotR3Axis::evaluate(const sim::PlantState& state, double t,
                                        const Eigen::Ref<const Eigen::VectorXd>& y) const {
  return evaluateIn(own<State>(state), t, y);
}

RobotR3Axis::Eval RobotR3Axis::evaluateIn(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  Eval ev{};
  const auto& m = s_.axis.motor;
  const double q = y[0], qd = y[1], phi_rel = y[2], w_rel = y[3], x = y[4], i = y[6];
  double qr = 0, qdr = 0, qddr = 0;
  {
    Eigen::Matrix<double, 1, 1> a, b, c;
    path_.evaluate(t, a, b, c);
    qr = a[0];
    qdr = b[0];
    qddr = c[0];
    (void)qddr;
  }
  ev.q_ref = qr;
  ev.qd_ref = qdr;
  const double N = s_.axis.ratio;
  const double phi_m = N * q - phi_rel;
  ev.wm = N * qd - w_rel;
  control::ControllerInputs in;  // the axis controller, its output the current reference [A]
  in.ratio = N;
  in.q_set = qr;
  in.qd_set = qdr;
  in.qm_fb = phi_m;
  in.qdm_fb = ev.wm;
  ev.i_ref = controller_.evaluate(in, &x, &ev.xdot).u;
  if (profiles_.active(st.inputs, 0)) {  // a current reference in place of the controller, which freezes
    ev.i_ref = profiles_.value(st.inputs, 0, t);
    ev.xdot = 0.0;
  }
  ev.tau_s = s_.axis.c * phi_rel + s_.axis.d * w_rel;
  // Load: J_L q̈ = −ratio τ_s + τ_L (the spring pulls the gear input with −τ_s; τ_L the load_torque port).
  ev.qdd = (-N * ev.tau_s + profiles_.value(st.inputs, 1, t)) / s_.load_inertia;
  const double tau_motor = m.k * i;
  ev.stuck_torque = tau_motor + ev.tau_s;  // the friction that keeps dω_m/dt = 0
  ev.tau_f = drive::frictionTorque(st.mode, s_.axis.Rv0 + s_.axis.Rv1 * std::abs(ev.wm), ev.stuck_torque);
  ev.wm_dot = st.mode == FrictionMode::Stuck ? 0.0 : (tau_motor - ev.tau_f + ev.tau_s) / m.J;
  return ev;
}

void RobotR3Axis::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> ydot) const {
  const Eval ev = evaluate(state, t, y);
  const auto& m = s_.axis.motor;
  ydot[0] = y[1];
  ydot[1] = ev.qdd;
  ydot[2] = y[3];
  ydot[3] = s_.axis.ratio * ev.qdd - ev.wm_dot;
  ydot[4] = ev.xdot;
  ydot[5] = (y[6] - ev.i_ref) / (m.Ri * m.C());
  ydot[6] = (-m.amp_gain * y[5] - m.Ra * y[6] - m.k * ev.wm) / m.La();
  ydot[7] = -m.amp_gain * y[5] * y[6];
  ydot[8] = m.Ra * y[6] * y[6];
  ydot[9] = s_.axis.d * y[3] * y[3];
  ydot[10] = ev.tau_f * ev.wm;
}

double RobotR3Axis::storedEnergy(const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const double wm = s_.axis.ratio * y[1] - y[3];
  return 0.5 * s_.load_inertia * y[1] * y[1] + 0.5 * s_.axis.motor.J * wm * wm + 0.5 * s_.axis.c * y[2] * y[2] +
         0.5 * s_.axis.motor.La() * y[6] * y[6];
}

void RobotR3Axis::roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                        Eigen::Ref<Eigen::VectorXd> g) const {
  const FrictionMode mode = own<State>(state).mode;
  const Eval ev = evaluateIn(own<State>(state), t, y);
  const double t0 = s_.axis.Rv0, t0max = s_.axis.peak * s_.axis.Rv0;
  double g0 = 1, g1 = 1;
  drive::frictionRoots(mode, ev.stuck_torque, ev.wm, ev.wm_dot, t0, t0max, g0, g1);
  g[0] = g0;
  g[1] = g1;
}

void RobotR3Axis::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              const std::vector<int>& fired) const {
  FrictionMode& mode = own<State>(state).mode;
  Eval ev{};
  drive::iterateFrictionModes(
      &mode, 1, fired, [&] { ev = evaluateIn(own<State>(state), t, y); },
      [&](size_t) {
        drive::FrictionElementView v;
        v.S = ev.stuck_torque;
        v.w = ev.wm;
        v.a = ev.wm_dot;
        v.tau0 = s_.axis.Rv0;
        v.tau0max = s_.axis.peak * s_.axis.Rv0;
        return v;
      });
}

void RobotR3Axis::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::VectorXd> row) const {
  const FrictionMode m = own<State>(state).mode;
  const Eval ev = evaluateIn(own<State>(state), t, y);
  const int mode = drive::frictionModeNumber(m);
  row << y[4], y[2], y[3], y[0], y[1], y[5], y[6], mode, m == FrictionMode::StartBackward ? 1.0 : 0.0,
      m == FrictionMode::StartForward ? 1.0 : 0.0, ev.tau_f, ev.i_ref, y[7], storedEnergy(y), y[8], y[9], y[10];
}

bool RobotR3Axis::alwaysActive(int port) const { return port == 1; }

}  // namespace jointsim::systems
