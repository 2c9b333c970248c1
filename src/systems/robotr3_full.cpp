#include "jointsim/systems/robotr3_full.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <Eigen/Cholesky>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::systems {

RobotR3AxisParams RobotR3AxisParams::fullRobot(int j) {
  // Axis parameters of [MSL, RobotR3.FullRobot].
  static const int type[6] = {1, 1, 1, 2, 2, 2};
  static const double ratio[6] = {-105, 210, 60, -99, 79.2, -99};
  static const double c[6] = {43, 8, 58, 0, 0, 0}, d[6] = {0.005, 0.01, 0.04, 0, 0, 0};
  static const double Rv0[6] = {0.4, 0.5, 0.7, 21.8, 30.1, 10.9};
  static const double Rv1[6] = {0.13 / 160, 0.1 / 130, 0.2 / 130, 9.8, 0.03, 3.92};
  static const double peak[6] = {1, 1, 1, 26.7 / 21.8, 39.6 / 30.1, 16.8 / 10.9};
  if (j < 1 || j > 6) throw InputError("RobotR3 axis must be 1..6, got " + std::to_string(j));
  RobotR3AxisParams p;
  const auto k = static_cast<size_t>(j - 1);
  p.type = type[k];
  p.ratio = ratio[k];
  p.motor = drive::OpAmpMotorParams::robotR3Axis(j);
  p.c = c[k];
  p.d = d[k];
  p.Rv0 = Rv0[k];
  p.Rv1 = Rv1[k];
  p.peak = peak[k];
  return p;
}

RobotR3AxisParams RobotR3AxisParams::oneAxis() {
  RobotR3AxisParams p;  // [MSL, RobotR3.OneAxis]
  p.type = 1;
  p.ratio = 210.0;
  p.motor = drive::OpAmpMotorParams::oneAxis();
  p.c = 8.0;
  p.d = 0.01;
  p.Rv0 = 0.5;
  p.Rv1 = 0.1 / 130.0;
  p.peak = 1.0;
  p.kp = 5.0;
  p.ks = 0.5;
  p.Ts = 0.05;
  return p;
}

void RobotR3FullSetup::validate() const {
  const char* const c = "RobotR3 robot";
  const auto n = static_cast<size_t>(arm.nq);
  check::that(axes.size() == n, c, "axes", "expected one axis per joint (" + std::to_string(n) + ")");
  for (size_t k = 0; k < axes.size(); ++k) {
    const auto& a = axes[k];
    const std::string key = "axes[" + std::to_string(k) + "]";
    a.motor.validate();
    check::that(a.type == 1 || a.type == 2, c, key + ".type", "expected axis type 1 or 2");
    check::nonZero(c, key + ".ratio", a.ratio, "(-)");
    if (a.type == 1) check::positive(c, key + ".c", a.c, "N·m/rad (type-1 spring)");
    check::atLeast(c, key + ".peak", a.peak, 1.0, "(-)");
    check::nonNegative(c, key + ".Rv0", a.Rv0, "N·m");
    check::positive(c, key + ".Ts", a.Ts, "s");
    if (initial_friction.size() == static_cast<Eigen::Index>(n))
      check::that(std::abs(initial_friction[static_cast<Eigen::Index>(k)]) <= a.peak * a.Rv0, c,
                  "initial_friction[" + std::to_string(k) + "]", "expected a torque within ±peak·Rv0");
  }
  check::that(initial_friction.size() == 0 || initial_friction.size() == static_cast<Eigen::Index>(n), c,
              "initial_friction", "expected one value per joint (or none)");
  check::that(load_inertia.size() == 0 || load_inertia.size() == static_cast<Eigen::Index>(n), c, "load_inertia",
              "expected one value per joint (or none: the arm's dynamics)");
  for (Eigen::Index k = 0; k < load_inertia.size(); ++k)
    check::positive(c, "load_inertia[" + std::to_string(k) + "]", load_inertia[k], "kg·m²");
  if (!one_axis_prefix.empty())
    check::that(n == 1 && axes[0].type == 1 && energy, c, "one_axis_prefix",
                "the OneAxis columns need a single type-1 axis with energy bookkeeping");
  const char* names[] = {"path.q_begin", "path.q_end", "path.qd_max", "path.qdd_max"};
  int i = 0;
  for (const Eigen::VectorXd* v : {&q_begin, &q_end, &qd_max, &qdd_max})
    check::that(static_cast<size_t>(v->size()) == n, c, names[i++], "expected one value per joint");
  check::positive(c, "stop_time", stop_time, "s");
  check::positive(c, "log_interval", log_interval, "s");
}

