// Robot-with-drives files: the multibody description plus one drive per joint (format in the header).
#include "jointsim/systems/robot_with_drives.hpp"

#include <algorithm>
#include <utility>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/drive_yaml.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::systems {

using io::YamlValue;

namespace {

control::JointControllerParams readController(const YamlValue& node) {
  control::JointControllerParams p;
  if (!node.defined()) return p;
  node.expectMap("a controller mapping {type, gains...}");
  const YamlValue type = node.required("type", "voltage_cascade, torque_cascade or none");
  const std::string t = type.asString("a controller type");
  // The names of earlier versions, numbered after the internal list of the source papers' models.
  if (t == "cascade_002" || t == "motor_ppi_000")
    type.fail("controller type '" + t + "' was renamed: use '" +
              (t == "cascade_002" ? "voltage_cascade" : "torque_cascade") + "' (the same controller and gains)");
  auto gain = [&](const char* key, const std::string& unit) {
    const YamlValue g = node.required(key, std::string("gain in ") + unit);
    const double v = g.asDouble("a gain in " + unit);
    if (!(v >= 0.0)) g.failExpected("a gain >= 0 " + unit + " (negative gains destabilise the loop)");
    return v;
  };
  if (t == "voltage_cascade") {
    node.allowKeys({"type", "P_pos", "P_vel", "I_vel", "P_cur", "I_cur"});
    p.type = control::ControllerType::VoltageCascade;
    p.P_pos = gain("P_pos", "1/s");
    p.P_vel = gain("P_vel", "A·s/rad");
    p.I_vel = gain("I_vel", "A/rad");
    p.P_cur = gain("P_cur", "V/A");
    p.I_cur = gain("I_cur", "V/(A·s)");
  } else if (t == "torque_cascade") {
    node.allowKeys({"type", "kp", "ks", "Ts"});
    p.type = control::ControllerType::TorqueCascade;
    p.kp = gain("kp", "1/s");
    p.ks = gain("ks", "N·m·s/rad");
    const YamlValue ts = node.required("Ts", "PI time constant in s");
    p.Ts = ts.asDouble("a time constant in s");
    if (!(p.Ts > 0)) ts.failExpected("a time constant > 0 s");
  } else if (t == "none") {
    node.allowKeys({"type"});
  } else {
    type.failExpected("voltage_cascade, torque_cascade or none");
  }
  return p;
}

}  // namespace

const std::vector<std::string>& driveComponents() {
  static const std::vector<std::string> names{"motor", "transmission", "friction", "sensors"};
  return names;
}

namespace {

/// The sensors' parameter table (the drive file's `sensors` keys), each row with the field it reads and writes.
std::vector<std::pair<drive::ParameterInfo, double SensorSpec::*>> sensorRows() {
  using R = drive::ParameterRange;
  const auto none = drive::ParameterRole::None;
  return {{{"joint_bias", "rad", 0.0, R{}, none, "constant offset of the measured joint angle"},
           &SensorSpec::joint_bias},
          {{"joint_quantum", "rad", 0.0, R::nonNegative(), none, "joint encoder resolution (0: none)"},
           &SensorSpec::joint_quantum},
          {{"motor_quantum", "rad", 0.0, R::nonNegative(), none,
            "motor encoder resolution (0: none; > 0: speed = Δ(quantised angle)/T_s)"},
           &SensorSpec::motor_quantum},
          {{"current_quantum", "A", 0.0, R::nonNegative(), none, "current sensor resolution (0: none)"},
           &SensorSpec::current_quantum},
          {{"joint_noise", "rad", 0.0, R::nonNegative(), none, "std of Gaussian noise on the joint angle"},
           &SensorSpec::joint_noise},
          {{"motor_velocity_noise", "rad/s", 0.0, R::nonNegative(), none, "std of Gaussian noise on the motor speed"},
           &SensorSpec::motor_velocity_noise},
          {{"current_noise", "A", 0.0, R::nonNegative(), none, "std of Gaussian noise on the current"},
           &SensorSpec::current_noise}};
}

}  // namespace

std::vector<drive::ParameterInfo> driveParameterTable(const DriveSpec& d, const std::string& component) {
  if (component == "motor") return drive::parameterTable(d.motor);
  if (component == "transmission")
    return d.transmission ? d.transmission->parameters() : std::vector<drive::ParameterInfo>{};
  if (component == "friction") return d.friction ? d.friction->parameters() : std::vector<drive::ParameterInfo>{};
  if (component == "sensors") {
    std::vector<drive::ParameterInfo> table;
    for (auto [info, field] : sensorRows()) {
      info.value = d.sensors.*field;
      table.push_back(info);
    }
    return table;
  }
  throw InputError("drive of joint '" + d.joint + "': no component '" + component +
                   "' (expected motor, transmission, friction or sensors)");
}

