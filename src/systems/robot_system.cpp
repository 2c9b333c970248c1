#include "jointsim/systems/robot_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <locale>
#include <random>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::systems {

namespace {
double quantise(double x, double quantum) { return quantum > 0.0 ? quantum * std::round(x / quantum) : x; }
}  // namespace

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
    : PlantStateOf(robot), drives(robot.drives_), data(robot.model_), id_data(robot.id_model_) {
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
  jac_y.setZero(robot.n_states_);
  jac_f.setZero(robot.n_states_);
  jac_tau0.setZero(n);
  jac_qdd0.setZero(n);
  jac_tau.setZero(n);
  jac_P.setZero(n, n);
  // The faults as they are at t = 0 (start() sets them for its start time and state).
  if (!robot.faults_.empty()) robot.updateFaults(*this, 0.0, Eigen::VectorXd::Zero(robot.n_states_), true);
}

namespace {
/// The noise generator's state as text (the standard library's portable textual form).
template <class T>
std::string streamed(const T& x) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << x;
  return out.str();
}
template <class T>
bool unstreamed(const std::string& text, T& x) {
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  in >> x;
  return !in.fail();
}
}  // namespace

void RobotSystem::State::save(ByteWriter& out) const {
  const int n = static_cast<int>(port.size());
  out.tag("robot inputs");
  for (int k = 0; k < n; ++k) {
    out.u64(static_cast<std::uint64_t>(port[static_cast<size_t>(k)]));
    out.u64(static_cast<std::uint64_t>(applied_port[static_cast<size_t>(k)]));
  }
  out.vector(cmd);
  out.vector(applied_cmd);
  out.flags(ref_held);
  out.vector(ref_q);
  out.vector(ref_qd);
  out.vector(ref_qdd);
  out.vector(q_start);
  out.u64(user_wrenches.size());
  for (const auto& [f, w] : user_wrenches) {
    out.i64(f);
    out.vector(w);
  }
  out.tag("sampled control");
  out.doubles(ctrl_x);
  out.vector(held_u);
  out.vector(held_i_ref);
  out.vector(held_q_fb);
  out.vector(prev_qm_meas);
  out.boolean(first_sample);
  out.i64(inner_count);
  out.text(streamed(engine));
  out.text(streamed(normal));
  out.tag("faults");
  out.doubles(fault_applied);
  out.u64(stuck_episode.size());
  for (long e : stuck_episode) out.i64(e);
  out.doubles(stuck_value);
}

