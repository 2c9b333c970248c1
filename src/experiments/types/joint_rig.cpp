// `type: joint_rig`: one drive on a test rig (systems/joint_rig.hpp): clamping benches, friction maps.
#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/drive/drive_yaml.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::experiments {

using io::YamlValue;
using systems::RigInput;
using systems::Side;

systems::JointRigSetup readJointRigSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "motor", "rotor_inertia", "transmission", "friction", "load", "input", "initial_state",
                  "duration", "log_rate", "solver"});
  systems::JointRigSetup s;
  s.name = name;
  if (root.has("motor")) s.motor = drive::motorFromYaml(root["motor"]);
  s.rotor_inertia = root["rotor_inertia"].asDouble(s.rotor_inertia, "a rotor inertia in kg·m²");
  if (!(s.rotor_inertia > 0.0)) root["rotor_inertia"].failExpected("a rotor inertia > 0 kg·m²");
  if (root.has("motor") && root.has("rotor_inertia"))
    root["rotor_inertia"].fail("give the rotor inertia as motor.J_M when a motor block is present");
  s.transmission = drive::transmissionFromYaml(root.required("transmission", "the transmission"));
  if (const YamlValue f = root["friction"]; f.defined()) {
    f.expectMap("a friction mapping {side, model}");
    f.allowKeys({"side", "model"});
    const std::string side = f["side"].asString("motor", "motor or output");
    if (side == "motor")
      s.friction_side = systems::Side::Motor;
    else if (side == "output")
      s.friction_side = systems::Side::Output;
    else
      f["side"].failExpected("motor or output");
    s.friction = drive::frictionFromYaml(f.required("model", "friction model {type, ...}"));
  }
  if (const YamlValue load = root["load"]; load.defined()) {
    load.expectMap("a load mapping {clamped, inertia, damping, torque}");
    load.allowKeys({"clamped", "inertia", "damping", "torque"});
    s.clamped = load.has("clamped") && load["clamped"].asBool("true or false");
    s.load_inertia = load["inertia"].asDouble(s.load_inertia, "an inertia in kg·m²");
    if (!(s.load_inertia > 0.0)) load["inertia"].failExpected("an inertia > 0 kg·m²");
    s.load_damping = load["damping"].asDouble(0.0, "a damping in N·m·s/rad");
    if (!(s.load_damping >= 0.0)) load["damping"].failExpected("a damping >= 0 N·m·s/rad");
    if (const YamlValue torque = load["torque"]; torque.defined()) {
      if (s.clamped) torque.fail("a clamped output takes no load torque; remove load.torque or load.clamped");
      s.load_torque = readProfile(torque, "N·m");
    }
  }
  const YamlValue input = root.required("input", "the input {type, profile, controller}");
  input.expectMap("an input mapping {type, profile, controller}");
  input.allowKeys({"type", "profile", "controller"});
  const YamlValue itype = input.required("type", "torque, voltage or velocity_pi");
  const std::string it = itype.asString("an input type");
  std::string unit = "N·m";
  if (it == "torque") {
    s.input = systems::RigInput::MotorTorque;
  } else if (it == "voltage") {
    s.input = systems::RigInput::Voltage;
    unit = "V";
  } else if (it == "velocity_pi") {
    s.input = systems::RigInput::VelocityPI;
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
    s.pi.measure = m == "motor" ? systems::Side::Motor : systems::Side::Output;
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
  root.validate([&] { s.validate(); });
  return s;
}