RobotR3Full::RobotR3Full(RobotR3FullSetup setup)
    : s_((setup.validate(), std::move(setup))),
      n_(s_.arm.nq),
      path_(s_.q_begin, s_.q_end, s_.qd_max, s_.qdd_max, s_.start_time) {
  // Type-2 rotors move with the joints: N² J joins the arm's joint-space inertia ([MSL, RobotR3.Utilities.GearType2]).
  s_.arm.armature = Eigen::VectorXd::Zero(n_);
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    if (a.type == 2) s_.arm.armature[j] = a.ratio * a.ratio * a.motor.J;
    controllers_.push_back(control::JointController::torqueCascade(a.kp, a.ks, a.Ts));
  }
  n_states_ = 2 * n_;
  rel_.assign(static_cast<size_t>(n_), -1);
  for (int j = 0; j < n_; ++j)
    if (s_.axes[static_cast<size_t>(j)].type == 1) {
      rel_[static_cast<size_t>(j)] = n_states_;
      n_states_ += 2;
    }
  ctrl_.assign(static_cast<size_t>(n_), 0);
  for (int j = 0; j < n_; ++j) {
    ctrl_[static_cast<size_t>(j)] = n_states_;
    n_states_ += 3;
  }
  if (s_.energy) {
    energy_ = n_states_;
    n_states_ += 4;
  }
  if (!s_.one_axis_prefix.empty()) {  // [MSL, RobotR3.OneAxis]
    const std::string& p = s_.one_axis_prefix;
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
                p + ".motor.i_ref[A]"};
  } else {  // [MSL, RobotR3.FullRobot]
    for (int j = 1; j <= n_; ++j) signals_.push_back("axis" + std::to_string(j) + ".controller.PI.x[rad/s]");
    for (int j = 1; j <= n_; ++j)
      if (s_.axes[static_cast<size_t>(j - 1)].type == 1)
        signals_.push_back("axis" + std::to_string(j) + ".gear.spring.phi_rel[rad]");
    for (int j = 1; j <= n_; ++j)
      if (s_.axes[static_cast<size_t>(j - 1)].type == 1)
        signals_.push_back("axis" + std::to_string(j) + ".gear.spring.w_rel[rad/s]");
    for (int j = 1; j <= n_; ++j) signals_.push_back("axis" + std::to_string(j) + ".motor.C.v[V]");
    for (int j = 1; j <= n_; ++j) signals_.push_back("axis" + std::to_string(j) + ".motor.La.i[A]");
    signals_.emplace_back("mechanics.b2.body.w_a[1][rad/s]");
    for (int j = 1; j <= n_; ++j) signals_.push_back("mechanics.r" + std::to_string(j) + ".phi[rad]");
    for (int j = 1; j <= n_; ++j)
      if (j != 2) signals_.push_back("mechanics.r" + std::to_string(j) + ".w[rad/s]");
    for (int j = 1; j <= n_; ++j) signals_.push_back("axis" + std::to_string(j) + ".gear.bearingFriction.mode[-]");
  }
  if (s_.energy) {  // after the OneAxis reference columns: W_el, stored, E_R, E_d, E_f
    for (const char* e : {"amplifier_work", "stored", "resistor_loss", "damper_loss", "friction_loss"})
      signals_.push_back(std::string("energy.") + e + "[J]");
  }
  for (int j = 0; j < n_; ++j) {
    const std::string& joint = s_.arm.joint_names[static_cast<size_t>(j)];
    sim::InputPort c;
    c.name = joint + ".current";
    c.unit = "A";
    c.description = "current reference of axis " + std::to_string(j + 1) + " (held in place of its controller's)";
    ports_.push_back(c);
    sim::InputPort l;
    l.name = joint + ".load_torque";
    l.unit = "N·m";
    l.description = "external torque at the joint " + joint;
    ports_.push_back(l);
  }
  profiles_.resize(ports_.size());
}