void RobotSystem::State::load(ByteReader& in) {
  const auto& robot = static_cast<const RobotSystem&>(owner());
  const int n = robot.model_.nq;
  auto portOf = [&in](const char* field) {
    const std::uint64_t v = in.u64(field);
    if (v > static_cast<std::uint64_t>(CommandPort::MotorTorque)) in.fail(std::string("bad ") + field);
    return static_cast<CommandPort>(v);
  };
  // Everything the setters would refuse is refused here too: a state of bytes is no less checked than one of calls.
  auto finite = [&in](const Eigen::VectorXd& v, const char* what) {
    if (!v.allFinite()) in.fail(std::string(what) + ": a value that is not finite");
    return v;
  };
  in.tag("robot inputs");
  for (int k = 0; k < n; ++k) {
    for (CommandPort* p : {&port[static_cast<size_t>(k)], &applied_port[static_cast<size_t>(k)]}) {
      *p = portOf("command port");
      const std::string why = robot.portRefusal(k, *p);
      if (!why.empty()) in.fail(std::string("joint ") + std::to_string(k) + ": the " + portName(*p) + " port " + why);
    }
  }
  cmd = finite(in.vector("commands", n), "commands");
  applied_cmd = finite(in.vector("applied commands", n), "applied commands");
  ref_held = in.flags("held references", n);
  for (char h : ref_held)
    if (h != 0 && h != 1) in.fail("held references: expected 0 or 1");
  ref_q = finite(in.vector("held q", n), "held q");
  ref_qd = finite(in.vector("held qd", n), "held qd");
  ref_qdd = finite(in.vector("held qdd", n), "held qdd");
  q_start = finite(in.vector("start angles", n), "start angles");
  const std::uint64_t wrenches = in.u64("external wrenches");
  if (wrenches > robot.model_.frames.size()) in.fail("more external wrenches than frames");
  user_wrenches.clear();
  for (std::uint64_t i = 0; i < wrenches; ++i) {
    const std::int64_t f = in.i64("wrench frame");
    if (f < 0 || f >= static_cast<std::int64_t>(robot.model_.frames.size()) ||
        robot.model_.frames[static_cast<size_t>(f)].joint < 0)
      in.fail("wrench frame " + std::to_string(f) + ": not a frame on a moving body");
    for (const auto& w : user_wrenches)
      if (w.first == f) in.fail("two wrenches on frame " + std::to_string(f));
    const Eigen::VectorXd w = finite(in.vector("wrench", 6), "wrench");
    if (w.isZero(0.0)) in.fail("a zero wrench (setExternalWrench removes those)");
    user_wrenches.emplace_back(static_cast<int>(f), w);
  }
  in.tag("sampled control");
  ctrl_x = in.doubles("controller states", static_cast<long>(ctrl_x.size()));
  for (double x : ctrl_x)
    if (!std::isfinite(x)) in.fail("controller states: a value that is not finite");
  held_u = finite(in.vector("held outputs", n), "held outputs");
  held_i_ref = finite(in.vector("held current references", n), "held current references");
  held_q_fb = finite(in.vector("held joint feedback", n), "held joint feedback");
  prev_qm_meas = finite(in.vector("encoder memory", n), "encoder memory");
  first_sample = in.boolean("first sample");
  inner_count = in.i64("current-loop samples");
  if (inner_count < 0 || inner_count > (1L << 60)) in.fail("current-loop samples: out of range");
  std::mt19937_64 engine_read;
  std::normal_distribution<double> normal_read;
  if (!unstreamed(in.text("noise generator"), engine_read)) in.fail("bad noise generator state");
  if (!unstreamed(in.text("noise distribution"), normal_read) || normal_read.mean() != 0.0 ||
      normal_read.stddev() != 1.0)
    in.fail("bad noise distribution state (expected the standard normal distribution)");
  engine = engine_read;
  normal = normal_read;
  in.tag("faults");
  fault_applied = in.doubles("applied fault values", static_cast<long>(fault_applied.size()));
  for (size_t i = 0; i < fault_applied.size(); ++i)  // NaN: a parameter fault before its onset
    if (std::isinf(fault_applied[i]) || (std::isnan(fault_applied[i]) && !robot.faults_[i].parameterFault()))
      in.fail("applied fault values: a value that is not finite");
  if (in.u64("stuck episodes") != stuck_episode.size()) in.fail("another number of faults");
  for (long& e : stuck_episode) e = in.i64("stuck episode");
  stuck_value = in.doubles("stuck values", static_cast<long>(stuck_value.size()));
  for (double v : stuck_value)
    if (!std::isfinite(v)) in.fail("stuck values: a value that is not finite");
  robot.rebuildDrives(*this, {});
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

void RobotSystem::setCommandPort(sim::PlantState& state, int joint, CommandPort port) const {
  State& st = own<State>(state);
  checkJoint(joint, "setCommandPort");
  const size_t k = static_cast<size_t>(joint);
  const std::string why = portRefusal(joint, port);
  if (!why.empty())
    throw InputError(name() + ": joint '" + drives_[k].joint + "': the " + portName(port) + " port " + why);
  if (st.port[k] != port) {
    st.port[k] = port;
    st.cmd[joint] = 0.0;  // a new port starts from a zero command unless set
    st.inputsChanged();
  }
}

std::string RobotSystem::portRefusal(int joint, CommandPort port) const {
  const size_t k = static_cast<size_t>(joint);
  const bool electrics = layout_[k].current >= 0;
  switch (port) {
    case CommandPort::Setpoint: break;
    case CommandPort::MotorVelocity:
      if (!controllers_[k].accepts(control::ControlEntry::MotorVelocity))
        return "needs a controller with a velocity loop (the drive has controller type none)";
      break;
    case CommandPort::Current:
      if (!electrics || !controllers_[k].accepts(control::ControlEntry::Current))
        return std::string("needs motor electrics and a current loop (controller voltage_cascade); this drive has ") +
               (electrics ? "no current loop" : "electrics: false");
      break;
    case CommandPort::Voltage:
      if (!electrics) return "needs motor electrics (the drive has electrics: false)";
      break;
    case CommandPort::MotorTorque: break;
  }
  return {};
}

const RobotSystem::InputSlot& RobotSystem::inputSlot(int port) const {
  if (port < 0 || static_cast<size_t>(port) >= inputs_.size())
    throw InputError(name() + ": input " + std::to_string(port) + " out of range 0.." +
                     std::to_string(static_cast<long>(inputs_.size()) - 1));
  return inputs_[static_cast<size_t>(port)];
}

std::vector<sim::InputPort> RobotSystem::inputPorts() const {
  static const char* const ref_names[] = {"q", "qd", "qdd"};
  static const char* const ref_units[] = {"rad", "rad/s", "rad/s²"};
  static const char* const ref_what[] = {"joint position reference", "joint velocity reference",
                                         "joint acceleration reference (feed-forward of the logged inverse dynamics)"};
  std::vector<sim::InputPort> out;
  out.reserve(inputs_.size());
  for (const InputSlot& in : inputs_) {
    const std::string& joint = drives_[static_cast<size_t>(in.joint)].joint;
    sim::InputPort p;
    p.group = joint;
    if (in.kind < 3) {
      p.name = joint + "." + ref_names[in.kind];
      p.unit = ref_units[in.kind];
      p.description = std::string(ref_what[in.kind]) + " of " + joint + ", held (setpoint port)";
      p.mode = "setpoint";
    } else {
      const auto port = static_cast<CommandPort>(in.kind - 3);
      p.name = joint + "." + portName(port);
      p.mode = portName(port);
      switch (port) {
        case CommandPort::MotorVelocity:
          p.unit = "rad/s";
          p.description = "motor speed reference into the velocity loop of " + joint;
          break;
        case CommandPort::Current:
          p.unit = "A";
          p.description = "current reference into the current loop of " + joint;
          break;
        case CommandPort::Voltage:
          p.unit = "V";
          p.description = "motor voltage command of " + joint + " (saturates at the supply voltage)";
          break;
        case CommandPort::MotorTorque:
          p.unit = "N·m";
          p.description = "electromagnetic motor torque of " + joint;
          break;
        case CommandPort::Setpoint: break;
      }
    }
    out.push_back(std::move(p));
  }
  return out;
}

void RobotSystem::setInput(sim::PlantState& state, int port, double value) const {
  const InputSlot& in = inputSlot(port);
  State& st = own<State>(state);
  const size_t k = static_cast<size_t>(in.joint);
  if (!std::isfinite(value))
    throw InputError(name() + ": input " + inputPorts()[static_cast<size_t>(port)].name +
                     ": expected a finite number, got " + formatNumber(value));
  if (in.kind < 3) {
    if (st.port[k] != CommandPort::Setpoint) setCommandPort(state, in.joint, CommandPort::Setpoint);
    const bool held = st.ref_held[k] != 0;
    // A reference held from now on: the parts not set yet are the start angle and zero rates.
    double r[3] = {held ? st.ref_q[in.joint] : st.q_start[in.joint], held ? st.ref_qd[in.joint] : 0.0,
                   held ? st.ref_qdd[in.joint] : 0.0};
    r[in.kind] = value;
    setSetpoint(state, in.joint, r[0], r[1], r[2]);
    return;
  }
  const auto p = static_cast<CommandPort>(in.kind - 3);
  if (st.port[k] != p) setCommandPort(state, in.joint, p);
  setCommand(state, in.joint, value);
}

double RobotSystem::input(const sim::PlantState& state, int port) const {
  const InputSlot& in = inputSlot(port);
  const State& st = own<State>(state);
  const bool held = st.ref_held[static_cast<size_t>(in.joint)] != 0;
  if (in.kind == 0) return held ? st.ref_q[in.joint] : st.q_start[in.joint];
  if (in.kind == 1) return held ? st.ref_qd[in.joint] : 0.0;
  if (in.kind == 2) return held ? st.ref_qdd[in.joint] : 0.0;
  return st.port[static_cast<size_t>(in.joint)] == static_cast<CommandPort>(in.kind - 3) ? st.cmd[in.joint] : 0.0;
}

bool RobotSystem::inputActive(const sim::PlantState& state, int port) const {
  const InputSlot& in = inputSlot(port);
  const CommandPort now = own<State>(state).port[static_cast<size_t>(in.joint)];
  return in.kind < 3 ? now == CommandPort::Setpoint : now == static_cast<CommandPort>(in.kind - 3);
}

CommandPort RobotSystem::commandPort(const sim::PlantState& state, int joint) const {
  const State& st = own<State>(state);
  checkJoint(joint, "commandPort");
  return st.port[static_cast<size_t>(joint)];
}

void RobotSystem::setCommand(sim::PlantState& state, int joint, double value) const {
  State& st = own<State>(state);
  checkJoint(joint, "setCommand");
  const size_t k = static_cast<size_t>(joint);
  const CommandPort port = st.port[k];
  // The message is built only on error: a controller calls this at every step.
  auto fail = [&](const std::string& why) {
    throw InputError(name() + ": joint '" + st.drives[k].joint + "': " + portName(port) + " command: " + why);
  };
  if (port == CommandPort::Setpoint)
    fail("the joint is under the setpoint port; use setSetpoint or choose another port");
  if (!std::isfinite(value)) fail("expected a finite number, got " + formatNumber(value));
  if (st.cmd[joint] != value) {
    st.cmd[joint] = value;
    st.inputsChanged();
  }
}

void RobotSystem::setCommands(sim::PlantState& state, const Eigen::VectorXd& values) const {
  const State& st = own<State>(state);
  if (values.size() != model_.nq)
    throw InputError(name() + ": setCommands: expected " + std::to_string(model_.nq) + " values, got " +
                     std::to_string(values.size()));
  for (int k = 0; k < model_.nq; ++k)
    if (st.port[static_cast<size_t>(k)] != CommandPort::Setpoint && !std::isfinite(values[k]))
      throw InputError(name() + ": setCommands: joint '" + st.drives[static_cast<size_t>(k)].joint +
                       "': expected a finite number, got " + formatNumber(values[k]));
  for (int k = 0; k < model_.nq; ++k)
    if (st.port[static_cast<size_t>(k)] != CommandPort::Setpoint) setCommand(state, k, values[k]);
}

double RobotSystem::command(const sim::PlantState& state, int joint) const {
  const State& st = own<State>(state);
  checkJoint(joint, "command");
  return st.cmd[joint];
}

void RobotSystem::setSetpoint(sim::PlantState& state, int joint, double q, double qd, double qdd) const {
  State& st = own<State>(state);
  checkJoint(joint, "setSetpoint");
  if (!std::isfinite(q) || !std::isfinite(qd) || !std::isfinite(qdd))
    throw InputError(name() + ": joint '" + st.drives[static_cast<size_t>(joint)].joint +
                     "': setpoint: expected finite q, qd, qdd, got " + formatNumber(q) + ", " + formatNumber(qd) +
                     ", " + formatNumber(qdd));
  char& held = st.ref_held[static_cast<size_t>(joint)];
  if (!held || st.ref_q[joint] != q || st.ref_qd[joint] != qd || st.ref_qdd[joint] != qdd) {
    held = 1;
    st.ref_q[joint] = q;
    st.ref_qd[joint] = qd;
    st.ref_qdd[joint] = qdd;
    st.inputsChanged();
  }
}

void RobotSystem::holdSetpoints(sim::PlantState& state, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd) const {
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
  for (int k = 0; k < n; ++k) setSetpoint(state, k, q[k], qd.size() ? qd[k] : 0.0, qdd.size() ? qdd[k] : 0.0);
}

void RobotSystem::releaseSetpoints(sim::PlantState& state) const {
  State& st = own<State>(state);
  for (auto& h : st.ref_held)
    if (h) {
      h = 0;
      st.inputsChanged();
    }
}

void RobotSystem::setExternalWrench(sim::PlantState& state, const std::string& frame,
                                    const Eigen::Matrix<double, 6, 1>& wrench) const {
  State& st = own<State>(state);
  const int f = model_.frameIndex(frame);
  if (!wrench.allFinite())
    throw InputError(name() + ": external wrench on frame '" + frame + "': expected finite values");
  if (model_.frames[static_cast<size_t>(f)].joint < 0)
    throw InputError(name() + ": external wrench on frame '" + frame +
                     "': the frame is fixed to the base, a wrench there does not act on the robot");
  auto it = std::find_if(st.user_wrenches.begin(), st.user_wrenches.end(), [f](const auto& w) { return w.first == f; });
  if (wrench.isZero(0.0)) {
    if (it != st.user_wrenches.end()) {
      st.user_wrenches.erase(it);
      st.inputsChanged();
    }
    return;
  }
  if (it == st.user_wrenches.end()) {
    st.user_wrenches.emplace_back(f, wrench);
    st.inputsChanged();
  } else if (it->second != wrench) {
    it->second = wrench;
    st.inputsChanged();
  }
}

void RobotSystem::clearExternalWrenches(sim::PlantState& state) const {
  State& st = own<State>(state);
  if (!st.user_wrenches.empty()) {
    st.user_wrenches.clear();
    st.inputsChanged();
  }
}

control::ControllerInputs RobotSystem::controllerInputs(const State& st, int k) const {
  const auto& L = layout_[static_cast<size_t>(k)];
  return {st.sig.q_set[k], st.sig.qd_set[k],  st.sig.q_fb[k], st.sig.qm[k],
          st.sig.qdm[k],   st.sig.current[k], L.ratio,        st.drives[static_cast<size_t>(k)].motor.V_supply};
}

void RobotSystem::applyInputs(sim::PlantState& state, double t, Eigen::Ref<Eigen::VectorXd> y) const {
  State& st = own<State>(state);
  for (int k = 0; k < model_.nq; ++k) {
    const size_t kk = static_cast<size_t>(k);
    if (st.port[kk] != st.applied_port[kk]) bumpless(st, k, st.applied_port[kk], t, y);
  }
  st.applied_port = st.port;
  st.applied_cmd = st.cmd;
}

void RobotSystem::bumpless(State& st, int k, CommandPort from, double t, Eigen::Ref<Eigen::VectorXd> y) const {
  const size_t kk = static_cast<size_t>(k);
  const DriveSpec& d = st.drives[kk];
  const DriveLayout& L = layout_[kk];
  const CommandPort to = st.port[kk];
  if (L.controller < 0 || !controllerDriven(to)) return;  // no integrators, or the controller is not in use
  setpointStage(st, t);
  measurementStage(st, t, y);
  double* x = sampled() ? st.ctrl_x.data() + L.controller : y.data() + L.controller;
  const bool cascade = d.controller.type == control::ControllerType::VoltageCascade;
  // The actuator value applied just before the switch: the output of the controller under its old entry (held
  // output under sampled control), the voltage or torque command, or for a cascade leaving the torque port the
  // voltage that holds the present current (V = R i + k_e q̇_m).
  double u_prev = 0.0, i_prev = st.sig.current[k];
  if (controllerDriven(from)) {
    if (sampled()) {
      u_prev = st.held_u[k];
      i_prev = st.held_i_ref[k];
    } else {
      control::ControllerInputs in = controllerInputs(st, k);
      in.entry = entryOf(from);
      in.command = st.applied_cmd[k];
      double xdot[4];
      const control::ControllerOutputs o = controllers_[kk].evaluate(in, x, xdot);
      u_prev = o.u;
      i_prev = o.i_ref;
    }
  } else if (from == CommandPort::Voltage) {
    u_prev = st.motors[kk].supplyVoltage(st.applied_cmd[k]);
  } else {  // MotorTorque
    u_prev = cascade ? d.motor.R * st.sig.current[k] + d.motor.ke * st.sig.qdm[k] : st.applied_cmd[k];
    if (cascade) i_prev = st.sig.current[k];
  }
  control::ControllerInputs in = controllerInputs(st, k);
  in.entry = entryOf(to);
  in.command = st.cmd[k];
  controllers_[kk].matchOutput(in, u_prev, i_prev, x);
  if (sampled()) {  // the held output continues until the next sample
    st.held_u[k] = u_prev;
    st.held_i_ref[k] = to == CommandPort::Current ? st.cmd[k] : i_prev;
  }
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
}

void RobotSystem::setTrajectory(std::shared_ptr<const control::JointTrajectory> trajectory) {
  checkConfigurable("setTrajectory");
  if (!trajectory) throw InputError(name() + ": no trajectory given");
  if (trajectory->dof() != model_.nq)
    throw InputError(name() + ": the trajectory has " + std::to_string(trajectory->dof()) + " joints, the robot " +
                     std::to_string(model_.nq));
  setpoint_breaks_ = trajectory->breakpoints();
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
  for (const Fault& f : faults_) {
    const std::vector<double> e = faultEvents(f, t_end);
    events.insert(events.end(), e.begin(), e.end());
  }
  return events;
}

void RobotSystem::setFaults(std::vector<Fault> faults) {
  checkConfigurable("setFaults");
  std::vector<int> drive;
  for (const Fault& f : faults) {
    const int k = model_.jointIndex(f.joint);  // InputError for an unknown joint
    DriveSpec probe = drives_[static_cast<size_t>(k)];
    applyFault(probe, f);  // applies to this drive? (InputError naming the fault and the component)
    drive.push_back(k);
  }
  faults_ = std::move(faults);
  fault_drive_ = std::move(drive);
}

void RobotSystem::updateFaults(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool restart) const {
  if (faults_.empty()) return;
  std::vector<char> dirty(drives_.size(), restart ? 1 : 0);
  for (size_t i = 0; i < faults_.size(); ++i) {
    const Fault& f = faults_[i];
    const int k = fault_drive_[i];
    if (f.intermittent()) {
      long episode = -1;
      if (restart) st.stuck_episode[i] = -1;
      if (f.type == FaultType::SensorStuck && faultEpisode(f, t, &episode) && episode != st.stuck_episode[i]) {
        st.stuck_episode[i] = episode;  // the reading at the episode's start, held through it
        st.stuck_value[i] = y[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias;
      }
      continue;
    }
    const double v = t >= f.onset ? scheduledFaultValue(f, t) : std::numeric_limits<double>::quiet_NaN();
    const double before = st.fault_applied[i];
    st.fault_applied[i] = f.type == FaultType::BearingRipple ? (std::isnan(v) ? 0.0 : v) : v;
    if (f.parameterFault() && !(v == before || (std::isnan(v) && std::isnan(before))))
      dirty[static_cast<size_t>(k)] = 1;
  }
  rebuildDrives(st, dirty);
}

void RobotSystem::rebuildDrives(State& st, const std::vector<char>& dirty) const {
  for (size_t k = 0; k < drives_.size(); ++k) {
    if (!dirty.empty() && !dirty[k]) continue;
    DriveSpec d = drives_[k];
    for (size_t i = 0; i < faults_.size(); ++i)
      if (static_cast<size_t>(fault_drive_[i]) == k && faults_[i].parameterFault() && !std::isnan(st.fault_applied[i]))
        applyFault(d, faults_[i], st.fault_applied[i]);
    st.drives[k] = std::move(d);
    st.motors[k] = drive::DcMotor(st.drives[k].motor);
  }
}

double RobotSystem::faultySensor(const State& st, int k, double t, double q_meas) const {
  for (size_t i = 0; i < faults_.size(); ++i) {
    if (fault_drive_[i] != k || !faults_[i].intermittent() || !faultEpisode(faults_[i], t)) continue;
    switch (faults_[i].type) {
      case FaultType::SensorDropout: q_meas = 0.0; break;
      case FaultType::SensorStuck: q_meas = st.stuck_value[i]; break;
      case FaultType::SensorSpike: q_meas += faults_[i].value; break;
      default: break;
    }
  }
  return q_meas;
}

void RobotSystem::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              const std::vector<int>&) const {
  updateFaults(own<State>(state), t, y, false);
}

void RobotSystem::start(sim::PlantState& state, double t0, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  st.q_start = y.head(model_.nq);
  updateFaults(st, t0, y, true);
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

RobotSystem::MotionMeasurement RobotSystem::measureMotion(State& st, int k, double t,
                                                          const Eigen::Ref<const Eigen::VectorXd>& y, double phi,
                                                          double phid, double Ts) const {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = st.drives[static_cast<size_t>(k)].sensors;
  const double qm = L.rigid ? L.ratio * phi : y[L.motor];
  const double qdm = L.rigid ? L.ratio * phid : y[L.motor + 1];
  // Noise first, then the sensor's quantiser; encoder speed by differencing over Ts.
  MotionMeasurement m;
  m.q = faultySensor(st, k, t, quantise(y[k] + S.joint_bias + st.gauss(S.joint_noise), S.joint_quantum));
  m.qm = quantise(qm, S.motor_quantum);
  m.qdm = qdm;
  if (S.motor_quantum > 0.0) m.qdm = st.first_sample ? 0.0 : (m.qm - st.prev_qm_meas[k]) / Ts;
  m.qdm += st.gauss(S.motor_velocity_noise);
  st.prev_qm_meas[k] = m.qm;
  st.held_q_fb[k] = m.q;
  return m;
}

double RobotSystem::measureCurrent(State& st, int k, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = st.drives[static_cast<size_t>(k)].sensors;
  return quantise((L.current >= 0 ? y[L.current] : 0.0) + st.gauss(S.current_noise), S.current_quantum);
}

void RobotSystem::controlStep(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  if (!sampled()) throw InputError("controlStep: sampled control is not enabled");
  if (current_rate_ > 0.0) {
    multiRateStep(st, t, y);
    return;
  }
  const int n = model_.nq;
  const double Ts = 1.0 / sample_rate_;
  setpointStage(st, t);
  const Eigen::VectorXd phi = coupled_ ? Eigen::VectorXd(Ginv_ * y.head(n)) : Eigen::VectorXd(y.head(n));
  const Eigen::VectorXd phid = coupled_ ? Eigen::VectorXd(Ginv_ * y.segment(n, n)) : Eigen::VectorXd(y.segment(n, n));
  std::vector<double> xdot(4, 0.0);
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const MotionMeasurement m = measureMotion(st, k, t, y, phi[k], phid[k], Ts);
    const double i_meas = measureCurrent(st, k, y);
    const CommandPort port = st.port[static_cast<size_t>(k)];
    if (!controllerDriven(port)) continue;  // voltage or torque command: the controller holds its state
    control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], m.q,     m.qm,
                                 m.qdm,           i_meas,           L.ratio, d.motor.V_supply};
    in.entry = entryOf(port);
    in.command = st.cmd[k];
    double* x = L.controller >= 0 ? st.ctrl_x.data() + L.controller : nullptr;
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot.data());
    for (int j = 0; j < L.n_controller; ++j) x[j] += Ts * xdot[static_cast<size_t>(j)];  // forward Euler
    st.held_u[k] = out.u;
    st.held_i_ref[k] = out.i_ref;
  }
  st.first_sample = false;
}

