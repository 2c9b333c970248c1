#pragma once
// Internal to the systems layer: helpers shared by the files of RobotSystem (robot_system.cpp: construction, state and
// configuration; robot_ports.cpp: command and input ports; robot_faults.cpp: faults during a run; robot_dynamics.cpp:
// the right-hand side, its Jacobian, sampled control and signals).
#include <cmath>

#include "jointsim/control/joint_controller.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems::detail {

/// x rounded to the nearest multiple of `quantum` (0: x).
inline double quantise(double x, double quantum) { return quantum > 0.0 ? quantum * std::round(x / quantum) : x; }

/// Where a command port's value enters the joint controller.
inline control::ControlEntry entryOf(CommandPort port) {
  switch (port) {
    case CommandPort::MotorVelocity: return control::ControlEntry::MotorVelocity;
    case CommandPort::Current: return control::ControlEntry::Current;
    default: return control::ControlEntry::Position;
  }
}

/// Whether the joint controller runs under this port (set point, motor velocity, current), as opposed to a port that
/// replaces it (voltage, motor torque).
inline bool controllerDriven(CommandPort port) {
  return port == CommandPort::Setpoint || port == CommandPort::MotorVelocity || port == CommandPort::Current;
}

}  // namespace jointsim::systems::detail
