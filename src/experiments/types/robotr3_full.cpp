// `type: robotr3_full`: the Manutec r3 with six RobotR3 axes ([MSL, RobotR3.FullRobot]; systems/robotr3_full.hpp).
#include <algorithm>

#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {

using io::YamlValue;

systems::RobotR3FullSetup readRobotR3FullSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "robot", "axes", "path", "stop_time", "log_interval", "solver", "energy"});
  systems::RobotR3FullSetup s;
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
    if (p.size() != 13 || p.rfind("robotr3_axis", 0) != 0 || p[12] < '1' || p[12] > '6')
      a["preset"].failExpected("robotr3_axis1..6");
    s.axes.push_back(systems::RobotR3AxisParams::fullRobot(p[12] - '0'));
  }
  const YamlValue path =
      root.required("path", "KinematicPTP2 path {q_begin, q_end, qd_max, qdd_max, start_time, swing_time}");
  path.expectMap("a path mapping");
  path.allowKeys({"q_begin", "q_end", "qd_max", "qdd_max", "start_time", "swing_time"});
  auto vec = [&](const char* key) {
    const auto v =
        path.required(key, "one value per joint").asDoubles(static_cast<size_t>(s.arm.nq), "one value per joint");
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
  s.energy = root["energy"].defined() && root["energy"].asBool("true or false (energy bookkeeping columns)");
  root.validate([&] { s.validate(); });
  return s;
}

namespace {

class RobotR3FullExperiment : public PlantExperiment<systems::RobotR3Full> {
 public:
  using PlantExperiment::PlantExperiment;
  std::optional<ArmKinematics> arm() const override {
    // The column names of [MSL, RobotR3.FullRobot]: mechanics.r<j>.phi, j = 1..6 from the base. A 1-D shaft
    // configuration (load_inertia set) has no arm to draw.
    const systems::RobotR3FullSetup& s = plant_.setup();
    if (s.load_inertia.size() > 0 || !s.one_axis_prefix.empty()) return std::nullopt;
    ArmKinematics a;
    a.model = &s.arm;
    for (int j = 0; j < s.arm.nq; ++j) a.angle_columns.push_back("mechanics.r" + std::to_string(j + 1) + ".phi");
    a.tcp_frame = s.arm.frameIndex(s.arm.tip_frame);
    a.q0 = s.q_begin;
    return a;
  }
  std::string keyUnit(const std::string& key) const override {
    return detail::patternKeyUnit(key, {{"path.q_begin[]", "rad"},
                                        {"path.q_end[]", "rad"},
                                        {"path.qd_max[]", "rad/s"},
                                        {"path.qdd_max[]", "rad/s²"},
                                        {"path.start_time", "s"},
                                        {"path.swing_time", "s"},
                                        {"stop_time", "s"},
                                        {"log_interval", "s"}});
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult& r) const override {
    w["end_time"] = plant_.endTime();
    w["events"] = r.events;
    w["state_size"] = plant_.stateSize();
    solverJson(w["solver"], plant_.setup().solver);
  }
};

std::vector<Figure> robotR3FullFigures(const RunData& run) {
  std::vector<Figure> figs;
  auto matching = [&](const std::string& prefix, const std::string& suffix) {
    return run.where([&](const std::string& n) { return startsWith(n, prefix) && endsWith(n, suffix); });
  };
  auto axisName = [](const std::string& n) { return n.substr(0, n.find('.')); };
  auto jointName = [](const std::string& n) { return "joint " + n.substr(11, n.find('.', 11) - 11); };
  Figure j{run.experiment + "_joints", run.experiment + ": joint motion", 1, 1, {}};
  if (auto c = matching("mechanics.r", ".phi"); !c.empty())
    j.panels.push_back(timePanel(run, c, "joint angles", "joint angle", jointName));
  if (auto c = matching("mechanics.r", ".w"); !c.empty())
    j.panels.push_back(timePanel(run, c, "joint speeds", "joint speed", jointName));
  grid(j, j.panels.size(), 1);
  if (!j.panels.empty()) figs.push_back(j);
  Figure d{run.experiment + "_drives", run.experiment + ": drives", 1, 1, {}};
  if (auto c = matching("axis", ".motor.La.i"); !c.empty())
    d.panels.push_back(timePanel(run, c, "motor currents", "current", axisName));
  if (auto c = matching("axis", ".motor.C.v"); !c.empty())
    d.panels.push_back(timePanel(run, c, "motor voltages (C.v)", "voltage", axisName));
  if (auto c = matching("axis", ".gear.spring.phi_rel"); !c.empty())
    d.panels.push_back(timePanel(run, c, "gear spring deflections", "deflection", axisName));
  if (auto c = matching("axis", ".controller.PI.x"); !c.empty())
    d.panels.push_back(timePanel(run, c, "speed controller PI states", "PI.x", axisName));
  grid(d, d.panels.size(), 2);
  if (!d.panels.empty()) figs.push_back(d);
  return figs;
}

}  // namespace

ExperimentType robotR3FullExperimentType() {
  ExperimentType t;
  t.name = "robotr3_full";
  t.description = "the Manutec r3 arm with six RobotR3 axes on a synchronised path: MSL FullRobot";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    systems::RobotR3FullSetup s = readRobotR3FullSetup(root, c.name);
    // Faults: constant parameter faults on an axis's drive, through its parameter table.
    for (const systems::Fault& f : c.faults) {
      const auto& names = s.arm.joint_names;
      const auto j = static_cast<size_t>(std::find(names.begin(), names.end(), f.joint) - names.begin());
      if (j >= s.axes.size())
        throw InputError("fault " + systems::describe(f) + ": no axis drives joint '" + f.joint + "'");
      const std::string what = "RobotR3 axis " + std::to_string(j + 1) + " (joint '" + f.joint + "')";
      s.axes[j] = s.axes[j].withParameters(systems::tableFaultChanges(s.axes[j].parameters(), f, what), what);
    }
    return std::make_unique<RobotR3FullExperiment>(std::move(s));
  };
  t.accepts_faults = true;
  t.figures = robotR3FullFigures;
  t.key_signal = [](const RunData& run) -> std::optional<KeySignal> {
    return timeKeySignal(run, run.col("mechanics.r1.phi"), "angle of joint 1");
  };
  return t;
}

}  // namespace jointsim::experiments