namespace {

class JointRigExperiment : public PlantExperiment<systems::JointRig> {
 public:
  using PlantExperiment::PlantExperiment;
  std::string keyUnit(const std::string& key) const override {
    const systems::JointRigSetup& s = plant_.setup();
    auto after = [&](const char* prefix) {
      const std::string p = prefix;
      return key.rfind(p, 0) == 0 ? key.substr(p.size()) : std::string();
    };
    if (const std::string k = after("motor."); !k.empty())
      return s.motor ? detail::tableKeyUnit(drive::parameterTable(*s.motor), k) : std::string();
    if (const std::string k = after("transmission."); !k.empty()) {
      const auto table = s.transmission->parameters();
      if (k == "alpha_t_deg") return "deg";
      if (k == "Z_FS" || k == "Z_CS") return "1";
      if (k == "damping.value") {  // every c_*: a unit when they share one (damping ratios)
        std::string unit;
        for (const auto& p : table)
          if (p.key.rfind("c_", 0) == 0) {
            if (!unit.empty() && unit != p.unit) return {};
            unit = p.unit;
          }
        return unit;
      }
      return detail::tableKeyUnit(table, k);
    }
    if (const std::string k = after("friction.model."); !k.empty())
      return s.friction ? detail::tableKeyUnit(s.friction->parameters(), k) : std::string();
    const std::string u = s.input == RigInput::MotorTorque ? "N·m" : s.input == RigInput::Voltage ? "V" : "rad/s";
    const std::string out = s.pi.voltage_output ? "V" : "N·m";
    const std::pair<std::string, std::string> units[] = {{"rotor_inertia", "kg·m²"},
                                                         {"load.inertia", "kg·m²"},
                                                         {"load.damping", "N·m·s/rad"},
                                                         {"initial_state.motor_angle", "rad"},
                                                         {"initial_state.output_angle", "rad"},
                                                         {"initial_state.motor_velocity", "rad/s"},
                                                         {"initial_state.output_velocity", "rad/s"},
                                                         {"input.controller.kp", out + "·s/rad"},
                                                         {"input.controller.ki", out + "/rad"},
                                                         {"input.controller.limit", out}};
    const std::string p = detail::keyPattern(key);
    for (const auto& [k, unit] : units)
      if (p == k) return unit;
    if (const std::string k = detail::profileKeyUnit(p, "input.profile.", u); !k.empty()) return k;
    if (const std::string k = detail::profileKeyUnit(p, "load.torque.", "N·m"); !k.empty()) return k;
    return detail::commonKeyUnit(key);
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult&) const override {
    const systems::JointRigSetup& s = plant_.setup();
    if (s.motor) {
      w["motor"] = {{"R", s.motor->R},   {"L", s.motor->L},     {"kt", s.motor->kt},
                    {"ke", s.motor->ke}, {"J_M", s.motor->J_M}, {"V_supply", s.motor->V_supply}};
    } else {
      w["rotor_inertia"] = s.rotor_inertia;
    }
    w["transmission"] = {{"type", s.transmission->type()},
                         {"ratio", s.transmission->ratio()},
                         {"states", s.transmission->stateNames()}};
    if (s.friction)
      w["friction"] = {{"type", s.friction->type()}, {"side", s.friction_side == Side::Motor ? "motor" : "output"}};
    else
      w["friction"] = nullptr;
    w["load"] = {{"clamped", s.clamped}, {"inertia", s.load_inertia}, {"damping", s.load_damping}};
    if (s.load_torque) w["load"]["torque"] = s.load_torque->describe();
    auto& in = w["input"];
    in["type"] = s.input == RigInput::MotorTorque ? "torque" : s.input == RigInput::Voltage ? "voltage" : "velocity_pi";
    in["profile"] = s.profile.describe();
    if (s.input == RigInput::VelocityPI) {
      in["kp"] = s.pi.kp;
      in["ki"] = s.pi.ki;
      in["limit"] = s.pi.limit;
      in["output"] = s.pi.voltage_output ? "voltage" : "torque";
      in["measure"] = s.pi.measure == Side::Motor ? "motor" : "output";
    }
    w["state_size"] = plant_.stateSize();
    w["duration"] = s.duration;
    w["log_rate"] = s.log_rate;
    solverJson(w["solver"], s.solver);
  }
};

/// Mean friction torque and velocity over the settled end (last 30 %) of each constant, non-zero plateau of
/// the velocity reference: the steady-state points of the static friction map.
std::vector<std::array<double, 2>> plateauMeans(const RunData& run, int ref, int vel, int fric) {
  std::vector<std::array<double, 2>> points;
  const auto& d = run.data;
  Eigen::Index start = 0;
  for (Eigen::Index i = 1; i <= d.rows(); ++i) {
    if (i < d.rows() && d(i, ref) == d(start, ref)) continue;
    const Eigen::Index n = i - start;
    if (d(start, ref) != 0 && n >= 10) {
      const Eigen::Index from = start + (n * 7) / 10;
      const Eigen::Index m = i - from;
      points.push_back({d.col(vel).segment(from, m).mean(), d.col(fric).segment(from, m).mean()});
    }
    start = i;
  }
  return points;
}

bool isClamped(const RunData& run) {
  const int oa = run.col("output_angle");
  const std::string clamped = run.param({"parameters", "load", "clamped"});
  return clamped == "true" || (clamped.empty() && (oa < 0 || run.maxAbs(oa) == 0));
}

std::vector<Figure> jointRigFigures(const RunData& run) {
  std::vector<Figure> figs;
  auto cols = [&](std::initializer_list<const char*> names) {
    std::vector<int> out;
    for (const char* n : names)
      if (run.col(n) >= 0) out.push_back(run.col(n));
    return out;
  };
  Figure f{run.experiment + "_signals", run.experiment + ": drive signals", 1, 1, {}};
  const auto angles = cols({"motor_angle", "output_angle"});
  const auto speeds = cols({"motor_velocity", "output_velocity", "reference_velocity"});
  const auto torques =
      cols({"motor_torque", "command_torque", "transmission_torque_in", "transmission_torque_out", "friction_torque"});
  const auto electric = cols({"motor_current", "motor_voltage"});
  if (!angles.empty()) f.panels.push_back(timePanel(run, angles, "angles", "angle"));
  if (!speeds.empty()) f.panels.push_back(timePanel(run, speeds, "velocities", "velocity"));
  if (!torques.empty()) f.panels.push_back(timePanel(run, torques, "torques", "torque"));
  if (!electric.empty()) {
    Panel p = timePanel(run, electric, "motor electrics", "current");
    p.ylabel = axisLabel("motor current", run.unit(electric.front()));
    if (electric.size() == 2) {
      p.series[1].y2 = true;
      p.y2label = axisLabel("motor voltage", run.unit(electric[1]));
    }
    f.panels.push_back(p);
  }
  for (auto& p : f.panels) p.auto_y2 = true;
  grid(f, f.panels.size(), f.panels.size() == 4 ? 2 : 1);
  if (!f.panels.empty()) figs.push_back(f);

  const int ma = run.col("motor_angle"), mt = run.col("motor_torque");
  const int ov = run.col("output_velocity"), mv = run.col("motor_velocity"), ft = run.col("friction_torque");
  const int rv = run.col("reference_velocity");
  // A clamped rig: the clamping curve (motor torque against motor angle).
  const bool clamped = isClamped(run);
  if (clamped && ma >= 0 && mt >= 0) {
    Figure c{run.experiment + "_clamping_curve", run.experiment + ": clamping curve", 1, 1, {}};
    Panel p;
    p.title = "motor torque against motor angle (output clamped)";
    p.xlabel = axisLabel("motor angle", run.unit(ma));
    p.ylabel = axisLabel("torque", run.unit(mt));
    p.time_axis = false;
    p.key = Key::top_left;
    p.series.push_back(xySeries(run, ma, mt, "motor torque"));
    const int ti = run.col("transmission_torque_in");
    if (ti >= 0) p.series.push_back(xySeries(run, ma, ti, "transmission torque (motor side)", LineStyle::Dashed));
    c.panels.push_back(p);
    figs.push_back(c);
  }
  // A velocity-controlled rig with friction: the friction map (friction torque against velocity on the
  // friction side), every sample plus the steady state of each reference plateau.
  const std::string input = run.param({"parameters", "input", "type"});
  const bool velocity_input = input == "velocity_pi" || (input.empty() && rv >= 0);
  if (velocity_input && ft >= 0 && !clamped) {
    const std::string side = run.param({"parameters", "friction", "side"});
    const int v = (side == "motor" || ov < 0) ? mv : ov;
    if (v >= 0) {
      Figure m{run.experiment + "_friction_map", run.experiment + ": friction map", 1, 1, {}};
      Panel p;
      p.title = "friction torque against " + run.name(v);
      p.xlabel = axisLabel(run.name(v), run.unit(v));
      p.ylabel = axisLabel("friction torque", run.unit(ft));
      p.time_axis = false;
      p.key = Key::top_left;
      p.series.push_back(xySeries(run, v, ft, "all samples", LineStyle::Samples));
      if (rv >= 0) {
        Series s;
        s.points = plateauMeans(run, rv, v, ft);
        s.title = "steady state of each velocity plateau";
        s.style = LineStyle::Markers;
        if (!s.points.empty()) p.series.push_back(s);
      }
      m.panels.push_back(p);
      figs.push_back(m);
    }
  }
  return figs;
}

std::optional<KeySignal> jointRigKeySignal(const RunData& run) {
  const int ma = run.col("motor_angle"), mt = run.col("motor_torque");
  if (isClamped(run) && ma >= 0 && mt >= 0) {
    KeySignal k;
    k.x = "motor_angle";
    k.y = "motor_torque";
    k.xlabel = axisLabel("motor angle", run.unit(ma));
    k.ylabel = axisLabel("motor torque", run.unit(mt));
    k.what = "clamping curve";
    return k;
  }
  for (const char* n : {"output_velocity", "motor_velocity"})
    if (run.col(n) >= 0) return timeKeySignal(run, run.col(n), n);
  return std::nullopt;
}

}  // namespace