RobotR3Full::State::State(const RobotR3Full& robot)
    : PlantStateOf(robot), modes(static_cast<size_t>(robot.n_), FrictionMode::Stuck), data(robot.s_.arm) {
  for (Eigen::VectorXd* v : {&q_ref, &qd_ref, &qdd_ref, &tau, &qdd, &wm, &wm_dot, &tau_f, &stuck, &xdot, &iref})
    v->setZero(robot.n_);
  Mbar.setZero(robot.n_, robot.n_);
  inputs.resize(robot.ports_.size());
}

void RobotR3Full::State::save(ByteWriter& out) const {
  drive::saveModes(out, modes);
  inputs.save(out);
}

void RobotR3Full::State::load(ByteReader& in) {
  drive::loadModes(in, modes);
  inputs.load(in);
}

const std::vector<FrictionMode>& RobotR3Full::modes(const sim::PlantState& state) const {
  return own<State>(state).modes;
}

std::string RobotR3Full::name() const {
  return (s_.one_axis_prefix.empty() ? "RobotR3 '" : "RobotR3 axis '") + s_.name + "'";
}

sim::SimulateOptions RobotR3Full::simulateOptions() const {
  return sim::SimulateOptions::everyInterval(endTime(), s_.log_interval, s_.solver);
}

std::vector<double> RobotR3Full::modelTimeEvents(double /*t_end*/) const { return path_.breakpoints(); }

double RobotR3Full::endTime() const { return std::min(s_.stop_time, path_.endTime() + s_.swing_time); }

Eigen::VectorXd RobotR3Full::initialState() const {
  // [MSL, Rotational.Components.InitializeFlange] and the Motor's steady-state initial equations, with the
  // friction torque sa(0) = initial_friction (undetermined in MSL, 0 by default; docs/validation.md): at rest on the
  // start angles, springs and currents holding gravity, electrical and PI steady state.
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_states_);
  y.head(n_) = s_.q_begin;
  multibody::Data data(s_.arm);
  const Eigen::VectorXd G = s_.load_inertia.size() > 0 ? Eigen::VectorXd::Zero(n_)  // fixed loads: no gravity
                                                       : multibody::gravityTorques(s_.arm, data, s_.q_begin);
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    double phi_rel = 0.0, i = 0.0;
    const double sa0 = s_.initial_friction.size() > 0 ? s_.initial_friction[j] : 0.0;
    if (a.type == 1) {
      const double tau_s = -G[j] / a.ratio;  // τ_j = −N τ_s = G
      phi_rel = tau_s / a.c;
      i = (sa0 - tau_s) / a.motor.k;  // k i = τ_f(0) − τ_s
      y[rel_[static_cast<size_t>(j)]] = phi_rel;
    } else {
      i = (G[j] + sa0) / (a.ratio * a.motor.k);  // N k i = G + τ_f(0)
    }
    const int c = ctrl_[static_cast<size_t>(j)];
    y[c] = a.ks > 0.0 ? i / a.ks - a.kp * phi_rel : 0.0;  // x = i/ks − e(0)
    y[c + 1] = -(a.motor.Ra * i) / a.motor.amp_gain;
    y[c + 2] = i;
  }
  return y;
}

