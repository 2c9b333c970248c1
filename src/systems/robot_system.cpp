#include "jointsim/systems/robot_system.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::systems {

struct RobotSystem::Rng {
  std::mt19937_64 engine;
  std::normal_distribution<double> normal{0.0, 1.0};
  double gauss(double sigma) { return sigma > 0.0 ? sigma * normal(engine) : 0.0; }
};

namespace {
double quantise(double x, double quantum) { return quantum > 0.0 ? quantum * std::round(x / quantum) : x; }
}  // namespace

void RobotSignals::resize(int n) {
  for (Eigen::VectorXd* v : {&q_set, &qd_set, &qdd_set, &q_fb, &qm, &qdm, &current, &i_ref, &u, &voltage, &tau_motor,
                             &tau_gear, &tau_friction, &tau_joint, &tau_stop, &qdd})
    v->setZero(n);
}

RobotSystem::RobotSystem(multibody::Model model, std::vector<DriveSpec> drives, Eigen::MatrixXd coupling)
    : model_(std::move(model)), drives_(std::move(drives)), data_(model_), id_data_(model_) {
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
    motors_.emplace_back(d.motor);  // validates
    d.controller.validate(where + ".controller");
    controllers_.emplace_back(d.controller);
    const bool voltage_out = d.controller.type == control::ControllerType::Cascade002;
    if (voltage_out && !d.electrics) throw InputError(where + ": the cascade_002 controller needs the motor electrics");
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
      throw InputError(where + ": the motor_ppi_000 controller commands torque; set electrics: false");
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
  data_ = multibody::Data(model_);
  sig_.resize(n);
  out_is_voltage_.assign(static_cast<size_t>(n), 0);
  zero_.setZero(n);
  phi_.setZero(n);
  phid_.setZero(n);
  tau_out_.setZero(n);
  tau_.setZero(n);
  tmp_.setZero(n_states_);
  fext_.setZero(6, n);
  M_.setZero(n, n);
  llt_ = Eigen::LLT<Eigen::MatrixXd>(n);
  llt_.compute(Eigen::MatrixXd::Identity(n, n));  // a defined status before the first use (the object is copied)

  // The logged signals and the inverse-dynamics reference model (the rotor inertias of all drives as
  // armature; rigid ones are already in the system's armature).
  id_model_ = model_;
  for (int k = 0; k < n; ++k) {
    const auto& L = layout_[static_cast<size_t>(k)];
    if (!L.rigid) id_model_.armature[k] += L.ratio * L.ratio * drives_[static_cast<size_t>(k)].motor.J_M;
  }
  id_data_ = multibody::Data(id_model_);
  tip_ = model_.frameIndex(model_.tip_frame);
  port_.assign(static_cast<size_t>(n), CommandPort::Setpoint);
  applied_port_ = port_;
  cmd_.setZero(n);
  applied_cmd_.setZero(n);
  ref_held_.assign(static_cast<size_t>(n), 0);
  ref_q_.setZero(n);
  ref_qd_.setZero(n);
  ref_qdd_.setZero(n);
  const char* per_joint[][2] = {
      {"q_set", "rad"},    {"q", "rad"},         {"q_fb", "rad"},  {"qd", "rad/s"},        {"motor_velocity", "rad/s"},
      {"current", "A"},    {"current_ref", "A"}, {"voltage", "V"}, {"gear_torque", "N·m"}, {"friction_torque", "N·m"},
      {"id_torque", "N·m"}};
  for (const auto& name : model_.joint_names)
    for (const auto& c : per_joint) signal_names_.push_back(std::string(c[0]) + "_" + name + "[" + c[1] + "]");
  for (const char* c : {"tcp_x[m]", "tcp_y[m]", "tcp_z[m]", "tcp_roll[rad]", "tcp_pitch[rad]", "tcp_yaw[rad]"})
    signal_names_.emplace_back(c);
}

const char* portName(CommandPort port) {
  switch (port) {
    case CommandPort::Setpoint: return "setpoint";
    case CommandPort::MotorVelocity: return "motor_velocity";
    case CommandPort::Current: return "current";
    case CommandPort::Voltage: return "voltage";
    case CommandPort::MotorTorque: return "motor_torque";
  }
  return "?";
}

CommandPort parsePort(const std::string& text) {
  for (CommandPort p : {CommandPort::Setpoint, CommandPort::MotorVelocity, CommandPort::Current, CommandPort::Voltage,
                        CommandPort::MotorTorque})
    if (text == portName(p)) return p;
  throw InputError("unknown command port '" + text +
                   "'; the ports are: setpoint, motor_velocity, current, voltage, motor_torque");
}

namespace {
control::ControlEntry entryOf(CommandPort port) {
  switch (port) {
    case CommandPort::MotorVelocity: return control::ControlEntry::MotorVelocity;
    case CommandPort::Current: return control::ControlEntry::Current;
    default: return control::ControlEntry::Position;
  }
}
bool controllerDriven(CommandPort port) {
  return port == CommandPort::Setpoint || port == CommandPort::MotorVelocity || port == CommandPort::Current;
}
}  // namespace

void RobotSystem::checkJoint(int joint, const char* what) const {
  if (joint < 0 || joint >= model_.nq)
    throw InputError(name() + ": " + what + ": joint index " + std::to_string(joint) + " out of range 0.." +
                     std::to_string(model_.nq - 1));
}

