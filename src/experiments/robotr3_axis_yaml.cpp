// `type: robotr3_axis` experiment files: one RobotR3 axis (type 1) on a 1-D load (MSL OneAxis).
#include "experiments/config_common.hpp"
#include "experiments/tracking_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/robotr3_axis.hpp"

namespace jointsim::experiments::detail {

using io::YamlValue;

RunReport runRobotR3Axis(const YamlValue& root, const std::string& config_path, const std::string& name,
                         const RunOptions& options) {
  root.allowKeys({"experiment", "prefix", "motor", "gear", "controller", "load", "path", "stop_time", "log_interval",
                  "initial_friction_torque", "solver"});
  RobotR3AxisSetup s;
  s.name = name;
  s.prefix = root["prefix"].asString(s.prefix, "a column-name prefix");
  auto num = [](const YamlValue& n, const char* key, double fallback, const std::string& what) {
    return n[key].asDouble(fallback, what);
  };
  if (const YamlValue m = root["motor"]; m.defined()) {
    m.expectMap("a motor mapping {preset, J, k, w, D}");
    m.allowKeys({"preset", "J", "k", "w", "D"});
    if (m.has("preset")) {
      const std::string p = m["preset"].asString("one_axis or robotr3_axis1..6");
      if (p == "one_axis") s.motor = drive::OpAmpMotorParams::oneAxis();
      else if (p.size() == 13 && p.rfind("robotr3_axis", 0) == 0 && p[12] >= '1' && p[12] <= '6')
        s.motor = drive::OpAmpMotorParams::robotR3Axis(p[12] - '0');
      else m["preset"].failExpected("one_axis or robotr3_axis1..6");
    }
    s.motor.J = num(m, "J", s.motor.J, "a rotor inertia in kg·m²");
    s.motor.k = num(m, "k", s.motor.k, "a motor constant in N·m/A");
    s.motor.w = num(m, "w", s.motor.w, "a current-loop frequency in rad/s");
    s.motor.D = num(m, "D", s.motor.D, "a damping ratio");
  }
  if (const YamlValue g = root["gear"]; g.defined()) {
    g.expectMap("a gear mapping {type, ratio, c, d, Rv0, Rv1, peak}");
    g.allowKeys({"type", "ratio", "c", "d", "Rv0", "Rv1", "peak"});
    if (g.has("type") && g["type"].asInt("1 (elastic); type 2 is not modelled yet") != 1)
      g["type"].failExpected("1 (the rigid type 2 is not modelled yet)");
    s.ratio = num(g, "ratio", s.ratio, "a gear ratio");
    s.c = num(g, "c", s.c, "a stiffness in N·m/rad");
    s.d = num(g, "d", s.d, "a damping in N·m·s/rad");
    s.Rv0 = num(g, "Rv0", s.Rv0, "a friction torque in N·m");
    s.Rv1 = num(g, "Rv1", s.Rv1, "a viscous coefficient in N·m·s/rad");
    s.peak = num(g, "peak", s.peak, "a stiction factor >= 1");
  }
  if (const YamlValue c = root["controller"]; c.defined()) {
    c.expectMap("a controller mapping {kp, ks, Ts}");
    c.allowKeys({"kp", "ks", "Ts"});
    s.kp = num(c, "kp", s.kp, "a gain in 1/s");
    s.ks = num(c, "ks", s.ks, "a gain in A·s/rad");
    s.Ts = num(c, "Ts", s.Ts, "a time constant in s");
  }
  if (const YamlValue l = root["load"]; l.defined()) {
    l.expectMap("a load mapping {inertia}");
    l.allowKeys({"inertia"});
    s.load_inertia = num(l, "inertia", s.load_inertia, "an inertia in kg·m²");
  }
  if (const YamlValue p = root["path"]; p.defined()) {
    p.expectMap("a path mapping {q_begin, q_end, qd_max, qdd_max, start_time, swing_time}");
    p.allowKeys({"q_begin", "q_end", "qd_max", "qdd_max", "start_time", "swing_time"});
    s.q_begin = num(p, "q_begin", s.q_begin, "an angle in rad");
    s.q_end = num(p, "q_end", s.q_end, "an angle in rad");
    s.qd_max = num(p, "qd_max", s.qd_max, "a speed in rad/s");
    s.qdd_max = num(p, "qdd_max", s.qdd_max, "an acceleration in rad/s²");
    s.start_time = num(p, "start_time", s.start_time, "a time in s");
    s.swing_time = num(p, "swing_time", s.swing_time, "a time in s");
  }
  s.stop_time = num(root, "stop_time", s.stop_time, "a time in s");
  s.log_interval = num(root, "log_interval", s.log_interval, "an output interval in s");
  s.sa0 = num(root, "initial_friction_torque", s.sa0, "a torque in N·m");
  s.solver = readSolver(root["solver"], s.solver);
  try {
    s.validate();
  } catch (const InputError& e) {
    root.fail(e.what());
  }
  RobotR3Axis axis(s);
  size_t events = 0;
  return runAndRecord(
      name, "robotr3_axis", options, axis.columns(),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        const AxisRunResult r = simulateRobotR3Axis(axis, sink);
        events = r.events;
        return SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
      },
      [&](io::JsonWriter& w) {
        w.beginObject();
        w.key("config_file"); w.value(config_path);
        w.key("end_time"); w.value(axis.endTime());
        w.key("events"); w.value(static_cast<long>(events));
        w.key("solver"); writeSolverOptions(w, s.solver);
        w.key("config"); writeYamlAsJson(w, root.node());
        w.endObject();
      });
}

}  // namespace jointsim::experiments::detail