void applyDriveParameters(std::vector<DriveSpec>& drives, const std::vector<DriveParameterChange>& changes) {
  for (const DriveParameterChange& c : changes) {
    const std::string at = c.where.empty() ? std::string() : c.where + ": ";
    DriveSpec* d = nullptr;
    for (auto& x : drives)
      if (x.joint == c.joint) d = &x;
    try {
      if (d == nullptr) {
        std::string joints;
        for (const auto& x : drives) joints += (joints.empty() ? "" : ", ") + x.joint;
        throw InputError("no drive of joint '" + c.joint + "' (the drives: " + joints + ")");
      }
      const drive::ParameterChanges one{{c.key, c.value}};
      if (c.component == "motor") {
        d->motor = drive::withParameters(d->motor, one);
      } else if (c.component == "transmission") {
        d->transmission = d->transmission->withParameters(one);
      } else if (c.component == "friction") {
        if (!d->friction) throw InputError("the drive of joint '" + c.joint + "' has no friction");
        d->friction = d->friction->withParameters(one);
      } else if (c.component == "sensors") {
        const auto rows = sensorRows();
        const auto row = std::find_if(rows.begin(), rows.end(), [&](const auto& r) { return r.first.key == c.key; });
        if (row == rows.end()) {
          std::string keys;
          for (const auto& r : rows) keys += (keys.empty() ? "" : ", ") + r.first.key;
          throw InputError("sensors: no parameter '" + c.key + "' (the parameters: " + keys + ")");
        }
        if (!row->first.range.contains(c.value))
          throw InputError("sensors: " + c.key + " = " + formatNumber(c.value) + " " + row->first.unit +
                           " is outside its range " + row->first.range.text());
        d->sensors.*(row->second) = c.value;
      } else {
        throw InputError("no component '" + c.component + "' (expected motor, transmission, friction or sensors)");
      }
    } catch (const InputError& e) {
      throw InputError(at + e.what());
    }
  }
}

RobotSystem loadRobotWithDrives(const std::string& path, const std::vector<Fault>& faults,
                                const std::vector<DriveParameterChange>& changes) {
  const YamlValue root = YamlValue::loadFile(path);
  root.expectMap("a robot-with-drives mapping {name, multibody, drives, coupling}");
  root.allowKeys({"name", "multibody", "drives", "coupling"});
  const YamlValue mb = root.required("multibody", "multibody description file, relative to this file");
  multibody::Model model;
  try {
    model = multibody::loadRobot(mb.asPath());
  } catch (const InputError& e) {
    mb.fail(std::string("cannot load the multibody description: ") + e.what());
  }
  if (root.has("name")) model.name = root["name"].asString("a robot name");
  const YamlValue drives = root.required("drives", "one drive per joint");
  drives.expectSequence("a list of drives");
  std::vector<DriveSpec> specs;
  std::vector<std::string> named;
  for (size_t k = 0; k < drives.size(); ++k) {
    const YamlValue d = drives.at(k);
    d.expectMap("a drive mapping {joint, motor, electrics, transmission, friction, controller}");
    d.allowKeys({"joint", "motor", "electrics", "transmission", "friction", "controller", "sensors"});
    DriveSpec s;
    const YamlValue joint = d.required("joint", "name of the joint this drive moves");
    s.joint = joint.asString("a joint name");
    try {
      model.jointIndex(s.joint);
    } catch (const InputError& e) {
      joint.fail(e.what());
    }
    for (const auto& n : named)
      if (n == s.joint) joint.fail("joint '" + s.joint + "' has two drives");
    named.push_back(s.joint);
    s.motor = drive::motorFromYaml(d.required("motor", "motor parameters"));
    s.transmission = drive::transmissionFromYaml(d.required("transmission", "the transmission"));
    if (d.has("friction")) s.friction = drive::frictionFromYaml(d["friction"]);
    s.controller = readController(d["controller"]);
    if (const YamlValue sn = d["sensors"]; sn.defined()) {
      sn.expectMap(
          "a sensors mapping {joint_quantum, motor_quantum, current_quantum, joint_noise, motor_velocity_noise, current_noise}");
      sn.allowKeys({"joint_quantum", "motor_quantum", "current_quantum", "joint_noise", "motor_velocity_noise",
                    "current_noise", "joint_bias"});
      s.sensors.joint_bias = sn["joint_bias"].asDouble(0.0, "a joint-angle bias in rad");
      auto nonneg = [&](const char* key, const char* unit) {
        const double v = sn[key].asDouble(0.0, std::string("a value in ") + unit);
        if (v < 0.0) sn[key].failExpected(std::string("a value >= 0 ") + unit);
        return v;
      };
      s.sensors.joint_quantum = nonneg("joint_quantum", "rad");
      s.sensors.motor_quantum = nonneg("motor_quantum", "rad");
      s.sensors.current_quantum = nonneg("current_quantum", "A");
      s.sensors.joint_noise = nonneg("joint_noise", "rad");
      s.sensors.motor_velocity_noise = nonneg("motor_velocity_noise", "rad/s");
      s.sensors.current_noise = nonneg("current_noise", "A");
    }
    s.electrics = d.has("electrics") ? d["electrics"].asBool("true or false")
                                     : s.controller.type == control::ControllerType::VoltageCascade;
    specs.push_back(std::move(s));
  }
  for (const auto& jn : model.joint_names) {
    bool found = false;
    for (const auto& n : named) found = found || n == jn;
    if (!found) drives.fail("joint '" + jn + "' has no drive (expected one drive per joint of " + model.name + ")");
  }
  Eigen::MatrixXd G;
  if (const YamlValue c = root["coupling"]; c.defined()) {
    c.expectSequence("an n×n matrix as a list of rows");
    const auto n = static_cast<size_t>(model.nq);
    if (c.size() != n) c.failExpected(std::to_string(n) + " rows");
    G.resize(model.nq, model.nq);
    for (size_t r = 0; r < n; ++r) {
      const auto row = c.at(r).asDoubles(n, "a row of " + std::to_string(n) + " numbers");
      for (size_t col = 0; col < n; ++col) G(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(col)) = row[col];
    }
  }
  applyDriveParameters(specs, changes);  // InputError names where the change was given
  applyFaults(specs, faults);            // the constant ones; InputError names the fault
  std::vector<Fault> during;
  for (const Fault& f : faults)
    if (f.timeVarying()) during.push_back(f);
  try {
    RobotSystem robot(std::move(model), std::move(specs), G);
    if (!during.empty()) robot.setFaults(std::move(during));
    return robot;
  } catch (const InputError& e) {
    root.relocate(e);
  }
}

}  // namespace jointsim::systems