void RobotSystem::setCommandPort(int joint, CommandPort port) {
  checkJoint(joint, "setCommandPort");
  const size_t k = static_cast<size_t>(joint);
  const DriveSpec& d = drives_[k];
  const std::string where = name() + ": joint '" + d.joint + "': the " + portName(port) + " port ";
  const bool electrics = layout_[k].current >= 0;
  switch (port) {
    case CommandPort::Setpoint: break;
    case CommandPort::MotorVelocity:
      if (!controllers_[k].accepts(control::ControlEntry::MotorVelocity))
        throw InputError(where + "needs a controller with a velocity loop (the drive has controller type none)");
      break;
    case CommandPort::Current:
      if (!electrics || !controllers_[k].accepts(control::ControlEntry::Current))
        throw InputError(where + "needs motor electrics and a current loop (controller cascade_002); this drive has " +
                         (electrics ? "no current loop" : "electrics: false"));
      break;
    case CommandPort::Voltage:
      if (!electrics) throw InputError(where + "needs motor electrics (the drive has electrics: false)");
      break;
    case CommandPort::MotorTorque: break;
  }
  if (port_[k] != port) {
    port_[k] = port;
    cmd_[joint] = 0.0;  // a new port starts from a zero command unless set
    ++revision_;
  }
}

CommandPort RobotSystem::commandPort(int joint) const {
  checkJoint(joint, "commandPort");
  return port_[static_cast<size_t>(joint)];
}

void RobotSystem::setCommand(int joint, double value) {
  checkJoint(joint, "setCommand");
  const size_t k = static_cast<size_t>(joint);
  const CommandPort port = port_[k];
  // The message is built only on error: a controller calls this at every step.
  auto fail = [&](const std::string& why) {
    throw InputError(name() + ": joint '" + drives_[k].joint + "': " + portName(port) + " command: " + why);
  };
  if (port == CommandPort::Setpoint)
    fail("the joint is under the setpoint port; use setSetpoint or choose another port");
  if (!std::isfinite(value)) fail("expected a finite number, got " + formatNumber(value));
  if (cmd_[joint] != value) {
    cmd_[joint] = value;
    ++revision_;
  }
}

void RobotSystem::setCommands(const Eigen::VectorXd& values) {
  if (values.size() != model_.nq)
    throw InputError(name() + ": setCommands: expected " + std::to_string(model_.nq) + " values, got " +
                     std::to_string(values.size()));
  for (int k = 0; k < model_.nq; ++k)
    if (port_[static_cast<size_t>(k)] != CommandPort::Setpoint && !std::isfinite(values[k]))
      throw InputError(name() + ": setCommands: joint '" + drives_[static_cast<size_t>(k)].joint +
                       "': expected a finite number, got " + formatNumber(values[k]));
  for (int k = 0; k < model_.nq; ++k)
    if (port_[static_cast<size_t>(k)] != CommandPort::Setpoint) setCommand(k, values[k]);
}

double RobotSystem::command(int joint) const {
  checkJoint(joint, "command");
  return cmd_[joint];
}

void RobotSystem::setSetpoint(int joint, double q, double qd, double qdd) {
  checkJoint(joint, "setSetpoint");
  if (!std::isfinite(q) || !std::isfinite(qd) || !std::isfinite(qdd))
    throw InputError(name() + ": joint '" + drives_[static_cast<size_t>(joint)].joint +
                     "': setpoint: expected finite q, qd, qdd, got " + formatNumber(q) + ", " + formatNumber(qd) +
                     ", " + formatNumber(qdd));
  char& held = ref_held_[static_cast<size_t>(joint)];
  if (!held || ref_q_[joint] != q || ref_qd_[joint] != qd || ref_qdd_[joint] != qdd) {
    held = 1;
    ref_q_[joint] = q;
    ref_qd_[joint] = qd;
    ref_qdd_[joint] = qdd;
    ++revision_;
  }
}

void RobotSystem::holdSetpoints(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  const int n = model_.nq;
  auto check = [&](const Eigen::VectorXd& v, const char* what, bool optional) {
    if ((optional && v.size() == 0)) return;
    if (v.size() != n)
      throw InputError(name() + ": holdSetpoints: " + what + ": expected " + std::to_string(n) + " values, got " +
                       std::to_string(v.size()));
    if (!v.allFinite()) throw InputError(name() + ": holdSetpoints: " + what + ": expected finite values");
  };
  check(q, "q", false);
  check(qd, "qd", true);
  check(qdd, "qdd", true);
  for (int k = 0; k < n; ++k) setSetpoint(k, q[k], qd.size() ? qd[k] : 0.0, qdd.size() ? qdd[k] : 0.0);
}

void RobotSystem::releaseSetpoints() {
  for (auto& h : ref_held_)
    if (h) {
      h = 0;
      ++revision_;
    }
}

void RobotSystem::setExternalWrench(const std::string& frame, const Eigen::Matrix<double, 6, 1>& wrench) {
  const int f = model_.frameIndex(frame);
  if (!wrench.allFinite())
    throw InputError(name() + ": external wrench on frame '" + frame + "': expected finite values");
  if (model_.frames[static_cast<size_t>(f)].joint < 0)
    throw InputError(name() + ": external wrench on frame '" + frame +
                     "': the frame is fixed to the base, a wrench there does not act on the robot");
  auto it = std::find_if(user_wrenches_.begin(), user_wrenches_.end(), [f](const auto& w) { return w.first == f; });
  if (wrench.isZero(0.0)) {
    if (it != user_wrenches_.end()) {
      user_wrenches_.erase(it);
      ++revision_;
    }
    return;
  }
  if (it == user_wrenches_.end()) {
    user_wrenches_.emplace_back(f, wrench);
    ++revision_;
  } else if (it->second != wrench) {
    it->second = wrench;
    ++revision_;
  }
}

