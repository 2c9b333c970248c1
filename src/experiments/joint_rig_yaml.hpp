#pragma once
// Internal: reading a joint-rig experiment file (format in docs/experiments.md) and writing its resolved
// parameters into summary.json.
#include <memory>
#include <string>

#include "io/yaml_reader.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/experiments/joint_rig.hpp"
#include "jointsim/io/json.hpp"

namespace jointsim::experiments::detail {

JointRigSetup readJointRig(const io::YamlValue& root, const std::string& name);
void writeJointRigParameters(io::JsonWriter& w, const JointRig& rig, const io::YamlValue& root,
                             const std::string& config_path);

/// `motor: {preset: ur5_joint1..6, R, L, kt, ke, J_M, V_supply}` (preset values overridable).
drive::DcMotorParams readMotor(const io::YamlValue& node);
/// `transmission: {type: rigid|elastic|elasto_backlash|strain_wave_gear, ...}`.
std::shared_ptr<const drive::Transmission> readTransmission(const io::YamlValue& node);
/// `model: {type: coulomb_viscous|table|stribeck|dahl|lugre|lugre_ur5, ...}` (drive/friction_yaml).
std::shared_ptr<const drive::Friction> readFrictionModel(const io::YamlValue& node);
/// The strain-wave-gear block of `transmission` (drive/strain_wave_gear_yaml).
std::shared_ptr<const drive::Transmission> readStrainWaveGear(const io::YamlValue& node);

}  // namespace jointsim::experiments::detail
