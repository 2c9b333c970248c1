#include "experiments/joint_rig_yaml.hpp"

#include <filesystem>

#include "experiments/config_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/drive/transmissions.hpp"

namespace jointsim::experiments::detail {

using io::YamlValue;

drive::DcMotorParams readMotor(const YamlValue& node) {
  node.expectMap("a motor mapping {preset, R, L, kt, ke, J_M, V_supply}");
  node.allowKeys({"preset", "R", "L", "kt", "ke", "J_M", "V_supply"});
  drive::DcMotorParams p;
  if (node.has("preset")) {
    const std::string preset = node["preset"].asString("ur5_joint1 .. ur5_joint6");
    if (preset.size() == 10 && preset.rfind("ur5_joint", 0) == 0 && preset[9] >= '1' && preset[9] <= '6')
      p = drive::DcMotorParams::ur5(preset[9] - '0');
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
  try {
    p.validate();
  } catch (const InputError& e) {
    node.fail(e.what());
  }
  return p;
}

namespace {
drive::ComplianceSide readSide(const YamlValue& node) {
  const std::string s = node.asString("motor", "motor or output");
  if (s == "motor") return drive::ComplianceSide::Motor;
  if (s == "output") return drive::ComplianceSide::Output;
  node.failExpected("motor or output");
}
}  // namespace

std::shared_ptr<const drive::Transmission> readTransmission(const YamlValue& node) {
  node.expectMap("a transmission mapping {type, ...}");
  const YamlValue type = node.required("type", "rigid, elastic, elasto_backlash or strain_wave_gear");
  const std::string t = type.asString("a transmission type");
  try {
    if (t == "rigid") {
      node.allowKeys({"type", "ratio"});
      return std::make_shared<drive::RigidGear>(node["ratio"].asDouble(1.0, "a ratio q_in/q_out"));
    }
    if (t == "elastic") {
      node.allowKeys({"type", "ratio", "stiffness", "damping", "side"});
      drive::ElasticGearParams p;
      p.ratio = node["ratio"].asDouble(1.0, "a ratio q_in/q_out");
      p.stiffness = node.required("stiffness", "c in N·m/rad").asDouble("a stiffness in N·m/rad");
      p.damping = node["damping"].asDouble(0.0, "a damping in N·m·s/rad");
      p.side = readSide(node["side"]);
      return std::make_shared<drive::ElasticGear>(p);
    }
    if (t == "elasto_backlash") {
      node.allowKeys({"type", "ratio", "stiffness", "damping", "backlash", "side"});
      drive::ElastoBacklashParams p;
      p.ratio = node["ratio"].asDouble(1.0, "a ratio q_in/q_out");
      p.stiffness = node.required("stiffness", "c in N·m/rad").asDouble("a stiffness in N·m/rad");
      p.damping = node["damping"].asDouble(0.0, "a damping in N·m·s/rad");
      p.backlash = node.required("backlash", "total backlash b in rad").asDouble("a backlash in rad");
      p.side = readSide(node["side"]);
      return std::make_shared<drive::ElastoBacklash>(p);
    }
    if (t == "strain_wave_gear") return readStrainWaveGear(node);
  } catch (const InputError& e) {
    if (std::string(e.what()).rfind(node.file(), 0) == 0) throw;
    node.fail(e.what());
  }
  type.failExpected("rigid, elastic, elasto_backlash or strain_wave_gear");
}

JointRigSetup readJointRig(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "motor", "rotor_inertia", "transmission", "friction", "load", "input",
                  "initial_state", "duration", "log_rate", "solver"});
  JointRigSetup s;
  s.name = name;
  if (root.has("motor")) s.motor = readMotor(root["motor"]);
  s.rotor_inertia = root["rotor_inertia"].asDouble(s.rotor_inertia, "a rotor inertia in kg·m²");
  if (!(s.rotor_inertia > 0.0)) root["rotor_inertia"].failExpected("a rotor inertia > 0 kg·m²");
  if (root.has("motor") && root.has("rotor_inertia"))
    root["rotor_inertia"].fail("give the rotor inertia as motor.J_M when a motor block is present");
  s.transmission = readTransmission(root.required("transmission", "the transmission"));
  if (const YamlValue f = root["friction"]; f.defined()) {
    f.expectMap("a friction mapping {side, model}");
    f.allowKeys({"side", "model"});
    const std::string side = f["side"].asString("motor", "motor or output");
    if (side == "motor") s.friction_side = Side::Motor;
    else if (side == "output") s.friction_side = Side::Output;
    else f["side"].failExpected("motor or output");
    s.friction = readFrictionModel(f.required("model", "friction model {type, ...}"));
  }
  if (const YamlValue load = root["load"]; load.defined()) {
    load.expectMap("a load mapping {clamped, inertia, damping}");
    load.allowKeys({"clamped", "inertia", "damping"});
    s.clamped = load.has("clamped") && load["clamped"].asBool("true or false");
    s.load_inertia = load["inertia"].asDouble(s.load_inertia, "an inertia in kg·m²");
    if (!(s.load_inertia > 0.0)) load["inertia"].failExpected("an inertia > 0 kg·m²");
    s.load_damping = load["damping"].asDouble(0.0, "a damping in N·m·s/rad");
    if (!(s.load_damping >= 0.0)) load["damping"].failExpected("a damping >= 0 N·m·s/rad");
  }
  const YamlValue input = root.required("input", "the input {type, profile, controller}");
  input.expectMap("an input mapping {type, profile, controller}");
  input.allowKeys({"type", "profile", "controller"});
  const YamlValue itype = input.required("type", "torque, voltage or velocity_pi");
  const std::string it = itype.asString("an input type");
  std::string unit = "N·m";
  if (it == "torque") {
    s.input = RigInput::MotorTorque;
  } else if (it == "voltage") {
    s.input = RigInput::Voltage;
    unit = "V";
  } else if (it == "velocity_pi") {
    s.input = RigInput::VelocityPI;
    unit = "rad/s";
    const YamlValue c = input.required("controller", "PI gains {kp, ki, limit, output, measure}");
    c.expectMap("a controller mapping {kp, ki, limit, output, measure}");
    c.allowKeys({"kp", "ki", "limit", "output", "measure"});
    s.pi.kp = c.required("kp", "proportional gain").asDouble("a gain");
    s.pi.ki = c.required("ki", "integral gain").asDouble("a gain");
    s.pi.limit = c["limit"].asDouble(s.pi.limit, "an output limit in N·m or V");
    const std::string out = c["output"].asString("torque", "torque or voltage");
    if (out != "torque" && out != "voltage") c["output"].failExpected("torque or voltage");
    s.pi.voltage_output = out == "voltage";
    const std::string m = c["measure"].asString("motor", "motor or output");
    if (m != "motor" && m != "output") c["measure"].failExpected("motor or output");
    s.pi.measure = m == "motor" ? Side::Motor : Side::Output;
  } else {
    itype.failExpected("torque, voltage or velocity_pi");
  }
  s.profile = readProfile(input.required("profile", "the input profile"), unit);
  if (const YamlValue init = root["initial_state"]; init.defined()) {
    init.expectMap("a mapping {motor_angle, motor_velocity, output_angle, output_velocity}");
    init.allowKeys({"motor_angle", "motor_velocity", "output_angle", "output_velocity"});
    s.q_m0 = init["motor_angle"].asDouble(0.0, "an angle in rad");
    s.qd_m0 = init["motor_velocity"].asDouble(0.0, "a velocity in rad/s");
    s.q_l0 = init["output_angle"].asDouble(0.0, "an angle in rad");
    s.qd_l0 = init["output_velocity"].asDouble(0.0, "a velocity in rad/s");
  }
  readDurationAndLogRate(root, s.duration, s.log_rate);
  s.solver = readSolver(root["solver"], s.solver);
  try {
    s.validate();
  } catch (const InputError& e) {
    root.fail(e.what());
  }
  return s;
}