void RobotSystem::clearExternalWrenches() {
  if (!user_wrenches_.empty()) {
    user_wrenches_.clear();
    ++revision_;
  }
}

control::ControllerInputs RobotSystem::controllerInputs(int k) const {
  const auto& L = layout_[static_cast<size_t>(k)];
  return {sig_.q_set[k], sig_.qd_set[k],  sig_.q_fb[k], sig_.qm[k],
          sig_.qdm[k],   sig_.current[k], L.ratio,      drives_[static_cast<size_t>(k)].motor.V_supply};
}

void RobotSystem::applyInputs(double t, Eigen::Ref<Eigen::VectorXd> y) {
  for (int k = 0; k < model_.nq; ++k) {
    const size_t kk = static_cast<size_t>(k);
    if (port_[kk] != applied_port_[kk]) bumpless(k, applied_port_[kk], t, y);
  }
  applied_port_ = port_;
  applied_cmd_ = cmd_;
}

void RobotSystem::bumpless(int k, CommandPort from, double t, Eigen::Ref<Eigen::VectorXd> y) {
  const size_t kk = static_cast<size_t>(k);
  const DriveSpec& d = drives_[kk];
  const DriveLayout& L = layout_[kk];
  const CommandPort to = port_[kk];
  if (L.controller < 0 || !controllerDriven(to)) return;  // no integrators, or the controller is not in use
  setpointStage(t);
  measurementStage(t, y);
  double* x = sampled() ? ctrl_x_.data() + L.controller : y.data() + L.controller;
  const bool cascade = d.controller.type == control::ControllerType::Cascade002;
  // The actuator value applied just before the switch: the output of the controller under its old entry (held
  // output under sampled control), the voltage or torque command, or for a cascade leaving the torque port the
  // voltage that holds the present current (V = R i + k_e q̇_m).
  double u_prev = 0.0, i_prev = sig_.current[k];
  if (controllerDriven(from)) {
    if (sampled()) {
      u_prev = held_u_[k];
      i_prev = held_i_ref_[k];
    } else {
      control::ControllerInputs in = controllerInputs(k);
      in.entry = entryOf(from);
      in.command = applied_cmd_[k];
      double xdot[4];
      const control::ControllerOutputs o = controllers_[kk].evaluate(in, x, xdot);
      u_prev = o.u;
      i_prev = o.i_ref;
    }
  } else if (from == CommandPort::Voltage) {
    u_prev = motors_[kk].supplyVoltage(applied_cmd_[k]);
  } else {  // MotorTorque
    u_prev = cascade ? d.motor.R * sig_.current[k] + d.motor.ke * sig_.qdm[k] : applied_cmd_[k];
    if (cascade) i_prev = sig_.current[k];
  }
  control::ControllerInputs in = controllerInputs(k);
  in.entry = entryOf(to);
  in.command = cmd_[k];
  controllers_[kk].matchOutput(in, u_prev, i_prev, x);
  if (sampled()) {  // the held output continues until the next sample
    held_u_[k] = u_prev;
    held_i_ref_[k] = to == CommandPort::Current ? cmd_[k] : i_prev;
  }
}

void RobotSystem::setJointLimits(const JointLimitSettings& settings) {
  signal_names_.resize(signal_names_.size() - stops_.joints().size());  // the signals of earlier stops
  stops_ = EndStops(model_, settings);
  sig_.tau_stop.setZero();
  for (int i : stops_.joints())
    signal_names_.push_back("end_stop_torque_" + model_.joint_names[static_cast<size_t>(i)] + "[N·m]");
}

void RobotSystem::roots(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> g) const {
  stops_.roots(y.head(model_.nq), g.data());
}

void RobotSystem::setSetpoints(SetpointFunction f) {
  setpoints_ = std::move(f);
  setpoint_breaks_.clear();
}

void RobotSystem::setTrajectory(std::shared_ptr<const control::JointTrajectory> trajectory) {
  if (!trajectory) throw InputError(name() + ": no trajectory given");
  if (trajectory->dof() != model_.nq)
    throw InputError(name() + ": the trajectory has " + std::to_string(trajectory->dof()) + " joints, the robot " +
                     std::to_string(model_.nq));
  setpoint_breaks_ = trajectory->breakpoints();
  setpoints_ = [trajectory](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                            Eigen::Ref<Eigen::VectorXd> qdd) { trajectory->evaluate(t, q, qd, qdd); };
}

void RobotSystem::setInitialPositions(const Eigen::VectorXd& q0) {
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
  for (const Fault& f : faults_) {
    const std::vector<double> e = faultEvents(f, t_end);
    events.insert(events.end(), e.begin(), e.end());
  }
  return events;
}

void RobotSystem::setFaults(std::vector<Fault> faults) {
  if (nominal_drives_.empty()) nominal_drives_ = drives_;
  std::vector<int> drive;
  for (const Fault& f : faults) {
    const int k = model_.jointIndex(f.joint);  // InputError for an unknown joint
    DriveSpec probe = nominal_drives_[static_cast<size_t>(k)];
    applyFault(probe, f);  // applies to this drive? (InputError naming the fault and the component)
    drive.push_back(k);
  }
  faults_ = std::move(faults);
  fault_drive_ = std::move(drive);
  fault_applied_.assign(faults_.size(), 0.0);
  stuck_episode_.assign(faults_.size(), -1);
  stuck_value_.assign(faults_.size(), 0.0);
  updateFaults(0.0, Eigen::VectorXd::Zero(n_states_), true);
}

