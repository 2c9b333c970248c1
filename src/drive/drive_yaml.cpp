// YAML readers of the drive components that have no file of their own: motor and transmission blocks.
#include "jointsim/drive/drive_yaml.hpp"

#include "jointsim/common/error.hpp"
#include "jointsim/drive/transmissions.hpp"

namespace jointsim::drive {

using io::YamlValue;

DcMotorParams motorFromYaml(const YamlValue& node) {
  node.expectMap("a motor mapping {preset, R, L, kt, ke, J_M, V_supply}");
  node.allowKeys({"preset", "R", "L", "kt", "ke", "J_M", "V_supply"});
  DcMotorParams p;
  if (node.has("preset")) {
    const std::string preset = node["preset"].asString("ur5_joint1 .. ur5_joint6");
    if (preset.size() == 10 && preset.rfind("ur5_joint", 0) == 0 && preset[9] >= '1' && preset[9] <= '6')
      p = DcMotorParams::ur5(preset[9] - '0');
    else
      node["preset"].failExpected("ur5_joint1 .. ur5_joint6");
  } else {
    for (const char* key : {"R", "L", "kt"}) node.required(key, "motor parameter (or a preset)");
  }
  p.R = node["R"].asDouble(p.R, "a resistance in Ω");
  p.L = node["L"].asDouble(p.L, "an inductance in H");
  const bool kt_given = node.has("kt");
  p.kt = node["kt"].asDouble(p.kt, "a torque constant in N·m/A");
  p.ke = node["ke"].asDouble(kt_given ? p.kt : p.ke, "a back-EMF constant in V·s/rad");
  p.J_M = node["J_M"].asDouble(p.J_M, "a rotor inertia in kg·m²");
  p.V_supply = node["V_supply"].asDouble(p.V_supply, "a supply voltage in V");
  node.validate([&] { p.validate(); });
  return p;
}

namespace {
ComplianceSide readSide(const YamlValue& node) {
  const std::string s = node.asString("motor", "motor or output");
  if (s == "motor") return ComplianceSide::Motor;
  if (s == "output") return ComplianceSide::Output;
  node.failExpected("motor or output");
}
}  // namespace

std::shared_ptr<const Transmission> transmissionFromYaml(const YamlValue& node) {
  node.expectMap("a transmission mapping {type, ...}");
  const YamlValue type = node.required("type", "rigid, elastic, elasto_backlash or strain_wave_gear");
  const std::string t = type.asString("a transmission type");
  try {
    if (t == "rigid") {
      node.allowKeys({"type", "ratio"});
      return std::make_shared<RigidGear>(node["ratio"].asDouble(1.0, "a ratio q_in/q_out"));
    }
    if (t == "elastic") {
      node.allowKeys({"type", "ratio", "stiffness", "damping", "side"});
      ElasticGearParams p;
      p.ratio = node["ratio"].asDouble(1.0, "a ratio q_in/q_out");
      p.stiffness = node.required("stiffness", "c in N·m/rad").asDouble("a stiffness in N·m/rad");
      p.damping = node["damping"].asDouble(0.0, "a damping in N·m·s/rad");
      p.side = readSide(node["side"]);
      return std::make_shared<ElasticGear>(p);
    }
    if (t == "elasto_backlash") {
      node.allowKeys({"type", "ratio", "stiffness", "damping", "backlash", "side"});
      ElastoBacklashParams p;
      p.ratio = node["ratio"].asDouble(1.0, "a ratio q_in/q_out");
      p.stiffness = node.required("stiffness", "c in N·m/rad").asDouble("a stiffness in N·m/rad");
      p.damping = node["damping"].asDouble(0.0, "a damping in N·m·s/rad");
      p.backlash = node.required("backlash", "total backlash b in rad").asDouble("a backlash in rad");
      p.side = readSide(node["side"]);
      return std::make_shared<ElastoBacklash>(p);
    }
    if (t == "strain_wave_gear") return std::make_shared<StrainWaveGear>(swgParamsFromYaml(node));
  } catch (const InputError& e) {
    node.relocate(e);
  }
  type.failExpected("rigid, elastic, elasto_backlash or strain_wave_gear");
}

}  // namespace jointsim::drive
