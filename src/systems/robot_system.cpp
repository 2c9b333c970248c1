// RobotSystem (robot_system.hpp): construction, the run state, configuration, the initial state (its bytes:
// robot_state.cpp).
#include "jointsim/systems/robot_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/algorithms.hpp"

#include "systems/robot_system_internal.hpp"

namespace jointsim::systems {

using detail::controllerDriven;
using detail::entryOf;
using detail::quantise;

void RobotSignals::resize(int n) {
  for (Eigen::VectorXd* v : {&q_set, &qd_set, &qdd_set, &q_fb, &qm, &qdm, &current, &i_ref, &u, &voltage, &tau_motor,
                             &tau_gear, &tau_friction, &tau_joint, &tau_stop, &qdd})
    v->setZero(n);
}

RobotSystem::RobotSystem(multibody::Model model, std::vector<DriveSpec> drives, Eigen::MatrixXd coupling)
    : model_(std::move(model)), drives_(std::move(drives)) {
  const int n = model_.nq;
  if (static_cast<int>(drives_.size()) != n)
    throw InputError("robot '" + model_.name + "' has " + std::to_string(n) + " joints but " +
                     std::to_string(drives_.size()) + " drives were given; expected one drive per joint");
  // Order the drives as the joints; every joint exactly once.
  std::vector<DriveSpec> ordered(static_cast<size_t>(n));
  std::vector<bool> seen(static_cast<size_t>(n), false);
  for (auto& d : drives_) {
    const int j = model_.jointIndex(d.joint);
    if (seen[static_cast<size_t>(j)]) throw InputError("joint '" + d.joint + "' has two drives");
    seen[static_cast<size_t>(j)] = true;
    ordered[static_cast<size_t>(j)] = std::move(d);
  }
  drives_ = std::move(ordered);
  if (coupling.size() == 0) {
    G_ = Ginv_ = Eigen::MatrixXd::Identity(n, n);
  } else {
    if (coupling.rows() != n || coupling.cols() != n)
      throw InputError("coupling matrix must be " + std::to_string(n) + "x" + std::to_string(n));
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(coupling);
    if (!lu.isInvertible()) throw InputError("coupling matrix must be invertible");
    G_ = coupling;
    Ginv_ = lu.inverse();
    coupled_ = !G_.isIdentity(0.0);
  }
  const Eigen::VectorXd file_armature = model_.armature.size() == n ? model_.armature : Eigen::VectorXd::Zero(n);
  reflected_ = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rotor = Eigen::VectorXd::Zero(n);
  n_states_ = 2 * n;
  layout_.resize(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const std::string where = "drive of joint '" + d.joint + "'";
    if (!d.transmission) throw InputError(where + ": missing transmission");
    drive::DcMotor{d.motor};  // validates
    d.controller.validate(where + ".controller");
    controllers_.emplace_back(d.controller);
    const bool voltage_out = d.controller.type == control::ControllerType::VoltageCascade;
    if (voltage_out && !d.electrics)
      throw InputError(where + ": the voltage_cascade controller needs the motor electrics");
    if (voltage_out) {
      // The continuous current loop L di/dt = V − R i, V = P_cur e + I_cur ∫e has the poles of
      // L s² + (R + P_cur) s + I_cur = 0, of magnitude at most (R + P_cur)/L + √(I_cur/L). Real current loops are
      // switched at ≤ ~100 kHz; poles beyond 1e8 rad/s (16 MHz) are a typo (P_cur = 1e12), and integrating them
      // takes steps of nanoseconds (such a run crawled for minutes before failing). Refused when the file is read.
      const control::JointControllerParams& c = d.controller;
      const double fastest = (d.motor.R + c.P_cur) / d.motor.L + std::sqrt(c.I_cur / d.motor.L);
      if (!(fastest <= kMaxCurrentLoopPole))
        throw InputError(where + ".controller: P_cur = " + formatNumber(c.P_cur) +
                         " V/A and I_cur = " + formatNumber(c.I_cur) + " V/(A·s) with R = " + formatNumber(d.motor.R) +
                         " Ω and L = " + formatNumber(d.motor.L) + " H give a current loop with poles up to " +
                         formatNumber(fastest, 3) + " rad/s, beyond " + formatNumber(kMaxCurrentLoopPole) +
                         " rad/s (16 MHz; real current loops switch at ~100 kHz): expected gains with (R + P_cur)/L + "
                         "√(I_cur/L) ≤ 1e8 rad/s");
    }
    if (!voltage_out && d.controller.type != control::ControllerType::None && d.electrics)
      throw InputError(where + ": the torque_cascade controller commands torque; set electrics: false");
    DriveLayout& L = layout_[static_cast<size_t>(k)];
    L.rigid = d.transmission->isRigid();
    L.ratio = d.transmission->ratio();
    if (L.rigid) {
      rotor[k] = L.ratio * L.ratio * d.motor.J_M;
    } else {
      L.motor = n_states_;
      n_states_ += 2;
    }
    if (d.electrics) L.current = n_states_++;
    L.n_gear = d.transmission->stateSize();
    if (L.n_gear > 0) {
      L.gear = n_states_;
      n_states_ += L.n_gear;
    }
    L.n_friction = d.friction ? d.friction->stateSize() : 0;
    if (L.n_friction > 0) {
      L.friction = n_states_;
      n_states_ += L.n_friction;
    }
    L.n_controller = controllers_.back().stateSize();
  }
  for (int k = 0; k < n; ++k) {
    for (int kind = 0; kind < 3; ++kind) inputs_.push_back({k, kind});
    for (CommandPort p :
         {CommandPort::MotorVelocity, CommandPort::Current, CommandPort::Voltage, CommandPort::MotorTorque})
      if (portRefusal(k, p).empty()) inputs_.push_back({k, 3 + static_cast<int>(p)});
  }
  for (int k = 0; k < n; ++k) {  // load torques after every command port (their indices stay as before)
    inputs_.push_back({k, kLoadTorqueInput});
    sim::InputPort p;
    p.name = drives_[static_cast<size_t>(k)].joint + ".load_torque";
    p.unit = model_.joint_types[static_cast<size_t>(k)] == multibody::JointType::Prismatic ? "N" : "N·m";
    p.description = "external torque at the joint " + drives_[static_cast<size_t>(k)].joint + " (0 until set)";
    load_ports_.push_back(p);
  }
  load_profiles_.resize(static_cast<size_t>(n));
  // Controller states come last, so that sampled control can take them out of the ODE state.
  for (auto& L : layout_) {
    if (L.n_controller > 0) {
      L.controller = n_states_;
      n_states_ += L.n_controller;
    }
  }
  if (coupled_ && rotor.any()) {
    crba_path_ = true;
    reflected_ = Ginv_.transpose() * rotor.asDiagonal() * Ginv_;
  } else {
    model_.armature = file_armature + rotor;  // diagonal reflected rotor inertia: ABA handles it
  }
  // The logged signals and the inverse-dynamics reference model (the rotor inertias of all drives as
  // armature; rigid ones are already in the system's armature).
  id_model_ = model_;
  for (int k = 0; k < n; ++k) {
    const auto& L = layout_[static_cast<size_t>(k)];
    if (!L.rigid) id_model_.armature[k] += L.ratio * L.ratio * drives_[static_cast<size_t>(k)].motor.J_M;
  }
  tip_ = model_.frameIndex(model_.tip_frame);
  const char* per_joint[][2] = {
      {"q_set", "rad"},    {"q", "rad"},         {"q_fb", "rad"},  {"qd", "rad/s"},        {"motor_velocity", "rad/s"},
      {"current", "A"},    {"current_ref", "A"}, {"voltage", "V"}, {"gear_torque", "N·m"}, {"friction_torque", "N·m"},
      {"id_torque", "N·m"}};
  for (const auto& name : model_.joint_names)
    for (const auto& c : per_joint) signal_names_.push_back(std::string(c[0]) + "_" + name + "[" + c[1] + "]");
  for (const char* c : {"tcp_x[m]", "tcp_y[m]", "tcp_z[m]", "tcp_roll[rad]", "tcp_pitch[rad]", "tcp_yaw[rad]"})
    signal_names_.emplace_back(c);
}

RobotSystem::State::State(const RobotSystem& robot)
    : PlantStateOf(robot), drives(robot.drives_), data(robot.model_), id_data(robot.id_model_), jac_data(robot.model_) {
  const int n = robot.model_.nq;
  port.assign(static_cast<size_t>(n), CommandPort::Setpoint);
  applied_port = port;
  cmd.setZero(n);
  applied_cmd.setZero(n);
  ref_held.assign(static_cast<size_t>(n), 0);
  ref_q.setZero(n);
  ref_qd.setZero(n);
  ref_qdd.setZero(n);
  q_start = robot.q0_.size() == n ? robot.q0_ : Eigen::VectorXd::Zero(n);
  ctrl_x.assign(static_cast<size_t>(robot.n_ctrl_sampled_), 0.0);
  held_u.setZero(n);
  held_i_ref.setZero(n);
  held_q_fb.setZero(n);
  prev_qm_meas.setZero(n);
  engine.seed(robot.seed_);
  fault_applied.assign(robot.faults_.size(), 0.0);
  stuck_episode.assign(robot.faults_.size(), -1);
  stuck_value.assign(robot.faults_.size(), 0.0);
  anchor.setZero(n);
  loads.resize(static_cast<size_t>(n));
  for (const DriveSpec& d : drives) motors.emplace_back(d.motor);
  sig.resize(n);
  out_is_voltage.assign(static_cast<size_t>(n), 0);
  zero.setZero(n);
  phi.setZero(n);
  phid.setZero(n);
  tau_out.setZero(n);
  tau.setZero(n);
  tmp.setZero(robot.n_states_);
  fext.setZero(6, n);
  M.setZero(n, n);
  llt = Eigen::LLT<Eigen::MatrixXd>(n);
  llt.compute(Eigen::MatrixXd::Identity(n, n));  // a defined status before the first use (the object is copied)
  // The Jacobian's workspace, sized here: jacobian() does not allocate.
  jac_structure = robot.jacobianStructure(&jac_block_drive);
  jac_block_columns.assign(jac_block_drive.size(), 0);
  friction_memo.resize(robot.drives_.size());
  jac_y.setZero(robot.n_states_);
  jac_f.setZero(robot.n_states_);
  jac_tau0.setZero(n);
  jac_qdd0.setZero(n);
  jac_tau.setZero(n);
  jac_P.setZero(n, n);
  // The faults as they are at t = 0 (start() sets them for its start time and state).
  if (!robot.faults_.empty()) robot.updateFaults(*this, 0.0, Eigen::VectorXd::Zero(robot.n_states_), true);
}

void RobotSystem::setJointLimits(const JointLimitSettings& settings) {
  checkConfigurable("setJointLimits");
  signal_names_.resize(signal_names_.size() - stops_.joints().size());  // the signals of earlier stops
  stops_ = EndStops(model_, settings);
  for (int i : stops_.joints())
    signal_names_.push_back("end_stop_torque_" + model_.joint_names[static_cast<size_t>(i)] + "[N·m]");
}

void RobotSystem::roots(const sim::PlantState&, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                        Eigen::Ref<Eigen::VectorXd> g) const {
  stops_.roots(y.head(model_.nq), g.data());
}

void RobotSystem::setSetpoints(SetpointFunction f) {
  checkConfigurable("setSetpoints");
  setpoints_ = std::move(f);
  setpoint_breaks_.clear();
  rests_.clear();
}

void RobotSystem::setRelativeReplay(bool on) {
  checkConfigurable("setRelativeReplay");
  relative_ = on;
}

bool RobotSystem::restStartsAt(int k, double t, double tol) const {
  if (rests_.empty()) return false;
  const auto& r = rests_[static_cast<size_t>(k)];
  // The first rest starting at or after t − tol.
  const auto it = std::lower_bound(r.begin(), r.end(), t - tol,
                                   [](const std::pair<double, double>& a, double x) { return a.first < x; });
  return it != r.end() && it->first <= t + tol;
}

void RobotSystem::reanchor(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool all) const {
  // The trajectory itself (not the references held through the ports), against the measured angle of the state y
  // (also under sampled control, where the held measurement may be unset at a start or a sample old at an event).
  if (setpoints_)
    setpoints_(t, st.sig.q_set, st.sig.qd_set, st.sig.qdd_set);
  else
    st.sig.q_set = st.q_start;
  const double tol = 1e-9 * std::max(1.0, std::abs(t));
  for (int k = 0; k < model_.nq; ++k) {
    if (!all && !restStartsAt(k, t, tol)) continue;
    const double q_meas = faultySensor(st, k, t, y[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias);
    st.anchor[k] = q_meas - st.sig.q_set[k];
  }
}

void RobotSystem::setTrajectory(std::shared_ptr<const control::JointTrajectory> trajectory) {
  checkConfigurable("setTrajectory");
  if (!trajectory) throw InputError(name() + ": no trajectory given");
  if (trajectory->dof() != model_.nq)
    throw InputError(name() + ": the trajectory has " + std::to_string(trajectory->dof()) + " joints, the robot " +
                     std::to_string(model_.nq));
  setpoint_breaks_ = trajectory->breakpoints();
  rests_ = trajectory->rests();
  if (!rests_.empty()) {
    if (rests_.size() != static_cast<size_t>(model_.nq))
      throw InputError(name() + ": the trajectory lists rests of " + std::to_string(rests_.size()) +
                       " joints, the robot has " + std::to_string(model_.nq));
    for (const auto& r : rests_)
      for (size_t i = 0; i < r.size(); ++i)
        if (std::isnan(r[i].first) || std::isnan(r[i].second) || r[i].first > r[i].second ||
            (i > 0 && r[i].first < r[i - 1].second))
          throw InputError(name() + ": the trajectory's rests must be increasing, disjoint intervals");
  }
  setpoints_ = [trajectory](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                            Eigen::Ref<Eigen::VectorXd> qdd) { trajectory->evaluate(t, q, qd, qdd); };
}

void RobotSystem::setInitialPositions(const Eigen::VectorXd& q0) {
  checkConfigurable("setInitialPositions");
  if (q0.size() != model_.nq)
    throw InputError(name() + ": initial joint positions: expected " + std::to_string(model_.nq) + " values");
  q0_ = q0;
}

bool RobotSystem::unboundedState(int i) const {
  if (i >= 0 && i < model_.nq) return true;
  for (const DriveLayout& L : layout_)
    if (L.motor >= 0 && i == L.motor) return true;
  return false;
}

std::string RobotSystem::stateName(int i) const {
  const int n = model_.nq;
  if (i < 0 || i >= n_states_) return {};
  if (i < n) return "q_" + model_.joint_names[static_cast<size_t>(i)] + " [rad]";
  if (i < 2 * n) return "qd_" + model_.joint_names[static_cast<size_t>(i - n)] + " [rad/s]";
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const std::string d = "drive of joint '" + model_.joint_names[static_cast<size_t>(k)] + "': ";
    auto in = [i](int first, int count) { return first >= 0 && i >= first && i < first + count; };
    if (in(L.motor, 1)) return d + "motor angle [rad]";
    if (in(L.motor + 1, 1) && L.motor >= 0) return d + "motor speed [rad/s]";
    if (in(L.current, 1)) return d + "motor current [A]";
    if (in(L.gear, L.n_gear)) return d + "transmission state " + std::to_string(i - L.gear);
    if (in(L.friction, L.n_friction)) return d + "friction state " + std::to_string(i - L.friction);
    if (sample_rate_ <= 0.0 && in(L.controller, L.n_controller))
      return d + "controller state " + std::to_string(i - L.controller);
  }
  return {};
}

Eigen::VectorXd RobotSystem::initialState() const {
  if (q0_.size() == model_.nq) return initialState(q0_);
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(model_.nq);
  if (setpoints_) {
    Eigen::VectorXd qd(model_.nq), qdd(model_.nq);
    setpoints_(0.0, q0, qd, qdd);
  }
  return initialState(q0);
}

std::vector<double> RobotSystem::timeEvents(double t_end) const {
  // Under sampled control the right-hand side does not read the reference (the held outputs do), and every
  // sample restarts the integrator anyway.
  std::vector<double> events = sampled() ? std::vector<double>{} : setpoint_breaks_;
  if (relative_)  // the rests' starts re-anchor the reference
    for (const auto& r : rests_)
      for (const auto& rest : r)
        if (std::isfinite(rest.first) && rest.first > 0.0 && rest.first < t_end) events.push_back(rest.first);
  for (const Fault& f : faults_) {
    const std::vector<double> e = faultEvents(f, t_end);
    events.insert(events.end(), e.begin(), e.end());
  }
  for (double b : load_profiles_.breakpoints(t_end)) events.push_back(b);  // load-torque profiles' jumps
  return events;
}

void RobotSystem::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              const std::vector<int>&) const {
  updateFaults(own<State>(state), t, y, false);
  if (relative_) reanchor(own<State>(state), t, y, false);
}