void RobotSystem::updateFaults(double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool restart) {
  if (faults_.empty()) return;
  std::vector<char> dirty(drives_.size(), restart ? 1 : 0);
  for (size_t i = 0; i < faults_.size(); ++i) {
    const Fault& f = faults_[i];
    const int k = fault_drive_[i];
    if (f.intermittent()) {
      long episode = -1;
      if (restart) stuck_episode_[i] = -1;
      if (f.type == FaultType::SensorStuck && faultEpisode(f, t, &episode) && episode != stuck_episode_[i]) {
        stuck_episode_[i] = episode;  // the reading at the episode's start, held through it
        stuck_value_[i] = y[k] + drives_[static_cast<size_t>(k)].sensors.joint_bias;
      }
      continue;
    }
    const double v = t >= f.onset ? scheduledFaultValue(f, t) : std::numeric_limits<double>::quiet_NaN();
    const double before = fault_applied_[i];
    fault_applied_[i] = f.type == FaultType::BearingRipple ? (std::isnan(v) ? 0.0 : v) : v;
    if (f.parameterFault() && !(v == before || (std::isnan(v) && std::isnan(before))))
      dirty[static_cast<size_t>(k)] = 1;
  }
  for (size_t k = 0; k < drives_.size(); ++k) {
    if (!dirty[k]) continue;
    DriveSpec d = nominal_drives_[k];
    for (size_t i = 0; i < faults_.size(); ++i)
      if (static_cast<size_t>(fault_drive_[i]) == k && faults_[i].parameterFault() && !std::isnan(fault_applied_[i]))
        applyFault(d, faults_[i], fault_applied_[i]);
    drives_[k] = std::move(d);
    motors_[k] = drive::DcMotor(drives_[k].motor);
  }
}

double RobotSystem::faultySensor(int k, double t, double q_meas) const {
  for (size_t i = 0; i < faults_.size(); ++i) {
    if (fault_drive_[i] != k || !faults_[i].intermittent() || !faultEpisode(faults_[i], t)) continue;
    switch (faults_[i].type) {
      case FaultType::SensorDropout: q_meas = 0.0; break;
      case FaultType::SensorStuck: q_meas = stuck_value_[i]; break;
      case FaultType::SensorSpike: q_meas += faults_[i].value; break;
      default: break;
    }
  }
  return q_meas;
}

void RobotSystem::updateModes(double t, const Eigen::Ref<const Eigen::VectorXd>& y, const std::vector<int>&) {
  updateFaults(t, y, false);
}

void RobotSystem::start(double t0, const Eigen::Ref<const Eigen::VectorXd>& y) {
  updateFaults(t0, y, true);
  applied_port_ = port_;  // the state starts consistent with the ports as they are
  applied_cmd_ = cmd_;
  if (sampled()) {
    first_sample_ = true;  // a (re)start: the encoder speed and the outer loops begin afresh
    inner_count_ = 0;
    controlStep(t0, y);
  }
}

void RobotSystem::setSampledControl(double rate, unsigned seed, double current_rate) {
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
  ctrl_x_.assign(static_cast<size_t>(n_states_ - first), 0.0);
  for (auto& L : layout_)
    if (L.controller >= 0) L.controller -= first;  // now an index into ctrl_x_
  n_states_ = first;
  held_u_.setZero(model_.nq);
  held_i_ref_.setZero(model_.nq);
  held_q_fb_.setZero(model_.nq);
  prev_qm_meas_.setZero(model_.nq);
  tmp_.setZero(n_states_);
  rng_ = std::make_shared<Rng>();
  rng_->engine.seed(seed);
}

Eigen::VectorXd RobotSystem::initialState(const Eigen::VectorXd& q0, double t0) const {
  const int n = model_.nq;
  if (q0.size() != n) throw InputError("initial joint positions: expected " + std::to_string(n) + " values");
  // With sampled control the controller states live outside y: build the full vector, then split.
  const int n_full = sampled() ? n_states_ + static_cast<int>(ctrl_x_.size()) : n_states_;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_full);
  y.head(n) = q0;
  if (setpoints_) {
    setpoints_(t0, sig_.q_set, sig_.qd_set, sig_.qdd_set);
  } else {
    sig_.q_set = q0;
    sig_.qd_set.setZero();
    sig_.qdd_set.setZero();
  }
  // Gravity preload: each drive starts holding its share of the static joint torques.
  const Eigen::VectorXd g = multibody::gravityTorques(model_, data_, q0);
  const Eigen::VectorXd tau_out_needed = coupled_ ? Eigen::VectorXd(G_.transpose() * g) : g;
  const Eigen::VectorXd phi = Ginv_ * q0;
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
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
      control::ControllerInputs in{sig_.q_set[k], sig_.qd_set[k], q0[k], q_in, 0.0, i, L.ratio, d.motor.V_supply};
      controllers_[static_cast<size_t>(k)].initialState(in, y.data() + c);
      if (holds && d.controller.type == control::ControllerType::Cascade002) {
        // Integrators holding the static current and voltage: i_ref = I_vel ∫e_vel, V = I_cur ∫e_cur = R i.
        if (d.controller.I_vel > 0) y[c] = i / d.controller.I_vel;
        if (d.controller.I_cur > 0) y[c + 1] = d.motor.R * i / d.controller.I_cur;
      } else if (holds && d.controller.type == control::ControllerType::MotorPPI000 && d.controller.ks > 0) {
        y[c] += tau_M / d.controller.ks;
      }
    }
  }
  if (!sampled()) return y;
  const_cast<RobotSystem*>(this)->ctrl_x_.assign(y.data() + n_states_, y.data() + n_full);
  const_cast<RobotSystem*>(this)->first_sample_ = true;
  const_cast<RobotSystem*>(this)->inner_count_ = 0;
  return y.head(n_states_);
}

