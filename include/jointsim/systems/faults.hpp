#pragma once
/// \file
/// Fault injection for prognostics data sets: typed, physically meaningful modifications of one drive of
/// a robot with drives (systems::DriveSpec), applied before the system is assembled. Each fault builds new
/// component objects from the old ones' parameters; nothing is mutated in place.
///
/// | type (YAML name)          | value                         | effect                                                     |
/// |---------------------------|-------------------------------|------------------------------------------------------------|
/// | `gear_stiffness_scale`    | factor s > 0 [-]              | every stiffness of the transmission × s (worn gear)        |
/// | `backlash_add`            | Δb >= 0 [rad], transmission's compliance side | total backlash + Δb (an elastic gear becomes elasto-backlash) |
/// | `coulomb_friction_scale`  | factor s > 0 [-]              | Coulomb level × s: f_c, α0 (both directions), table torques |
/// | `sigma0_scale`            | factor s > 0 [-]              | bristle stiffness σ0 (LuGre, UR5 LuGre) or Dahl σ × s      |
/// | `torque_constant_scale`   | factor s > 0 [-]              | motor k_t and k_e × s (demagnetised motor); needs electrics |
/// | `sensor_bias`             | bias [rad]                    | constant offset of the measured joint angle; needs a controller that reads it (cascade_002) |
///
/// A fault that does not apply to the drive's components (e.g. backlash on a strain-wave gear, σ0 on
/// Coulomb friction) throws InputError naming the joint, the fault and the component type.

#include <string>
#include <vector>

namespace jointsim::systems {

struct DriveSpec;  // robot_system.hpp

enum class FaultType {
  GearStiffnessScale,
  BacklashAdd,
  CoulombFrictionScale,
  Sigma0Scale,
  TorqueConstantScale,
  SensorBias
};

struct Fault {
  FaultType type = FaultType::GearStiffnessScale;
  std::string joint;   ///< joint whose drive is affected
  double value = 1.0;  ///< factor [-], backlash [rad] or bias [rad], see the table above
};

const char* toString(FaultType type);
/// Parses a YAML/CLI name (e.g. "gear_stiffness_scale"); throws InputError listing the known names.
FaultType faultTypeFromString(const std::string& name);
/// All fault type names, in the order of the enum.
std::vector<std::string> faultTypeNames();
/// "gear_stiffness_scale@elbow_joint=0.8".
std::string describe(const Fault& fault);

/// Applies `fault` to `drive` (whose joint must be fault.joint). Throws InputError when the fault does not
/// apply to the drive's components or its value is out of range.
void applyFault(DriveSpec& drive, const Fault& fault);
/// Applies every fault to the drive of its joint; throws InputError for a joint without a drive.
void applyFaults(std::vector<DriveSpec>& drives, const std::vector<Fault>& faults);

}  // namespace jointsim::systems