#include "jointsim/experiments/robotr3_full.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments::detail {

RunReport runRobotR3Full(const YamlValue& root, const std::string& config_path, const std::string& name,
                         const RunOptions& options) {
  root.allowKeys({"experiment", "robot", "axes", "path", "stop_time", "log_interval", "solver"});
  RobotR3FullSetup s;
  s.name = name;
  const YamlValue robot_node = root.required("robot", "multibody description of the arm");
  try {
    s.arm = multibody::loadRobot(robot_node.asPath());
  } catch (const InputError& e) {
    robot_node.fail(std::string("cannot load robot: ") + e.what());
  }
  const YamlValue axes = root.required("axes", "one axis per joint: {preset: robotr3_axis1..6}");
  axes.expectSequence("a list of axes");
  for (size_t k = 0; k < axes.size(); ++k) {
    const YamlValue a = axes.at(k);
    a.expectMap("an axis mapping {preset}");
    a.allowKeys({"preset"});
    const std::string p = a.required("preset", "robotr3_axis1..6").asString("robotr3_axis1..6");
    if (p.size() != 13 || p.rfind("robotr3_axis", 0) != 0 || p[12] < '1' || p[12] > '6') a["preset"].failExpected("robotr3_axis1..6");
    s.axes.push_back(RobotR3AxisParams::fullRobot(p[12] - '0'));
  }
  const YamlValue path = root.required("path", "KinematicPTP2 path {q_begin, q_end, qd_max, qdd_max, start_time, swing_time}");
  path.expectMap("a path mapping");
  path.allowKeys({"q_begin", "q_end", "qd_max", "qdd_max", "start_time", "swing_time"});
  auto vec = [&](const char* key) {
    const auto v = path.required(key, "one value per joint").asDoubles(static_cast<size_t>(s.arm.nq), "one value per joint");
    return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  s.q_begin = vec("q_begin");
  s.q_end = vec("q_end");
  s.qd_max = vec("qd_max");
  s.qdd_max = vec("qdd_max");
  s.start_time = path["start_time"].asDouble(0.0, "a time in s");
  s.swing_time = path["swing_time"].asDouble(0.5, "a time in s");
  s.stop_time = root["stop_time"].asDouble(s.stop_time, "a time in s");
  s.log_interval = root["log_interval"].asDouble(s.log_interval, "an output interval in s");
  s.solver = readSolver(root["solver"], s.solver);
  try {
    s.validate();
  } catch (const InputError& e) {
    root.fail(e.what());
  }
  RobotR3Full robot(s);
  size_t events = 0;
  return runAndRecord(
      name, "robotr3_full", options, robot.columns(),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        const FullRunResult r = simulateRobotR3Full(robot, sink);
        events = r.events;
        return SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
      },
      [&](io::JsonWriter& w) {
        w.beginObject();
        w.key("config_file"); w.value(config_path);
        w.key("end_time"); w.value(robot.endTime());
        w.key("events"); w.value(static_cast<long>(events));
        w.key("state_size"); w.value(robot.stateSize());
        w.key("solver"); writeSolverOptions(w, s.solver);
        w.key("config"); writeYamlAsJson(w, root.node());
        w.endObject();
      },
      robot.endTime());
}

}  // namespace jointsim::experiments::detail