RobotSystem::MotionMeasurement RobotSystem::measureMotion(int k, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                                                          double phi, double phid, double Ts) {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = drives_[static_cast<size_t>(k)].sensors;
  const double qm = L.rigid ? L.ratio * phi : y[L.motor];
  const double qdm = L.rigid ? L.ratio * phid : y[L.motor + 1];
  // Noise first, then the sensor's quantiser; encoder speed by differencing over Ts.
  MotionMeasurement m;
  m.q = faultySensor(k, t, quantise(y[k] + S.joint_bias + rng_->gauss(S.joint_noise), S.joint_quantum));
  m.qm = quantise(qm, S.motor_quantum);
  m.qdm = qdm;
  if (S.motor_quantum > 0.0) m.qdm = first_sample_ ? 0.0 : (m.qm - prev_qm_meas_[k]) / Ts;
  m.qdm += rng_->gauss(S.motor_velocity_noise);
  prev_qm_meas_[k] = m.qm;
  held_q_fb_[k] = m.q;
  return m;
}

double RobotSystem::measureCurrent(int k, const Eigen::Ref<const Eigen::VectorXd>& y) {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = drives_[static_cast<size_t>(k)].sensors;
  return quantise((L.current >= 0 ? y[L.current] : 0.0) + rng_->gauss(S.current_noise), S.current_quantum);
}

void RobotSystem::controlStep(double t, const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (!sampled()) throw InputError("controlStep: sampled control is not enabled");
  if (current_rate_ > 0.0) {
    multiRateStep(t, y);
    return;
  }
  const int n = model_.nq;
  const double Ts = 1.0 / sample_rate_;
  setpointStage(t);
  const Eigen::VectorXd phi = coupled_ ? Eigen::VectorXd(Ginv_ * y.head(n)) : Eigen::VectorXd(y.head(n));
  const Eigen::VectorXd phid = coupled_ ? Eigen::VectorXd(Ginv_ * y.segment(n, n)) : Eigen::VectorXd(y.segment(n, n));
  std::vector<double> xdot(4, 0.0);
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const MotionMeasurement m = measureMotion(k, t, y, phi[k], phid[k], Ts);
    const double i_meas = measureCurrent(k, y);
    const CommandPort port = port_[static_cast<size_t>(k)];
    if (!controllerDriven(port)) continue;  // voltage or torque command: the controller holds its state
    control::ControllerInputs in{sig_.q_set[k], sig_.qd_set[k], m.q, m.qm, m.qdm, i_meas, L.ratio, d.motor.V_supply};
    in.entry = entryOf(port);
    in.command = cmd_[k];
    double* x = L.controller >= 0 ? ctrl_x_.data() + L.controller : nullptr;
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot.data());
    for (int j = 0; j < L.n_controller; ++j) x[j] += Ts * xdot[static_cast<size_t>(j)];  // forward Euler
    held_u_[k] = out.u;
    held_i_ref_[k] = out.i_ref;
  }
  first_sample_ = false;
}

void RobotSystem::multiRateStep(double t, const Eigen::Ref<const Eigen::VectorXd>& y) {
  // Every call is a current-loop sample; every inner_per_outer_-th also an outer (position, velocity) sample.
  const int n = model_.nq;
  const double Ts_in = 1.0 / current_rate_, Ts_out = 1.0 / sample_rate_;
  const bool outer = inner_count_ % inner_per_outer_ == 0;
  ++inner_count_;
  setpointStage(t);
  double xdot[4] = {0.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const CommandPort port = port_[static_cast<size_t>(k)];
    const bool cascade = d.controller.type == control::ControllerType::Cascade002;
    double* x = L.controller >= 0 ? ctrl_x_.data() + L.controller : nullptr;
    const double i_meas = measureCurrent(k, y);
    if (outer) {  // measure the joint and the motor, advance the outer loops over Ts_out
      const double phi = coupled_ ? Ginv_.row(k).dot(y.head(n)) : y[k];
      const double phid = coupled_ ? Ginv_.row(k).dot(y.segment(n, n)) : y[n + k];
      const MotionMeasurement m = measureMotion(k, t, y, phi, phid, Ts_out);
      if (controllerDriven(port)) {
        control::ControllerInputs in{sig_.q_set[k], sig_.qd_set[k], m.q,     m.qm,
                                     m.qdm,         i_meas,         L.ratio, d.motor.V_supply};
        in.entry = entryOf(port);
        in.command = cmd_[k];
        const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
        if (cascade) {
          x[0] += Ts_out * xdot[0];  // the velocity integrator; the current loop below
          held_i_ref_[k] = out.i_ref;
        } else {
          for (int j = 0; j < L.n_controller; ++j) x[j] += Ts_out * xdot[j];
          held_u_[k] = out.u;
          held_i_ref_[k] = out.i_ref;
        }
      }
    }
    if (!cascade || !controllerDriven(port)) continue;
    // The current loop on the held reference (or the Current port's command), over Ts_in.
    control::ControllerInputs in{sig_.q_set[k], sig_.qd_set[k], held_q_fb_[k], 0.0,
                                 0.0,           i_meas,         L.ratio,       d.motor.V_supply};
    in.entry = control::ControlEntry::Current;
    in.command = port == CommandPort::Current ? cmd_[k] : held_i_ref_[k];
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
    x[1] += Ts_in * xdot[1];
    held_u_[k] = out.u;
  }
  first_sample_ = false;
}