void RobotSystem::multiRateStep(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  // Every call is a current-loop sample; every inner_per_outer_-th also an outer (position, velocity) sample.
  const int n = model_.nq;
  const double Ts_in = 1.0 / current_rate_, Ts_out = 1.0 / sample_rate_;
  const bool outer = st.inner_count % inner_per_outer_ == 0;
  ++st.inner_count;
  setpointStage(st, t);
  double xdot[4] = {0.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const CommandPort port = st.port[static_cast<size_t>(k)];
    const bool cascade = d.controller.type == control::ControllerType::VoltageCascade;
    double* x = L.controller >= 0 ? st.ctrl_x.data() + L.controller : nullptr;
    const double i_meas = measureCurrent(st, k, y);
    if (outer) {  // measure the joint and the motor, advance the outer loops over Ts_out
      const double phi = coupled_ ? Ginv_.row(k).dot(y.head(n)) : y[k];
      const double phid = coupled_ ? Ginv_.row(k).dot(y.segment(n, n)) : y[n + k];
      const MotionMeasurement m = measureMotion(st, k, t, y, phi, phid, Ts_out);
      if (controllerDriven(port)) {
        control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], m.q,     m.qm,
                                     m.qdm,           i_meas,           L.ratio, d.motor.V_supply};
        in.entry = entryOf(port);
        in.command = st.cmd[k];
        const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
        if (cascade) {
          x[0] += Ts_out * xdot[0];  // the velocity integrator; the current loop below
          st.held_i_ref[k] = out.i_ref;
        } else {
          for (int j = 0; j < L.n_controller; ++j) x[j] += Ts_out * xdot[j];
          st.held_u[k] = out.u;
          st.held_i_ref[k] = out.i_ref;
        }
      }
    }
    if (!cascade || !controllerDriven(port)) continue;
    // The current loop on the held reference (or the Current port's command), over Ts_in.
    control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], st.held_q_fb[k], 0.0, 0.0,
                                 i_meas,          L.ratio,          d.motor.V_supply};
    in.entry = control::ControlEntry::Current;
    in.command = port == CommandPort::Current ? st.cmd[k] : st.held_i_ref[k];
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
    x[1] += Ts_in * xdot[1];
    st.held_u[k] = out.u;
  }
  st.first_sample = false;
}

