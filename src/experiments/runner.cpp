#include "jointsim/experiments/runner.hpp"

#include <filesystem>

#include "experiments/config_common.hpp"
#include "experiments/joint_rig_yaml.hpp"
#include "experiments/tracking_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/joint_rig.hpp"
#include "jointsim/experiments/passive_robot.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;

Eigen::VectorXd readVector(const YamlValue& v, const std::string& what) {
  if (!v.defined()) return {};
  const auto values = v.asDoubles(0, what);
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

RunReport runPassiveRobot(const YamlValue& root, const std::string& config_path, const std::string& name,
                          const RunOptions& options) {
  root.allowKeys({"experiment", "robot", "initial_state", "joint_damping", "duration", "log_rate", "solver"});
  const YamlValue robot_node = root.required("robot", "robot description file, relative to this file");
  const std::string robot_path = robot_node.asPath();
  multibody::Model model;
  try {
    model = multibody::loadRobot(robot_path);
  } catch (const InputError& e) {
    robot_node.fail(std::string("cannot load robot: ") + e.what());
  }
  PassiveRobotParams p;
  p.name = name;
  if (const YamlValue init = root["initial_state"]; init.defined()) {
    init.expectMap("a mapping {q, qd}");
    init.allowKeys({"q", "qd"});
    p.q0 = readVector(init["q"], "a list of joint positions in rad");
    p.qd0 = readVector(init["qd"], "a list of joint velocities in rad/s");
    if (p.q0.size() && p.q0.size() != model.nq)
      init["q"].failExpected(std::to_string(model.nq) + " joint positions (one per joint of " + model.name + ")");
    if (p.qd0.size() && p.qd0.size() != model.nq)
      init["qd"].failExpected(std::to_string(model.nq) + " joint velocities (one per joint of " + model.name + ")");
  }
  p.damping = readVector(root["joint_damping"], "a list of damping coefficients in N·m·s/rad");
  if (p.damping.size() && (p.damping.size() != model.nq || p.damping.minCoeff() < 0))
    root["joint_damping"].failExpected(std::to_string(model.nq) + " damping coefficients >= 0 N·m·s/rad");
  detail::readDurationAndLogRate(root, p.duration, p.log_rate);
  p.solver = detail::readSolver(root["solver"], p.solver);
  p.validate(model);

  return detail::runAndRecord(
      name, "passive_robot", options, passiveRobotColumns(model),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        const PassiveRobotResult r = simulatePassiveRobot(model, p, sink);
        return detail::SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
      },
      [&](io::JsonWriter& w) {
        w.beginObject();
        w.key("config_file"); w.value(config_path);
        w.key("robot_file"); w.value(robot_path);
        w.key("robot"); w.value(model.name);
        w.key("joints"); w.beginArray(); for (const auto& j : model.joint_names) w.value(j); w.endArray();
        w.key("gravity"); w.value(Eigen::VectorXd(model.gravity));
        w.key("q0"); w.value(p.q0.size() ? p.q0 : Eigen::VectorXd::Zero(model.nq));
        w.key("qd0"); w.value(p.qd0.size() ? p.qd0 : Eigen::VectorXd::Zero(model.nq));
        w.key("joint_damping"); w.value(p.damping.size() ? p.damping : Eigen::VectorXd::Zero(model.nq));
        w.key("duration"); w.value(p.duration);
        w.key("log_rate"); w.value(p.log_rate);
        w.key("solver"); detail::writeSolverOptions(w, p.solver);
        w.key("config"); detail::writeYamlAsJson(w, root.node());
        w.endObject();
      },
      p.duration);
}

RunReport runJointRig(const YamlValue& root, const std::string& config_path, const std::string& name,
                      const RunOptions& options) {
  const JointRigSetup setup = detail::readJointRig(root, name);
  const JointRig rig(setup);
  return detail::runAndRecord(
      name, "joint_rig", options, rig.columns(),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        const RigRunResult r = simulateJointRig(rig, sink);
        return detail::SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
      },
      [&](io::JsonWriter& w) { detail::writeJointRigParameters(w, rig, root, config_path); }, setup.duration);
}

}  // namespace

RunReport runExperimentFile(const std::string& config_path, const RunOptions& options) {
  const YamlValue root = YamlValue::loadFile(config_path);
  detail::applyOverrides(root.node(), options.overrides, config_path);
  root.expectMap("an experiment description mapping");
  const YamlValue exp = root.required("experiment", "mapping {name, type}");
  exp.expectMap("a mapping {name, type}");
  exp.allowKeys({"name", "type", "description"});
  const std::string name = exp.required("name", "experiment name").asString("a name");
  if (name.empty() || name.find_first_of("/\\") != std::string::npos)
    exp["name"].failExpected("a non-empty name without path separators");
  const YamlValue type = exp.required("type", "experiment type");
  const std::string t = type.asString("an experiment type");
  if (!options.faults.empty() && t != "tracking")
    type.fail("faults (" + sim::describe(options.faults.front()) + ", ...) apply to experiments with a robot with drives "
              "(type tracking), not to type '" + t + "'");
  if (t == "passive_robot") return runPassiveRobot(root, config_path, name, options);
  if (t == "joint_rig") return runJointRig(root, config_path, name, options);
  if (t == "tracking") return detail::runTracking(root, config_path, name, options);
  if (t == "drive_chain") return detail::runDriveChain(root, config_path, name, options);
  if (t == "robotr3_axis") return detail::runRobotR3Axis(root, config_path, name, options);
  if (t == "robotr3_full") return detail::runRobotR3Full(root, config_path, name, options);
  if (t == "clamping") return detail::runClamping(root, config_path, name, options);
  type.failExpected(
      "an experiment type (known: passive_robot, joint_rig, tracking, drive_chain, robotr3_axis, robotr3_full, clamping)");
}

}  // namespace jointsim::experiments