void RobotR3Full::solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const auto q = y.head(n_);
  const auto qd = y.segment(n_, n_);
  path_.evaluate(t, st.q_ref, st.qd_ref, st.qdd_ref);
  // Drive torques on the joints, with the friction of sliding type-2 joints.
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    const int c = ctrl_[static_cast<size_t>(j)];
    const double i = y[c + 2], N = a.ratio;
    double phi_m = N * q[j];
    st.wm[j] = N * qd[j];
    if (a.type == 1) {
      const int r = rel_[static_cast<size_t>(j)];
      phi_m -= y[r];
      st.wm[j] -= y[r + 1];
      const double tau_s = a.c * y[r] + a.d * y[r + 1];
      st.tau[j] = -N * tau_s;
      st.stuck[j] = a.motor.k * i + tau_s;  // motor-side friction that keeps dω_m/dt = 0
    } else {
      st.tau[j] = N * a.motor.k * i;
    }
    st.tau[j] += profiles_.value(st.inputs, static_cast<size_t>(2 * j + 1), t);  // external torque at the joint
    control::ControllerInputs in;  // the axis controller, its output the current reference [A]
    in.ratio = N;
    in.q_set = st.q_ref[j];
    in.qd_set = st.qd_ref[j];
    in.qm_fb = phi_m;
    in.qdm_fb = st.wm[j];
    st.iref[j] = controllers_[static_cast<size_t>(j)].evaluate(in, y.data() + c, &st.xdot[j]).u;
    if (profiles_.active(st.inputs, static_cast<size_t>(2 * j))) {  // in place of the controller, which freezes
      st.iref[j] = profiles_.value(st.inputs, static_cast<size_t>(2 * j), t);
      st.xdot[j] = 0.0;
    }
    const double w = a.type == 1 ? st.wm[j] : qd[j];
    st.tau_f[j] =
        drive::frictionTorque(st.modes[static_cast<size_t>(j)], a.Rv0 + a.Rv1 * std::abs(w), 0.0);  // stuck: below
    if (a.type == 2 && st.modes[static_cast<size_t>(j)] != FrictionMode::Stuck) st.tau[j] -= st.tau_f[j];
  }
  // Arm: M̄ q̈ = τ − h, with q̈_j = 0 and τ_f,j unknown for stuck type-2 joints; fixed loads: M̄ diagonal, h = 0.
  const bool fixed_loads = s_.load_inertia.size() > 0;
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 12, 1> rhs(n_);
  if (fixed_loads) {
    st.Mbar.setZero();
    for (int j = 0; j < n_; ++j) st.Mbar(j, j) = s_.load_inertia[j] + s_.arm.armature[j];
    rhs = st.tau;
  } else {
    st.Mbar = multibody::crba(s_.arm, st.data, q);
    const Eigen::VectorXd& h = multibody::nonLinearEffects(s_.arm, st.data, q, qd);
    rhs = st.tau - h;
  }
  Eigen::Matrix<int, Eigen::Dynamic, 1, 0, 12, 1> freeIdx(n_);
  int nf = 0;
  for (int j = 0; j < n_; ++j) {
    const bool stuck2 =
        s_.axes[static_cast<size_t>(j)].type == 2 && st.modes[static_cast<size_t>(j)] == FrictionMode::Stuck;
    if (!stuck2) freeIdx[nf++] = j;
  }
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 12, 12> Mff(nf, nf);
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 12, 1> bf(nf);
  for (int a = 0; a < nf; ++a) {
    bf[a] = rhs[freeIdx[a]];
    for (int b = 0; b < nf; ++b) Mff(a, b) = st.Mbar(freeIdx[a], freeIdx[b]);
  }
  st.qdd.setZero();
  if (fixed_loads) {
    for (int a = 0; a < nf; ++a) st.qdd[freeIdx[a]] = rhs[freeIdx[a]] / st.Mbar(freeIdx[a], freeIdx[a]);
  } else if (nf > 0) {
    const Eigen::LLT<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 12, 12>> llt(Mff);
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 12, 1> x = llt.solve(bf);
    for (int a = 0; a < nf; ++a) st.qdd[freeIdx[a]] = x[a];
  }
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    if (a.type == 2 && st.modes[static_cast<size_t>(j)] == FrictionMode::Stuck) {
      // τ_f = τ_drive − h − (M̄ q̈)_j.
      st.stuck[j] = rhs[j] - st.Mbar.row(j).dot(st.qdd);
      st.tau_f[j] = st.stuck[j];
    }
  }
  // Motor accelerations of type-1 axes.
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    if (a.type == 2) {
      st.wm_dot[j] = a.ratio * st.qdd[j];
      continue;
    }
    if (st.modes[static_cast<size_t>(j)] == FrictionMode::Stuck) {
      st.tau_f[j] = st.stuck[j];
      st.wm_dot[j] = 0.0;
    } else {
      const int r = rel_[static_cast<size_t>(j)];
      const double tau_s = a.c * y[r] + a.d * y[r + 1];
      st.wm_dot[j] = (a.motor.k * y[ctrl_[static_cast<size_t>(j)] + 2] - st.tau_f[j] + tau_s) / a.motor.J;
    }
  }
}

