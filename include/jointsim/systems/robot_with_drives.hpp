#pragma once
/// \file
/// Robot-with-drives files: a multibody description and one drive per joint, loaded into a RobotSystem.
///
/// A robot-with-drives YAML names its multibody description and one drive per joint:
/// ```yaml
/// name: ur5_twin
/// multibody: ur5.yaml                  # URDF or YAML robot file, relative to this file
/// drives:
///   - joint: shoulder_pan_joint
///     motor: {preset: ur5_joint1}      # or R, L, kt, ke, J_M, V_supply
///     electrics: true                  # default: true for voltage_cascade, false otherwise
///     transmission: {type: strain_wave_gear, size: A}   # any joint-rig transmission
///     friction: {type: lugre_ur5, f_c: 7, f_v: 4, k_q: 1}   # on the gear output shaft (optional)
///     controller: {type: voltage_cascade, P_pos: 7400, P_vel: 1, I_vel: 0.1, P_cur: 10, I_cur: 10000}
/// coupling: [[...], ...]               # optional n×n matrix G: q_joint = G φ_gear_out
/// ```

#include <string>

#include <vector>

#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems {

/// Loads a robot-with-drives file. Throws InputError (file:line: key.path) on bad input, including a
/// joint without a drive and gains of the wrong sign. `faults` are applied to the drives before the
/// system is assembled (InputError if one does not apply).
RobotSystem loadRobotWithDrives(const std::string& path, const std::vector<Fault>& faults = {});

}  // namespace jointsim::systems