void RobotSystem::setpointStage(double t) const {
  if (setpoints_) setpoints_(t, sig_.q_set, sig_.qd_set, sig_.qdd_set);
  for (int k = 0; k < model_.nq; ++k)
    if (ref_held_[static_cast<size_t>(k)]) {
      sig_.q_set[k] = ref_q_[k];
      sig_.qd_set[k] = ref_qd_[k];
      sig_.qdd_set[k] = ref_qdd_[k];
    }
}

void RobotSystem::measurementStage(double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  // Gear output angles and speeds: φ = G⁻¹ q.
  if (coupled_) {
    phi_.noalias() = Ginv_ * q;
    phid_.noalias() = Ginv_ * qd;
  } else {
    phi_ = q;
    phid_ = qd;
  }
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    sig_.qm[k] = L.rigid ? L.ratio * phi_[k] : y[L.motor];
    sig_.qdm[k] = L.rigid ? L.ratio * phid_[k] : y[L.motor + 1];
    sig_.current[k] = L.current >= 0 ? y[L.current] : 0.0;
    sig_.q_fb[k] =
        sampled() ? held_q_fb_[k] : faultySensor(k, t, q[k] + drives_[static_cast<size_t>(k)].sensors.joint_bias);
  }
}

void RobotSystem::controllerStage(const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    control::ControllerOutputs out;
    const CommandPort port = port_[static_cast<size_t>(k)];
    if (!controllerDriven(port)) {  // the command bypasses the controller, whose integrators hold
      out.voltage = port == CommandPort::Voltage;
      out.u = cmd_[k];
      if (!sampled())
        for (int j = 0; j < L.n_controller; ++j) ydot[L.controller + j] = 0.0;
    } else if (sampled()) {  // zero-order hold of the last sample's outputs
      out.voltage = d.controller.type == control::ControllerType::Cascade002;
      out.u = held_u_[k];
      out.i_ref = held_i_ref_[k];
    } else {
      control::ControllerInputs in{sig_.q_set[k], sig_.qd_set[k],  sig_.q_fb[k], sig_.qm[k],
                                   sig_.qdm[k],   sig_.current[k], L.ratio,      d.motor.V_supply};
      in.entry = entryOf(port);
      in.command = cmd_[k];
      out = controllers_[static_cast<size_t>(k)].evaluate(in, L.controller >= 0 ? y.data() + L.controller : nullptr,
                                                          L.controller >= 0 ? ydot + L.controller : nullptr);
    }
    sig_.i_ref[k] = out.i_ref;
    sig_.u[k] = out.u;
    out_is_voltage_[static_cast<size_t>(k)] = out.voltage;
  }
}

void RobotSystem::powerElectronicsStage() const {
  // Averaged PWM: the commanded voltage, saturated at the supply [Raviola2023, eq. 1].
  for (int k = 0; k < model_.nq; ++k) {
    const bool electrics = layout_[static_cast<size_t>(k)].current >= 0;
    const double V_cmd = out_is_voltage_[static_cast<size_t>(k)] ? sig_.u[k] : 0.0;
    sig_.voltage[k] = electrics ? motors_[static_cast<size_t>(k)].supplyVoltage(V_cmd) : 0.0;
  }
}

void RobotSystem::motorElectricsStage(double* ydot) const {
  // L di/dt = V − R i − k_e q̇_m, τ_M = k_t i; a motor without electrics gives the commanded torque.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const drive::DcMotor& motor = motors_[static_cast<size_t>(k)];
    if (L.current >= 0 && port_[static_cast<size_t>(k)] == CommandPort::MotorTorque) {
      // Electrics bypassed: the torque is the command; the current relaxes to τ/k_t with L/R.
      const drive::DcMotorParams& m = drives_[static_cast<size_t>(k)].motor;
      sig_.tau_motor[k] = sig_.u[k];
      ydot[L.current] = (sig_.u[k] / m.kt - sig_.current[k]) * m.R / m.L;
    } else if (L.current >= 0) {
      const double V_cmd = out_is_voltage_[static_cast<size_t>(k)] ? sig_.u[k] : 0.0;
      ydot[L.current] = motor.currentDerivative(sig_.current[k], V_cmd, sig_.qdm[k]);
      sig_.tau_motor[k] = motor.torque(sig_.current[k]);
    } else {
      sig_.tau_motor[k] = out_is_voltage_[static_cast<size_t>(k)] ? 0.0 : sig_.u[k];
    }
  }
}

void RobotSystem::transmissionStage(const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (L.rigid) {
      sig_.tau_gear[k] = L.ratio * sig_.tau_motor[k];  // the rotor's inertial reaction follows the accelerations
      continue;
    }
    const drive::PortTorques pt =
        d.transmission->evaluate({sig_.qm[k], sig_.qdm[k], phi_[k], phid_[k]},
                                 L.gear >= 0 ? y.data() + L.gear : nullptr, L.gear >= 0 ? ydot + L.gear : nullptr);
    sig_.tau_gear[k] = pt.tau_out;
    ydot[L.motor] = sig_.qdm[k];
    ydot[L.motor + 1] = (sig_.tau_motor[k] - pt.tau_in) / d.motor.J_M;  // rotor: J_M q̈_m = τ_M − τ_in
  }
}