void RobotR3Full::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> ydot) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  ydot.head(n_) = y.segment(n_, n_);
  ydot.segment(n_, n_) = st.qdd;
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    if (a.type == 1) {
      const int r = rel_[static_cast<size_t>(j)];
      ydot[r] = y[r + 1];
      ydot[r + 1] = a.ratio * st.qdd[j] - st.wm_dot[j];
    }
    const int c = ctrl_[static_cast<size_t>(j)];
    const auto& m = a.motor;
    ydot[c] = st.xdot[j];
    ydot[c + 1] = (y[c + 2] - st.iref[j]) / (m.Ri * m.C());
    ydot[c + 2] = (-m.amp_gain * y[c + 1] - m.Ra * y[c + 2] - m.k * st.wm[j]) / m.La();
  }
  if (energy_ >= 0) {  // W_el, E_R, E_d, E_f summed over the axes
    double W = 0.0, R = 0.0, D = 0.0, F = 0.0;
    for (int j = 0; j < n_; ++j) {
      const auto& a = s_.axes[static_cast<size_t>(j)];
      const int c = ctrl_[static_cast<size_t>(j)];
      W += -a.motor.amp_gain * y[c + 1] * y[c + 2];
      R += a.motor.Ra * y[c + 2] * y[c + 2];
      if (a.type == 1) D += a.d * y[rel_[static_cast<size_t>(j)] + 1] * y[rel_[static_cast<size_t>(j)] + 1];
      F += st.tau_f[j] * (a.type == 1 ? st.wm[j] : y[n_ + j]);
    }
    ydot[energy_] = W;
    ydot[energy_ + 1] = R;
    ydot[energy_ + 2] = D;
    ydot[energy_ + 3] = F;
  }
}

double RobotR3Full::storedEnergy(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  // ½ q̇ᵀ M̄ q̇ (M̄ from solve(), type-2 rotors as armature) + potential energy of the arm + per type-1 axis the
  // rotor ½ J ω_m² and spring ½ c φ_rel², per axis the inductance ½ La i².
  const auto qd = y.segment(n_, n_);
  double E = s_.load_inertia.size() > 0 ? 0.0 : multibody::potentialEnergy(s_.arm, st.data, y.head(n_));
  for (int a = 0; a < n_; ++a)
    for (int b = 0; b < n_; ++b) E += 0.5 * qd[a] * st.Mbar(a, b) * qd[b];
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    if (a.type == 1) {
      const double phi_rel = y[rel_[static_cast<size_t>(j)]];
      E += 0.5 * a.motor.J * st.wm[j] * st.wm[j] + 0.5 * a.c * phi_rel * phi_rel;
    }
    const double i = y[ctrl_[static_cast<size_t>(j)] + 2];
    E += 0.5 * a.motor.La() * i * i;
  }
  return E;
}