namespace {

/// A constant parameter fault on the rig's drive, named `rig` (systems/faults.hpp): the drive's components through
/// their parameter tables, as for a robot with drives (applyFault on a drive made of the rig's components).
void applyRigFault(systems::JointRigSetup& s, const systems::Fault& f) {
  const std::string what = "fault " + systems::describe(f) + ": ";
  if (f.joint != "rig") throw InputError(what + "a joint rig's drive is called 'rig', not '" + f.joint + "'");
  if (!f.parameterFault() || f.type == systems::FaultType::SensorBias)
    throw InputError(what + "does not apply to a joint rig (" + systems::toString(f.type) +
                     " needs the sensors and controllers of a robot with drives, experiment type tracking)");
  if (f.timeVarying())
    throw InputError(what + "does not apply to a joint rig with a time law (it takes constant faults, acting from "
                            "t = 0; onsets and progressions need a robot with drives, experiment type tracking)");
  systems::DriveSpec d;
  d.joint = "rig";
  d.electrics = s.motor.has_value();
  if (s.motor) d.motor = *s.motor;
  d.transmission = s.transmission;
  d.friction = s.friction;
  systems::applyFault(d, f);  // InputError naming the fault when the components have no parameter of its role
  s.transmission = d.transmission;
  s.friction = d.friction;
  if (s.motor) s.motor = d.motor;
}

}  // namespace

ExperimentType jointRigExperimentType() {
  ExperimentType t;
  t.name = "joint_rig";
  t.description = "one drive (motor, transmission, friction) on a test rig: clamping bench, friction map, steps";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    systems::JointRigSetup s = readJointRigSetup(root, c.name);
    for (const systems::Fault& f : c.faults) applyRigFault(s, f);
    return std::make_unique<JointRigExperiment>(std::move(s));
  };
  t.accepts_faults = true;
  t.figures = jointRigFigures;
  t.key_signal = jointRigKeySignal;
  return t;
}

}  // namespace jointsim::experiments