void RobotSystem::frictionStage(const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  // On the gear output shaft, driven by the gear output torque.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = drives_[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    sig_.tau_friction[k] = d.friction ? d.friction->evaluate({phid_[k], sig_.tau_gear[k]},
                                                             L.friction >= 0 ? y.data() + L.friction : nullptr,
                                                             L.friction >= 0 ? ydot + L.friction : nullptr)
                                      : 0.0;
  }
  // A bearing defect of the output shaft: τ_b = A sin(order · φ_out), with the amplitude of its schedule.
  for (size_t i = 0; i < faults_.size(); ++i)
    if (faults_[i].type == FaultType::BearingRipple) {
      const int k = fault_drive_[i];
      sig_.tau_friction[k] += fault_applied_[i] * std::sin(faults_[i].order * phi_[k]);
    }
}

void RobotSystem::jointTorqueStage() const {
  // τ_out = τ_gear − τ_f on the gear outputs; τ_joint = G⁻ᵀ τ_out.
  tau_out_ = sig_.tau_gear - sig_.tau_friction;
  if (coupled_)
    tau_.noalias() = Ginv_.transpose() * tau_out_;
  else
    tau_ = tau_out_;
  sig_.tau_joint = tau_;
}

void RobotSystem::multibodyStage(double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  if (stops_.active()) {  // end stops act on the joints beside the drives
    stops_.torques(q, qd, sig_.tau_stop);
    tau_ += sig_.tau_stop;
  }
  const multibody::Matrix6Xd* fext = nullptr;
  if (wrenches_ || !user_wrenches_.empty()) {
    multibody::forwardKinematics(model_, data_, q);
    fext_.setZero();
    if (wrenches_) wrenches_(t, model_, data_, q, qd, fext_);
    for (const auto& [f, w] : user_wrenches_) {
      // World wrench at the frame origin → body frame of the carrying body, moment about the body origin.
      const multibody::Frame& fr = model_.frames[static_cast<size_t>(f)];
      const multibody::Placement& B = data_.oMi[static_cast<size_t>(fr.joint)];
      const Eigen::Vector3d r = data_.oMf[static_cast<size_t>(f)].p - B.p;
      fext_.col(fr.joint).head<3>() += B.R.transpose() * (w.tail<3>() + r.cross(w.head<3>()));
      fext_.col(fr.joint).tail<3>() += B.R.transpose() * w.head<3>();
    }
    fext = &fext_;
  }
  if (crba_path_) {
    // (M + G⁻ᵀ diag(N² J_M) G⁻¹) q̈ = τ − h(q, q̇) [− Jᵀ f_ext through RNEA]
    if (fext)
      data_.nle = multibody::rnea(model_, data_, q, qd, zero_, fext);
    else
      multibody::nonLinearEffects(model_, data_, q, qd);
    M_ = multibody::crba(model_, data_, q);
    M_ += reflected_;
    llt_.compute(M_);
    sig_.qdd = tau_ - data_.nle;
    llt_.solveInPlace(sig_.qdd);
  } else {
    sig_.qdd = multibody::aba(model_, data_, q, qd, tau_, fext);
  }
}

void RobotSystem::rotorReactionStage() const {
  // Rigid drives: the gear output torque includes the rotor's inertial reaction −N² J_M φ̈.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (!L.rigid) continue;
    const double phidd = coupled_ ? Ginv_.row(k).dot(sig_.qdd) : sig_.qdd[k];
    sig_.tau_gear[k] -= L.ratio * L.ratio * drives_[static_cast<size_t>(k)].motor.J_M * phidd;
  }
}

void RobotSystem::evaluate(double t, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  setpointStage(t);
  measurementStage(t, y);
  controllerStage(y, ydot);
  powerElectronicsStage();
  motorElectricsStage(ydot);
  transmissionStage(y, ydot);
  frictionStage(y, ydot);
  jointTorqueStage();
  multibodyStage(t, y);
  rotorReactionStage();
  const int n = model_.nq;
  Eigen::Map<Eigen::VectorXd> yd(ydot, n_states_);
  yd.head(n) = y.segment(n, n);
  yd.segment(n, n) = sig_.qdd;
}

void RobotSystem::derivatives(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> ydot) const {
  evaluate(t, y, ydot.data());
}

sim::JacobianStructure RobotSystem::jacobianStructure() const { return jacobianStructure(nullptr); }

sim::JacobianStructure RobotSystem::jacobianStructure(std::vector<int>* drive_of_block) const {
  sim::JacobianStructure s;
  const int n = model_.nq;
  for (int i = 0; i < 2 * n; ++i) s.hub.push_back(i);
  if (drive_of_block) drive_of_block->clear();
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    std::vector<int> b;
    auto add = [&b](int first, int count) {
      if (first >= 0)
        for (int j = 0; j < count; ++j) b.push_back(first + j);
    };
    if (!L.rigid) add(L.motor, 2);
    add(L.current, 1);
    add(L.gear, L.n_gear);
    add(L.friction, L.n_friction);
    if (!sampled()) add(L.controller, L.n_controller);  // sampled: the controller states are not ODE states
    if (b.empty()) continue;
    s.blocks.push_back(std::move(b));
    if (drive_of_block) drive_of_block->push_back(k);
  }
  return s;
}