void RobotSystem::setpointStage(const State& st, double t) const {
  if (setpoints_) {
    setpoints_(t, st.sig.q_set, st.sig.qd_set, st.sig.qdd_set);
  } else {  // no reference given: hold the start pose
    st.sig.q_set = st.q_start;
    st.sig.qd_set.setZero();
    st.sig.qdd_set.setZero();
  }
  for (int k = 0; k < model_.nq; ++k)
    if (st.ref_held[static_cast<size_t>(k)]) {
      st.sig.q_set[k] = st.ref_q[k];
      st.sig.qd_set[k] = st.ref_qd[k];
      st.sig.qdd_set[k] = st.ref_qdd[k];
    }
}

void RobotSystem::measurementStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  // Gear output angles and speeds: φ = G⁻¹ q.
  if (coupled_) {
    st.phi.noalias() = Ginv_ * q;
    st.phid.noalias() = Ginv_ * qd;
  } else {
    st.phi = q;
    st.phid = qd;
  }
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    st.sig.qm[k] = L.rigid ? L.ratio * st.phi[k] : y[L.motor];
    st.sig.qdm[k] = L.rigid ? L.ratio * st.phid[k] : y[L.motor + 1];
    st.sig.current[k] = L.current >= 0 ? y[L.current] : 0.0;
    st.sig.q_fb[k] = sampled() ? st.held_q_fb[k]
                               : faultySensor(st, k, t, q[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias);
  }
}

