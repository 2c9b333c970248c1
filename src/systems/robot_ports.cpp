// RobotSystem (robot_system.hpp): the command ports and named inputs, bumpless switches between them.
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

#include "systems/robot_system_internal.hpp"

namespace jointsim::systems {

using detail::controllerDriven;
using detail::entryOf;
using detail::quantise;

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
    if (in.kind == kLoadTorqueInput) {
      out.push_back(load_ports_[static_cast<size_t>(in.joint)]);
      continue;
    }
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
  if (in.kind == kLoadTorqueInput) {
    if (st.loads.set(k, value, load_ports_, name())) st.inputsChanged();
    return;
  }
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
  if (in.kind == kLoadTorqueInput) return st.loads.value[static_cast<size_t>(in.joint)];
  const bool held = st.ref_held[static_cast<size_t>(in.joint)] != 0;
  if (in.kind == 0) return held ? st.ref_q[in.joint] : st.q_start[in.joint];
  if (in.kind == 1) return held ? st.ref_qd[in.joint] : 0.0;
  if (in.kind == 2) return held ? st.ref_qdd[in.joint] : 0.0;
  return st.port[static_cast<size_t>(in.joint)] == static_cast<CommandPort>(in.kind - 3) ? st.cmd[in.joint] : 0.0;
}

bool RobotSystem::inputActive(const sim::PlantState& state, int port) const {
  const InputSlot& in = inputSlot(port);
  const CommandPort now = own<State>(state).port[static_cast<size_t>(in.joint)];
  if (in.kind == kLoadTorqueInput) return true;  // adds to the joint torques
  return in.kind < 3 ? now == CommandPort::Setpoint : now == static_cast<CommandPort>(in.kind - 3);
}

void RobotSystem::setInputProfile(int port, const control::Profile& profile) {
  const InputSlot& in = inputSlot(port);
  if (in.kind != kLoadTorqueInput)
    throw InputError(name() + ": input " + inputPorts()[static_cast<size_t>(port)].name +
                     ": a command port takes no profile (set it between steps, or give the drive a trajectory); "
                     "the load torques take profiles");
  checkConfigurable("setInputProfile");
  load_profiles_.set(in.joint, profile, load_ports_, name());
}

void RobotSystem::releaseInput(sim::PlantState& state, int port) const {
  const InputSlot& in = inputSlot(port);
  if (in.kind != kLoadTorqueInput)
    throw InputError(name() + ": input " + inputPorts()[static_cast<size_t>(port)].name +
                     ": a command port is not released; choose another port (setCommandPort) instead");
  State& st = own<State>(state);
  if (st.loads.release(static_cast<size_t>(in.joint))) st.inputsChanged();
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

}  // namespace jointsim::systems