void RobotSystem::jacobian(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                           Eigen::Ref<Eigen::MatrixXd> J) const {
  const int n = model_.nq;
  if (jac_y_.size() != n_states_) {  // first call for this state layout
    jac_structure_ = jacobianStructure(&jac_block_drive_);
    jac_y_.resize(n_states_);
    jac_f_.resize(n_states_);
    jac_tau0_.resize(n);
    jac_qdd0_.resize(n);
    jac_tau_.resize(n);
    jac_P_.resize(n, n);
  }
  Eigen::VectorXd& yp = jac_y_;
  Eigen::VectorXd& fp = jac_f_;
  yp = y;
  // The base point: the drives' output torques and the total joint torque (drives, end stops) behind q̈.
  evaluate(t, y, fp.data());
  jac_tau0_ = tau_out_;
  jac_qdd0_ = sig_.qdd;
  const Eigen::VectorXd& tau_total = tau_;
  // ∂q̈/∂τ_out = M⁻¹ G⁻ᵀ, column by column; q̈ is affine in the joint torque, so a unit difference is exact to
  // rounding. (The external wrenches fext_ of the base evaluation stay in place.)
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  const bool with_fext = wrenches_ || !user_wrenches_.empty();
  for (int j = 0; j < n; ++j) {
    jac_tau_ = tau_total;
    if (coupled_)
      jac_tau_ += Ginv_.row(j).transpose();
    else
      jac_tau_[j] += 1.0;
    if (crba_path_) {
      jac_P_.col(j) = jac_tau_ - data_.nle;
      llt_.solveInPlace(jac_P_.col(j));
    } else {
      jac_P_.col(j) = multibody::aba(model_, data_, q, qd, jac_tau_, with_fext ? &fext_ : nullptr);
    }
    jac_P_.col(j) -= jac_qdd0_;
  }
  // Hub columns: whole difference quotients.
  for (int j = 0; j < 2 * n; ++j) {
    yp[j] = y[j] + inc[j];
    evaluate(t, yp, fp.data());
    J.col(j) = (fp - f) / inc[j];
    yp[j] = y[j];
  }
  // Drive columns: state c of every drive at once.
  size_t max_m = 0;
  for (const auto& b : jac_structure_.blocks) max_m = std::max(max_m, b.size());
  const auto& blocks = jac_structure_.blocks;
  for (size_t c = 0; c < max_m; ++c) {
    for (const auto& b : blocks)
      if (b.size() > c) yp[b[c]] = y[b[c]] + inc[b[c]];
    evaluate(t, yp, fp.data());
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
      const auto& b = blocks[bi];
      if (b.size() <= c) continue;
      const int s = b[c];
      for (int r : b) J(r, s) = (fp[r] - f[r]) / inc[s];
      const int k = jac_block_drive_[bi];
      J.col(s).segment(n, n) = jac_P_.col(k) * ((tau_out_[k] - jac_tau0_[k]) / inc[s]);
      yp[s] = y[s];
    }
  }
}

const RobotSignals& RobotSystem::driveSignals(double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  evaluate(t, y, tmp_.data());
  return sig_;
}

void RobotSystem::signals(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> out) const {
  const int n = model_.nq;
  const RobotSignals& s = driveSignals(t, y);
  const Eigen::VectorXd& id = multibody::rnea(id_model_, id_data_, s.q_set, s.qd_set, s.qdd_set);
  Eigen::Index c = 0;
  for (int k = 0; k < n; ++k) {
    const auto& d = drives_[static_cast<size_t>(k)];
    const double f_ss = d.friction ? d.friction->steadyState(s.qd_set[k]) : 0.0;
    out[c++] = s.q_set[k];
    out[c++] = y[k];
    out[c++] = s.q_fb[k];
    out[c++] = y[n + k];
    out[c++] = s.qdm[k];
    out[c++] = s.current[k];
    out[c++] = s.i_ref[k];
    out[c++] = s.voltage[k];
    out[c++] = s.tau_gear[k];
    out[c++] = s.tau_friction[k];
    out[c++] = id[k] + f_ss;
  }
  multibody::forwardKinematics(id_model_, id_data_, y.head(n));
  const multibody::Placement& X = id_data_.oMf[static_cast<size_t>(tip_)];
  // Roll-pitch-yaw (URDF convention R = Rz(yaw) Ry(pitch) Rx(roll)).
  const double pitch = std::asin(std::clamp(-X.R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(X.R(2, 1), X.R(2, 2));
  const double yaw = std::atan2(X.R(1, 0), X.R(0, 0));
  out.segment(c, 3) = X.p;
  c += 3;
  out[c++] = roll;
  out[c++] = pitch;
  out[c++] = yaw;
  for (int i : stops_.joints()) out[c++] = s.tau_stop[i];
}

double RobotSystem::mechanicalEnergy(const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  double E = multibody::kineticEnergy(model_, data_, q, qd) + multibody::potentialEnergy(model_, data_, q);
  if (crba_path_) E += 0.5 * qd.dot(reflected_ * qd);
  E += stops_.energy(q);
  const Eigen::VectorXd phi = Ginv_ * q, phid = Ginv_ * qd;
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (L.rigid) continue;
    const double qdm = y[L.motor + 1];
    E += 0.5 * drives_[static_cast<size_t>(k)].motor.J_M * qdm * qdm;
    E += drives_[static_cast<size_t>(k)].transmission->storedEnergy({y[L.motor], qdm, phi[k], phid[k]},
                                                                    L.gear >= 0 ? y.data() + L.gear : nullptr);
  }
  return E;
}

}  // namespace jointsim::systems