void RobotSystem::controllerStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    control::ControllerOutputs out;
    const CommandPort port = st.port[static_cast<size_t>(k)];
    if (!controllerDriven(port)) {  // the command bypasses the controller, whose integrators hold
      out.voltage = port == CommandPort::Voltage;
      out.u = st.cmd[k];
      if (!sampled())
        for (int j = 0; j < L.n_controller; ++j) ydot[L.controller + j] = 0.0;
    } else if (sampled()) {  // zero-order hold of the last sample's outputs
      out.voltage = d.controller.type == control::ControllerType::VoltageCascade;
      out.u = st.held_u[k];
      out.i_ref = st.held_i_ref[k];
    } else {
      control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k],  st.sig.q_fb[k], st.sig.qm[k],
                                   st.sig.qdm[k],   st.sig.current[k], L.ratio,        d.motor.V_supply};
      in.entry = entryOf(port);
      in.command = st.cmd[k];
      out = controllers_[static_cast<size_t>(k)].evaluate(in, L.controller >= 0 ? y.data() + L.controller : nullptr,
                                                          L.controller >= 0 ? ydot + L.controller : nullptr);
    }
    st.sig.i_ref[k] = out.i_ref;
    st.sig.u[k] = out.u;
    st.out_is_voltage[static_cast<size_t>(k)] = out.voltage;
  }
}