void RobotSystem::start(sim::PlantState& state, double t0, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  st.q_start = y.head(model_.nq);
  updateFaults(st, t0, y, true);
  if (relative_) reanchor(st, t0, y, true);
  st.applied_port = st.port;  // the state starts consistent with the ports as they are
  st.applied_cmd = st.cmd;
  if (sampled()) {
    // The controller states (outside y) holding the gravity load at y's joint angles, as initialState() sets them.
    const Eigen::VectorXd full = initialFull(y.head(model_.nq), t0);
    st.ctrl_x.assign(full.data() + n_states_, full.data() + full.size());
    st.first_sample = true;  // a (re)start: the encoder speed and the outer loops begin afresh
    st.inner_count = 0;
    controlStep(state, t0, y);
  }
}

void RobotSystem::setExternalWrenches(WrenchFunction f) {
  checkConfigurable("setExternalWrenches");
  wrenches_ = std::move(f);
}

void RobotSystem::setSampledControl(double rate, unsigned seed, double current_rate) {
  checkConfigurable("setSampledControl");
  if (!(rate > 0.0) || !std::isfinite(rate)) throw InputError("control rate: expected a sampling rate > 0 Hz");
  if (sample_rate_ > 0.0) throw InputError("sampled control already set");
  long per_outer = 1;
  if (current_rate != 0.0) {
    per_outer = std::isfinite(current_rate) ? std::lround(current_rate / rate) : 0;
    if (!(current_rate >= rate) || per_outer < 1 ||
        std::abs(static_cast<double>(per_outer) * rate - current_rate) > 1e-9 * current_rate)
      throw InputError("current rate " + formatNumber(current_rate) +
                       " Hz: expected an integer multiple of the control rate " + formatNumber(rate) + " Hz");
  }
  const double loop_rate = current_rate != 0.0 ? current_rate : rate;
  // A current loop that the sampling makes unstable would ring at the Nyquist frequency against the supply
  // limits: refuse it, naming the rate from which it is stable.
  for (size_t k = 0; k < drives_.size(); ++k) {
    const DriveSpec& d = drives_[k];
    if (!d.electrics) continue;
    auto radius = [&](double f) {
      return control::sampledCurrentLoopRadius(d.controller, d.motor.R, d.motor.L, 1.0 / f);
    };
    const double rho = radius(loop_rate);
    if (rho < 1.0) continue;
    double lo = loop_rate, hi = loop_rate;
    while (radius(hi) >= 1.0 && hi < 1e9) hi *= 2.0;
    for (int it = 0; it < 60; ++it) {
      const double mid = std::sqrt(lo * hi);
      (radius(mid) >= 1.0 ? lo : hi) = mid;
    }
    throw InputError(std::string(current_rate != 0.0 ? "current rate " : "control rate ") + formatNumber(loop_rate) +
                     " Hz: the current loop of drive '" + d.joint + "' (P_cur = " + formatNumber(d.controller.P_cur) +
                     " V/A, I_cur = " + formatNumber(d.controller.I_cur) + " V/(A·s), R = " + formatNumber(d.motor.R) +
                     " Ω, L = " + formatNumber(d.motor.L) +
                     " H) is unstable when sampled at this rate (discrete pole magnitude " + formatNumber(rho, 3) +
                     " ≥ 1): it would ring at the Nyquist frequency against the supply "
                     "voltage. It is stable from about " +
                     formatNumber(hi, 3) +
                     " Hz; sample faster, run the current loop "
                     "faster than the outer loops (control.current_rate), or lower P_cur");
  }
  sample_rate_ = rate;
  current_rate_ = per_outer > 1 ? current_rate : 0.0;  // equal rates: the single-rate controller
  inner_per_outer_ = per_outer;
  int first = n_states_;
  for (const auto& L : layout_)
    if (L.controller >= 0) first = std::min(first, L.controller);
  n_ctrl_sampled_ = n_states_ - first;
  for (auto& L : layout_)
    if (L.controller >= 0) L.controller -= first;  // now an index into State::ctrl_x
  n_states_ = first;
  seed_ = seed;
}