void RobotR3Full::roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                        Eigen::Ref<Eigen::VectorXd> g) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  for (int j = 0; j < n_; ++j) {
    const auto& a = s_.axes[static_cast<size_t>(j)];
    const double w = a.type == 1 ? st.wm[j] : y[n_ + j];
    const double acc = a.type == 1 ? st.wm_dot[j] : st.qdd[j];
    double g0 = 1, g1 = 1;
    drive::frictionRoots(st.modes[static_cast<size_t>(j)], st.stuck[j], w, acc, a.Rv0, a.peak * a.Rv0, g0, g1);
    g[2 * j] = g0;
    g[2 * j + 1] = g1;
  }
}

void RobotR3Full::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              const std::vector<int>& fired) const {
  State& st = own<State>(state);
  drive::iterateFrictionModes(
      st.modes.data(), st.modes.size(), fired, [&] { solve(st, t, y); },
      [&](size_t k) {
        const auto j = static_cast<int>(k);
        const auto& a = s_.axes[k];
        drive::FrictionElementView v;
        v.S = st.stuck[j];
        v.w = a.type == 1 ? st.wm[j] : y[n_ + j];
        v.a = a.type == 1 ? st.wm_dot[j] : st.qdd[j];
        v.tau0 = a.Rv0;
        v.tau0max = a.peak * a.Rv0;
        return v;
      });
}

void RobotR3Full::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::VectorXd> row) const {
  const State& st = own<State>(state);
  if (energy_ >= 0) solve(st, t, y);  // τ_f, i_ref, M̄ and ω_m at t
  Eigen::Index c = 0;
  auto energies = [&] {
    row[c++] = y[energy_];
    row[c++] = storedEnergy(st, y);
    for (int k = 1; k < 4; ++k) row[c++] = y[energy_ + k];
  };
  if (!s_.one_axis_prefix.empty()) {  // [MSL, RobotR3.OneAxis]: one type-1 axis, states as its Modelica model
    const FrictionMode m = st.modes[0];
    const int x = ctrl_[0], r = rel_[0];
    for (double v : {y[x], y[r], y[r + 1], y[0], y[1], y[x + 1], y[x + 2]}) row[c++] = v;
    row[c++] = drive::frictionModeNumber(m);
    row[c++] = m == FrictionMode::StartBackward ? 1.0 : 0.0;
    row[c++] = m == FrictionMode::StartForward ? 1.0 : 0.0;
    row[c++] = st.tau_f[0];
    row[c++] = st.iref[0];
    energies();
    return;
  }
  for (int j = 0; j < n_; ++j) row[c++] = y[ctrl_[static_cast<size_t>(j)]];
  for (int j = 0; j < n_; ++j)
    if (rel_[static_cast<size_t>(j)] >= 0) row[c++] = y[rel_[static_cast<size_t>(j)]];
  for (int j = 0; j < n_; ++j)
    if (rel_[static_cast<size_t>(j)] >= 0) row[c++] = y[rel_[static_cast<size_t>(j)] + 1];
  for (int j = 0; j < n_; ++j) row[c++] = y[ctrl_[static_cast<size_t>(j)] + 1];
  for (int j = 0; j < n_; ++j) row[c++] = y[ctrl_[static_cast<size_t>(j)] + 2];
  row[c++] = y[n_ + 1];  // b2's angular velocity about its joint axis = q̇_2 ([MSL] reference results)
  for (int j = 0; j < n_; ++j) row[c++] = y[j];
  for (int j = 0; j < n_; ++j)
    if (j != 1) row[c++] = y[n_ + j];
  for (int j = 0; j < n_; ++j) row[c++] = drive::frictionModeNumber(st.modes[static_cast<size_t>(j)]);
  if (energy_ >= 0) energies();
}

bool RobotR3Full::alwaysActive(int port) const { return port % 2 == 1; }

}  // namespace jointsim::systems