void RobotSystem::powerElectronicsStage(const State& st) const {
  // Averaged PWM: the commanded voltage, saturated at the supply [Raviola2023, eq. 1].
  for (int k = 0; k < model_.nq; ++k) {
    const bool electrics = layout_[static_cast<size_t>(k)].current >= 0;
    const double V_cmd = st.out_is_voltage[static_cast<size_t>(k)] ? st.sig.u[k] : 0.0;
    st.sig.voltage[k] = electrics ? st.motors[static_cast<size_t>(k)].supplyVoltage(V_cmd) : 0.0;
  }
}

void RobotSystem::motorElectricsStage(const State& st, double* ydot) const {
  // L di/dt = V − R i − k_e q̇_m, τ_M = k_t i; a motor without electrics gives the commanded torque.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const drive::DcMotor& motor = st.motors[static_cast<size_t>(k)];
    if (L.current >= 0 && st.port[static_cast<size_t>(k)] == CommandPort::MotorTorque) {
      // Electrics bypassed: the torque is the command; the current relaxes to τ/k_t with L/R.
      const drive::DcMotorParams& m = st.drives[static_cast<size_t>(k)].motor;
      st.sig.tau_motor[k] = st.sig.u[k];
      ydot[L.current] = (st.sig.u[k] / m.kt - st.sig.current[k]) * m.R / m.L;
    } else if (L.current >= 0) {
      const double V_cmd = st.out_is_voltage[static_cast<size_t>(k)] ? st.sig.u[k] : 0.0;
      ydot[L.current] = motor.currentDerivative(st.sig.current[k], V_cmd, st.sig.qdm[k]);
      st.sig.tau_motor[k] = motor.torque(st.sig.current[k]);
    } else {
      st.sig.tau_motor[k] = st.out_is_voltage[static_cast<size_t>(k)] ? 0.0 : st.sig.u[k];
    }
  }
}