Eigen::VectorXd RobotSystem::initialState(const Eigen::VectorXd& q0, double t0) const {
  if (q0.size() != model_.nq)
    throw InputError("initial joint positions: expected " + std::to_string(model_.nq) + " values");
  // With sampled control the controller states live outside y (start() sets them from the same computation).
  return initialFull(q0, t0).head(n_states_);
}

Eigen::VectorXd RobotSystem::initialFull(const Eigen::VectorXd& q0, double t0) const {
  const int n = model_.nq;
  // A state for its workspace and the drives with the faults active at t0.
  State st(*this);
  updateFaults(st, t0, Eigen::VectorXd::Zero(n_states_), true);
  const int n_full = n_states_ + n_ctrl_sampled_;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_full);
  y.head(n) = q0;
  if (setpoints_) {
    setpoints_(t0, st.sig.q_set, st.sig.qd_set, st.sig.qdd_set);
  } else {
    st.sig.q_set = q0;
    st.sig.qd_set.setZero();
    st.sig.qdd_set.setZero();
  }
  if (relative_)  // the relative replay starts on the measured angles (start() anchors there)
    for (int k = 0; k < n; ++k) st.sig.q_set[k] = q0[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias;
  // Gravity preload: each drive starts holding its share of the static joint torques.
  const Eigen::VectorXd g = multibody::gravityTorques(model_, st.data, q0);
  const Eigen::VectorXd tau_out_needed = coupled_ ? Eigen::VectorXd(G_.transpose() * g) : g;
  const Eigen::VectorXd phi = Ginv_ * q0;
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const bool holds = d.controller.type != control::ControllerType::None;
    const double target = holds ? tau_out_needed[k] : 0.0;
    double q_in = L.ratio * phi[k], tau_M = 0.0;
    if (L.rigid) {
      tau_M = target / L.ratio;
    } else {
      // Secant iterations on the motor angle for the static output torque (exact in one step for a linear gear).
      double* x = L.gear >= 0 ? y.data() + L.gear : nullptr;
      std::vector<double> xd(static_cast<size_t>(std::max(1, L.n_gear)));
      auto outTorque = [&](double qm) {
        d.transmission->initialState(qm, phi[k], x);
        return d.transmission->evaluate({qm, 0.0, phi[k], 0.0}, x, xd.data());
      };
      double a = q_in, fa = outTorque(a).tau_out - target;
      double b = q_in + 1e-3 * L.ratio, fb = outTorque(b).tau_out - target;
      for (int it = 0; it < 50 && std::abs(fb) > 1e-12 * (1.0 + std::abs(target)); ++it) {
        if (fb == fa) break;
        const double c = b - fb * (b - a) / (fb - fa);
        a = b;
        fa = fb;
        b = c;
        fb = outTorque(b).tau_out - target;
      }
      q_in = b;
      tau_M = outTorque(q_in).tau_in;
      y[L.motor] = q_in;
    }
    const double i = d.electrics ? tau_M / d.motor.kt : 0.0;
    if (L.current >= 0) y[L.current] = i;
    if (L.friction >= 0) d.friction->initialState(y.data() + L.friction);
    if (L.controller >= 0) {
      const int c = sampled() ? n_states_ + L.controller : L.controller;
      control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], q0[k], q_in, 0.0, i, L.ratio, d.motor.V_supply};
      controllers_[static_cast<size_t>(k)].initialState(in, y.data() + c);
      if (holds && d.controller.type == control::ControllerType::VoltageCascade) {
        // Integrators holding the static current and voltage: i_ref = I_vel ∫e_vel, V = I_cur ∫e_cur = R i.
        if (d.controller.I_vel > 0) y[c] = i / d.controller.I_vel;
        if (d.controller.I_cur > 0) y[c + 1] = d.motor.R * i / d.controller.I_cur;
      } else if (holds && d.controller.type == control::ControllerType::TorqueCascade && d.controller.ks > 0) {
        y[c] += tau_M / d.controller.ks;
      }
    }
  }
  return y;
}

}  // namespace jointsim::systems
