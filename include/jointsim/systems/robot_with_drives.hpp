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

#include "jointsim/drive/parameters.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems {

/// A change of one parameter of one drive's component by the key of the component's parameter table
/// (drive/parameters.hpp): how an experiment, a sweep or an FMU changes a robot file's drive without editing it.
struct DriveParameterChange {
  std::string joint;      ///< the joint whose drive
  std::string component;  ///< "motor", "transmission" or "friction"
  std::string key;        ///< a key of the component's table, e.g. "stiffness", "positive.alpha0", "tau_pos[1][1]"
  double value = 0.0;     ///< in the table's unit
  std::string
      where;  ///< where it was given, prefixed to errors (e.g. "exp.yaml:12: drives.elbow_joint..."); may be empty
};

/// The components of a drive that have parameter tables.
const std::vector<std::string>& driveComponents();
/// The parameter table of `component` ("motor", "transmission", "friction", "sensors") of drive `d`; empty for a drive without
/// friction. \throws InputError for another component name.
std::vector<drive::ParameterInfo> driveParameterTable(const DriveSpec& d, const std::string& component);
/// Applies `changes` to the drives of their joints (new, validated components). \throws InputError prefixed with
/// the change's `where`: a joint without a drive, an unknown component or key, a value the component refuses.
void applyDriveParameters(std::vector<DriveSpec>& drives, const std::vector<DriveParameterChange>& changes);

/// Loads a robot-with-drives file. Throws InputError (file:line: key.path) on bad input, including a
/// joint without a drive and gains of the wrong sign. `changes` are applied to the drives, then `faults` (InputError
/// if one does not apply), before the system is assembled.
RobotSystem loadRobotWithDrives(const std::string& path, const std::vector<Fault>& faults = {},
                                const std::vector<DriveParameterChange>& changes = {});

}  // namespace jointsim::systems