void RobotSystem::transmissionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (L.rigid) {
      st.sig.tau_gear[k] = L.ratio * st.sig.tau_motor[k];  // the rotor's inertial reaction follows the accelerations
      continue;
    }
    const drive::PortTorques pt =
        d.transmission->evaluate({st.sig.qm[k], st.sig.qdm[k], st.phi[k], st.phid[k]},
                                 L.gear >= 0 ? y.data() + L.gear : nullptr, L.gear >= 0 ? ydot + L.gear : nullptr);
    st.sig.tau_gear[k] = pt.tau_out;
    ydot[L.motor] = st.sig.qdm[k];
    ydot[L.motor + 1] = (st.sig.tau_motor[k] - pt.tau_in) / d.motor.J_M;  // rotor: J_M q̈_m = τ_M − τ_in
  }
}

void RobotSystem::frictionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  // On the gear output shaft, driven by the gear output torque.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    st.sig.tau_friction[k] = d.friction ? d.friction->evaluate({st.phid[k], st.sig.tau_gear[k]},
                                                               L.friction >= 0 ? y.data() + L.friction : nullptr,
                                                               L.friction >= 0 ? ydot + L.friction : nullptr)
                                        : 0.0;
  }
  // A bearing defect of the output shaft: τ_b = A sin(order · φ_out), with the amplitude of its schedule.
  for (size_t i = 0; i < faults_.size(); ++i)
    if (faults_[i].type == FaultType::BearingRipple) {
      const int k = fault_drive_[i];
      st.sig.tau_friction[k] += st.fault_applied[i] * std::sin(faults_[i].order * st.phi[k]);
    }
}

void RobotSystem::jointTorqueStage(const State& st) const {
  // τ_out = τ_gear − τ_f on the gear outputs; τ_joint = G⁻ᵀ τ_out.
  st.tau_out = st.sig.tau_gear - st.sig.tau_friction;
  if (coupled_)
    st.tau.noalias() = Ginv_.transpose() * st.tau_out;
  else
    st.tau = st.tau_out;
  st.sig.tau_joint = st.tau;
}

void RobotSystem::multibodyStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  if (stops_.active()) {  // end stops act on the joints beside the drives
    stops_.torques(q, qd, st.sig.tau_stop);
    st.tau += st.sig.tau_stop;
  }
  const multibody::Matrix6Xd* fext = nullptr;
  if (wrenches_ || !st.user_wrenches.empty()) {
    multibody::forwardKinematics(model_, st.data, q);
    st.fext.setZero();
    if (wrenches_) wrenches_(t, model_, st.data, q, qd, st.fext);
    for (const auto& [f, w] : st.user_wrenches) {
      // World wrench at the frame origin → body frame of the carrying body, moment about the body origin.
      const multibody::Frame& fr = model_.frames[static_cast<size_t>(f)];
      const multibody::Placement& B = st.data.oMi[static_cast<size_t>(fr.joint)];
      const Eigen::Vector3d r = st.data.oMf[static_cast<size_t>(f)].p - B.p;
      st.fext.col(fr.joint).head<3>() += B.R.transpose() * (w.tail<3>() + r.cross(w.head<3>()));
      st.fext.col(fr.joint).tail<3>() += B.R.transpose() * w.head<3>();
    }
    fext = &st.fext;
  }
  if (crba_path_) {
    // (M + G⁻ᵀ diag(N² J_M) G⁻¹) q̈ = τ − h(q, q̇) [− Jᵀ f_ext through RNEA]
    if (fext)
      st.data.nle = multibody::rnea(model_, st.data, q, qd, st.zero, fext);
    else
      multibody::nonLinearEffects(model_, st.data, q, qd);
    st.M = multibody::crba(model_, st.data, q);
    st.M += reflected_;
    st.llt.compute(st.M);
    st.sig.qdd = st.tau - st.data.nle;
    st.llt.solveInPlace(st.sig.qdd);
  } else {
    st.sig.qdd = multibody::aba(model_, st.data, q, qd, st.tau, fext);
  }
}

