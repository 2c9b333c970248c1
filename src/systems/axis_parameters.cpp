// Parameter tables of the axes of the clamping and RobotR3 models and of the drive chain's elements (drive/parameters.hpp), through which faults and
// other front ends change them as they change the drive components of a robot with drives.
#include <string>
#include <vector>

#include "jointsim/drive/parameters.hpp"
#include "jointsim/systems/clamped_robot.hpp"
#include "jointsim/systems/drive_chain.hpp"
#include "jointsim/systems/robotr3_full.hpp"

namespace jointsim::systems {

using drive::ParameterChanges;
using drive::ParameterInfo;
using drive::ParameterRange;
using drive::ParameterRef;
using drive::ParameterRole;

namespace {

ParameterRef ref(std::string key, std::string unit, ParameterRange range, ParameterRole role, std::string what,
                 double* target) {
  return {{std::move(key), std::move(unit), 0.0, range, role, std::move(what)}, target};
}

std::vector<ParameterRef> clampingRefs(ClampingAxisParams& a) {
  std::vector<ParameterRef> r{
      ref("inertia", "kg·m²", ParameterRange::positive(), ParameterRole::None, "motor (rotor) inertia J", &a.inertia),
      ref("c", "N·m/rad", ParameterRange::positive(), ParameterRole::Stiffness,
          "ElastoBacklash stiffness c (motor side)", &a.c),
      ref("d", "N·m·s/rad", ParameterRange::nonNegative(), ParameterRole::None, "ElastoBacklash damping d (motor side)",
          &a.d),
      ref("b", "rad", ParameterRange::nonNegative(), ParameterRole::Backlash, "total backlash b (motor side)", &a.b)};
  for (size_t i = 0; i < a.tau_pos.size(); ++i)
    r.push_back(ref("friction.tau_pos[" + std::to_string(i) + "][1]", "N·m", ParameterRange::nonNegative(),
                    ParameterRole::Coulomb, "bearing friction torque at the row's speed", &a.tau_pos[i][1]));
  r.push_back(ref("friction.peak", "1", ParameterRange::atLeast(1.0), ParameterRole::None,
                  "stiction factor (breakaway = peak · tau_pos(0))", &a.peak));
  return r;
}

std::vector<ParameterRef> robotR3Refs(RobotR3AxisParams& a) {
  std::vector<ParameterRef> r{ref("motor.J", "kg·m²", ParameterRange::positive(), ParameterRole::None,
                                  "rotor inertia J", &a.motor.J),
                              ref("motor.k", "N·m/A", ParameterRange::positive(), ParameterRole::TorqueConstant,
                                  "EMF and torque constant k (V·s/rad = N·m/A)", &a.motor.k)};
  if (a.type == 1) {
    r.push_back(ref("c", "N·m/rad", ParameterRange::positive(), ParameterRole::Stiffness,
                    "gear spring stiffness c (motor side)", &a.c));
    r.push_back(
        ref("d", "N·m·s/rad", ParameterRange::nonNegative(), ParameterRole::None, "gear damper d (motor side)", &a.d));
  }
  r.push_back(ref("Rv0", "N·m", ParameterRange::nonNegative(), ParameterRole::Coulomb,
                  "Coulomb friction torque Rv0 of the bearing", &a.Rv0));
  r.push_back(ref("Rv1", "N·m·s/rad", ParameterRange::nonNegative(), ParameterRole::None,
                  "viscous friction coefficient Rv1 of the bearing", &a.Rv1));
  r.push_back(ref("peak", "1", ParameterRange::atLeast(1.0), ParameterRole::None, "stiction factor", &a.peak));
  return r;
}

std::vector<ParameterRef> chainRefs(ChainElement& e) {
  std::vector<ParameterRef> r;
  if (e.type == ChainElementType::SpringDamper || e.type == ChainElementType::ElastoBacklash) {
    r.push_back(ref("c", "N·m/rad", ParameterRange::nonNegative(), ParameterRole::Stiffness, "stiffness c", &e.c));
    r.push_back(ref("d", "N·m·s/rad", ParameterRange::nonNegative(), ParameterRole::None, "damping d", &e.d));
  }
  if (e.type == ChainElementType::ElastoBacklash)
    r.push_back(ref("backlash", "rad", ParameterRange::nonNegative(), ParameterRole::Backlash, "total backlash b",
                    &e.backlash));
  if (e.isFriction()) {
    const bool bearing = e.type == ChainElementType::BearingFriction;
    for (size_t i = 0; i < e.table.size(); ++i)
      r.push_back(ref(std::string(bearing ? "tau_pos" : "mu") + "[" + std::to_string(i) + "][1]", bearing ? "N·m" : "1",
                      ParameterRange::nonNegative(), ParameterRole::Coulomb,
                      bearing ? "friction torque at the row's speed" : "friction coefficient at the row's speed",
                      &e.table[i][1]));
    if (!bearing)
      r.push_back(
          ref("fn_max", "N", ParameterRange::nonNegative(), ParameterRole::None, "maximum normal force", &e.fn_max));
    r.push_back(ref("peak", "1", ParameterRange::atLeast(1.0), ParameterRole::None, "stiction factor", &e.peak));
  }
  return r;
}

}  // namespace

std::vector<ParameterInfo> ChainElement::parameters() const {
  ChainElement copy = *this;
  return drive::describeParameters(chainRefs(copy));
}

ChainElement ChainElement::withParameters(const ParameterChanges& changes) const {
  ChainElement copy = *this;
  drive::assignParameters(chainRefs(copy), changes, "drive chain element '" + name + "'");
  return copy;
}

std::vector<ParameterInfo> ClampingAxisParams::parameters() const {
  ClampingAxisParams copy = *this;
  return drive::describeParameters(clampingRefs(copy));
}

ClampingAxisParams ClampingAxisParams::withParameters(const ParameterChanges& changes) const {
  ClampingAxisParams copy = *this;
  drive::assignParameters(clampingRefs(copy), changes, "clamping axis '" + joint + "'");
  copy.validate();
  return copy;
}

std::vector<ParameterInfo> RobotR3AxisParams::parameters() const {
  RobotR3AxisParams copy = *this;
  return drive::describeParameters(robotR3Refs(copy));
}

RobotR3AxisParams RobotR3AxisParams::withParameters(const ParameterChanges& changes,
                                                    const std::string& component) const {
  RobotR3AxisParams copy = *this;
  drive::assignParameters(robotR3Refs(copy), changes, component);
  return copy;
}

}  // namespace jointsim::systems
