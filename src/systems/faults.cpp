#include "jointsim/systems/faults.hpp"

#include <cmath>
#include <memory>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems {
namespace {

const char* const kNames[] = {"gear_stiffness_scale", "backlash_add",          "coulomb_friction_scale",
                              "sigma0_scale",         "torque_constant_scale", "sensor_bias"};

[[noreturn]] void notApplicable(const Fault& f, const std::string& component) {
  throw InputError("fault " + describe(f) + ": does not apply to " + component);
}

void transmissionFault(DriveSpec& d, const Fault& f) {
  const drive::Transmission* t = d.transmission.get();
  const std::string type = t ? t->type() : "no transmission";
  if (f.type == FaultType::GearStiffnessScale) {
    if (auto* e = dynamic_cast<const drive::ElasticGear*>(t)) {
      auto p = e->params();
      p.stiffness *= f.value;
      d.transmission = std::make_shared<drive::ElasticGear>(p);
    } else if (auto* b = dynamic_cast<const drive::ElastoBacklash*>(t)) {
      auto p = b->params();
      p.stiffness *= f.value;
      d.transmission = std::make_shared<drive::ElastoBacklash>(p);
    } else if (auto* s = dynamic_cast<const drive::StrainWaveGear*>(t)) {
      auto p = s->params();
      for (double* k : {&p.K_WG, &p.K_b, &p.K_FS, &p.K_m, &p.K_CS}) *k *= f.value;
      d.transmission = std::make_shared<drive::StrainWaveGear>(p);
    } else {
      notApplicable(f, "a " + type + " transmission (no stiffness)");
    }
    return;
  }
  // BacklashAdd
  if (auto* e = dynamic_cast<const drive::ElasticGear*>(t)) {
    const auto& q = e->params();
    drive::ElastoBacklashParams p;
    p.ratio = q.ratio;
    p.stiffness = q.stiffness;
    p.damping = q.damping;
    p.side = q.side;
    p.backlash = f.value;
    d.transmission = std::make_shared<drive::ElastoBacklash>(p);
  } else if (auto* b = dynamic_cast<const drive::ElastoBacklash*>(t)) {
    auto p = b->params();
    p.backlash += f.value;
    d.transmission = std::make_shared<drive::ElastoBacklash>(p);
  } else {
    notApplicable(f, "a " + type + " transmission (backlash needs an elastic or elasto_backlash gear)");
  }
}

void frictionFault(DriveSpec& d, const Fault& f) {
  const drive::Friction* fr = d.friction.get();
  if (!fr) notApplicable(f, "a drive without friction");
  const double s = f.value;
  if (f.type == FaultType::CoulombFrictionScale) {
    if (auto* m = dynamic_cast<const drive::CoulombViscousFriction*>(fr)) {
      auto p = m->params();
      p.f_c *= s;
      d.friction = std::make_shared<drive::CoulombViscousFriction>(p);
    } else if (auto* m = dynamic_cast<const drive::TableFriction*>(fr)) {
      auto p = m->params();
      for (auto& row : p.tau_pos) row[1] *= s;
      d.friction = std::make_shared<drive::TableFriction>(p);
    } else if (auto* m = dynamic_cast<const drive::StribeckFriction*>(fr)) {
      auto p = m->params();
      p.positive.alpha0 *= s;
      p.negative.alpha0 *= s;
      d.friction = std::make_shared<drive::StribeckFriction>(p);
    } else if (auto* m = dynamic_cast<const drive::DahlFriction*>(fr)) {
      auto p = m->params();
      p.f_c *= s;
      d.friction = std::make_shared<drive::DahlFriction>(p);
    } else if (auto* m = dynamic_cast<const drive::LuGreFriction*>(fr)) {
      auto p = m->params();
      p.positive.alpha0 *= s;
      p.negative.alpha0 *= s;
      d.friction = std::make_shared<drive::LuGreFriction>(p);
    } else if (auto* m = dynamic_cast<const drive::LuGreUr5Friction*>(fr)) {
      auto p = m->params();
      p.f_c *= s;
      d.friction = std::make_shared<drive::LuGreUr5Friction>(p);
    } else {
      notApplicable(f, fr->type() + " friction");
    }
    return;
  }
  // Sigma0Scale
  if (auto* m = dynamic_cast<const drive::LuGreFriction*>(fr)) {
    auto p = m->params();
    p.sigma0 *= s;
    d.friction = std::make_shared<drive::LuGreFriction>(p);
  } else if (auto* m = dynamic_cast<const drive::LuGreUr5Friction*>(fr)) {
    auto p = m->params();
    p.sigma0 *= s;
    d.friction = std::make_shared<drive::LuGreUr5Friction>(p);
  } else if (auto* m = dynamic_cast<const drive::DahlFriction*>(fr)) {
    auto p = m->params();
    p.sigma *= s;
    d.friction = std::make_shared<drive::DahlFriction>(p);
  } else {
    notApplicable(f, fr->type() + " friction (no bristle stiffness)");
  }
}

}  // namespace

const char* toString(FaultType type) { return kNames[static_cast<int>(type)]; }

std::vector<std::string> faultTypeNames() { return {std::begin(kNames), std::end(kNames)}; }

FaultType faultTypeFromString(const std::string& name) {
  for (int i = 0; i < 6; ++i)
    if (name == kNames[i]) return static_cast<FaultType>(i);
  std::string list;
  for (const char* n : kNames) list += (list.empty() ? "" : ", ") + std::string(n);
  throw InputError("unknown fault '" + name + "' (known: " + list + ")");
}

std::string describe(const Fault& f) {
  std::ostringstream os;
  os.precision(12);
  os << toString(f.type) << "@" << f.joint << "=" << f.value;
  return os.str();
}

void applyFault(DriveSpec& d, const Fault& f) {
  if (!std::isfinite(f.value)) throw InputError("fault " + describe(f) + ": value must be finite");
  const bool factor = f.type != FaultType::BacklashAdd && f.type != FaultType::SensorBias;
  if (factor && !(f.value > 0.0)) throw InputError("fault " + describe(f) + ": the factor must be > 0");
  if (f.type == FaultType::BacklashAdd && !(f.value >= 0.0))
    throw InputError("fault " + describe(f) + ": the added backlash must be >= 0 rad");
  switch (f.type) {
    case FaultType::GearStiffnessScale:
    case FaultType::BacklashAdd: transmissionFault(d, f); break;
    case FaultType::CoulombFrictionScale:
    case FaultType::Sigma0Scale: frictionFault(d, f); break;
    case FaultType::TorqueConstantScale:
      if (!d.electrics) notApplicable(f, "a torque-controlled motor without electrics (k_t and k_e are not used)");
      d.motor.kt *= f.value;
      d.motor.ke *= f.value;
      break;
    case FaultType::SensorBias:
      if (d.controller.type != control::ControllerType::Cascade002)
        notApplicable(f, "a drive whose controller does not read the joint angle (only cascade_002 does)");
      d.sensors.joint_bias += f.value;
      break;
  }
}

void applyFaults(std::vector<DriveSpec>& drives, const std::vector<Fault>& faults) {
  for (const auto& f : faults) {
    bool found = false;
    for (auto& d : drives)
      if (d.joint == f.joint) {
        applyFault(d, f);
        found = true;
      }
    if (!found) throw InputError("fault " + describe(f) + ": no drive moves joint '" + f.joint + "'");
  }
}

}  // namespace jointsim::systems