void RobotSystem::rotorReactionStage(const State& st) const {
  // Rigid drives: the gear output torque includes the rotor's inertial reaction −N² J_M φ̈.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (!L.rigid) continue;
    const double phidd = coupled_ ? Ginv_.row(k).dot(st.sig.qdd) : st.sig.qdd[k];
    st.sig.tau_gear[k] -= L.ratio * L.ratio * st.drives[static_cast<size_t>(k)].motor.J_M * phidd;
  }
}

void RobotSystem::evaluate(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  setpointStage(st, t);
  measurementStage(st, t, y);
  controllerStage(st, y, ydot);
  powerElectronicsStage(st);
  motorElectricsStage(st, ydot);
  transmissionStage(st, y, ydot);
  frictionStage(st, y, ydot);
  jointTorqueStage(st);
  multibodyStage(st, t, y);
  rotorReactionStage(st);
  const int n = model_.nq;
  Eigen::Map<Eigen::VectorXd> yd(ydot, n_states_);
  yd.head(n) = y.segment(n, n);
  yd.segment(n, n) = st.sig.qdd;
}

void RobotSystem::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> ydot) const {
  evaluate(own<State>(state), t, y, ydot.data());
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

void RobotSystem::jacobian(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                           Eigen::Ref<Eigen::MatrixXd> J) const {
  const State& st = own<State>(state);
  const int n = model_.nq;
  Eigen::VectorXd& yp = st.jac_y;
  Eigen::VectorXd& fp = st.jac_f;
  yp = y;
  // The base point: the drives' output torques and the total joint torque (drives, end stops) behind q̈.
  evaluate(st, t, y, fp.data());
  st.jac_tau0 = st.tau_out;
  st.jac_qdd0 = st.sig.qdd;
  const Eigen::VectorXd& tau_total = st.tau;
  // ∂q̈/∂τ_out = M⁻¹ G⁻ᵀ, column by column; q̈ is affine in the joint torque, so a unit difference is exact to
  // rounding. (The external wrenches st.fext of the base evaluation stay in place.)
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  const bool with_fext = wrenches_ || !st.user_wrenches.empty();
  for (int j = 0; j < n; ++j) {
    st.jac_tau = tau_total;
    if (coupled_)
      st.jac_tau += Ginv_.row(j).transpose();
    else
      st.jac_tau[j] += 1.0;
    if (crba_path_) {
      st.jac_P.col(j) = st.jac_tau - st.data.nle;
      st.llt.solveInPlace(st.jac_P.col(j));
    } else {
      st.jac_P.col(j) = multibody::aba(model_, st.data, q, qd, st.jac_tau, with_fext ? &st.fext : nullptr);
    }
    st.jac_P.col(j) -= st.jac_qdd0;
  }
  // Hub columns: whole difference quotients.
  for (int j = 0; j < 2 * n; ++j) {
    yp[j] = y[j] + inc[j];
    evaluate(st, t, yp, fp.data());
    J.col(j) = (fp - f) / inc[j];
    yp[j] = y[j];
  }
  // Drive columns: state c of every drive at once.
  size_t max_m = 0;
  for (const auto& b : st.jac_structure.blocks) max_m = std::max(max_m, b.size());
  const auto& blocks = st.jac_structure.blocks;
  for (size_t c = 0; c < max_m; ++c) {
    for (const auto& b : blocks)
      if (b.size() > c) yp[b[c]] = y[b[c]] + inc[b[c]];
    evaluate(st, t, yp, fp.data());
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
      const auto& b = blocks[bi];
      if (b.size() <= c) continue;
      const int s = b[c];
      for (int r : b) J(r, s) = (fp[r] - f[r]) / inc[s];
      const int k = st.jac_block_drive[bi];
      J.col(s).segment(n, n) = st.jac_P.col(k) * ((st.tau_out[k] - st.jac_tau0[k]) / inc[s]);
      yp[s] = y[s];
    }
  }
}

const RobotSignals& RobotSystem::driveSignals(const sim::PlantState& state, double t,
                                              const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const State& st = own<State>(state);
  evaluate(st, t, y, st.tmp.data());
  return st.sig;
}

void RobotSystem::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::VectorXd> out) const {
  const State& st = own<State>(state);
  const int n = model_.nq;
  const RobotSignals& s = driveSignals(state, t, y);
  const Eigen::VectorXd& id = multibody::rnea(id_model_, st.id_data, s.q_set, s.qd_set, s.qdd_set);
  Eigen::Index c = 0;
  for (int k = 0; k < n; ++k) {
    const auto& d = st.drives[static_cast<size_t>(k)];
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
  multibody::forwardKinematics(id_model_, st.id_data, y.head(n));
  const multibody::Placement& X = st.id_data.oMf[static_cast<size_t>(tip_)];
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
  multibody::Data data(model_);
  double E = multibody::kineticEnergy(model_, data, q, qd) + multibody::potentialEnergy(model_, data, q);
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