void writeJointRigParameters(io::JsonWriter& w, const JointRig& rig, const YamlValue& root,
                             const std::string& config_path) {
  const JointRigSetup& s = rig.setup();
  w.beginObject();
  w.key("config_file"); w.value(config_path);
  if (s.motor) {
    w.key("motor");
    w.beginObject();
    w.key("R"); w.value(s.motor->R);
    w.key("L"); w.value(s.motor->L);
    w.key("kt"); w.value(s.motor->kt);
    w.key("ke"); w.value(s.motor->ke);
    w.key("J_M"); w.value(s.motor->J_M);
    w.key("V_supply"); w.value(s.motor->V_supply);
    w.endObject();
  } else {
    w.key("rotor_inertia"); w.value(s.rotor_inertia);
  }
  w.key("transmission");
  w.beginObject();
  w.key("type"); w.value(s.transmission->type());
  w.key("ratio"); w.value(s.transmission->ratio());
  w.key("states"); w.beginArray(); for (const auto& n : s.transmission->stateNames()) w.value(n); w.endArray();
  w.endObject();
  w.key("friction");
  if (s.friction) {
    w.beginObject();
    w.key("type"); w.value(s.friction->type());
    w.key("side"); w.value(s.friction_side == Side::Motor ? "motor" : "output");
    w.endObject();
  } else {
    w.null();
  }
  w.key("load");
  w.beginObject();
  w.key("clamped"); w.value(s.clamped);
  w.key("inertia"); w.value(s.load_inertia);
  w.key("damping"); w.value(s.load_damping);
  w.endObject();
  w.key("input");
  w.beginObject();
  w.key("type"); w.value(s.input == RigInput::MotorTorque ? "torque" : s.input == RigInput::Voltage ? "voltage" : "velocity_pi");
  w.key("profile"); w.value(s.profile.describe());
  if (s.input == RigInput::VelocityPI) {
    w.key("kp"); w.value(s.pi.kp);
    w.key("ki"); w.value(s.pi.ki);
    w.key("limit"); w.value(s.pi.limit);
    w.key("output"); w.value(s.pi.voltage_output ? "voltage" : "torque");
    w.key("measure"); w.value(s.pi.measure == Side::Motor ? "motor" : "output");
  }
  w.endObject();
  w.key("state_size"); w.value(rig.stateSize());
  w.key("duration"); w.value(s.duration);
  w.key("log_rate"); w.value(s.log_rate);
  w.key("solver"); writeSolverOptions(w, s.solver);
  w.key("config"); writeYamlAsJson(w, root.node());
  w.endObject();
}

}  // namespace jointsim::experiments::detail
