// `type: passive_robot`: a rigid robot moving under gravity, no actuation (systems/passive_robot.hpp).
#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;

Eigen::VectorXd readVector(const YamlValue& v, const std::string& what) {
  if (!v.defined()) return {};
  const auto values = v.asDoubles(0, what);
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

class PassiveRobotExperiment : public PlantExperiment<systems::PassiveRobot> {
 public:
  explicit PassiveRobotExperiment(PassiveRobotSetup s)
      : PlantExperiment(std::move(s.model), std::move(s.params)), robot_file_(std::move(s.robot_file)) {
    setJointLimits(jointLimitMonitor(plant_.model(), plant_, plant_.params().joint_limits));
  }
  std::optional<ArmKinematics> arm() const override {
    const multibody::Model& m = plant_.model();
    ArmKinematics a;
    a.model = &m;
    for (const auto& j : m.joint_names) a.angle_columns.push_back("q_" + j);
    a.tcp_frame = m.frameIndex(m.tip_frame);
    a.q0 = plant_.params().q0;
    return a;
  }
  std::string keyUnit(const std::string& key) const override {
    // Per joint: rad for a revolute, m for a prismatic one.
    const std::string p = detail::keyPattern(key);
    const auto open = key.find('['), close = key.find(']');
    if (open != std::string::npos && close != std::string::npos &&
        (p == "initial_state.q[]" || p == "initial_state.qd[]" || p == "joint_damping[]")) {
      const auto j = static_cast<size_t>(std::stoul(key.substr(open + 1, close - open - 1)));
      const auto& types = plant_.model().joint_types;
      if (j >= types.size()) return {};
      const bool rev = types[j] == multibody::JointType::Revolute;
      if (p == "initial_state.q[]") return rev ? "rad" : "m";
      if (p == "initial_state.qd[]") return rev ? "rad/s" : "m/s";
      return rev ? "N·m·s/rad" : "N·s/m";
    }
    return detail::commonKeyUnit(key);
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult&) const override {
    const auto& model = plant_.model();
    const auto& p = plant_.params();
    w["robot_file"] = robot_file_;
    w["robot"] = model.name;
    w["joints"] = model.joint_names;
    w["gravity"] = detail::vectorJson(model.gravity);
    w["q0"] = detail::vectorJson(p.q0.size() ? p.q0 : Eigen::VectorXd::Zero(model.nq));
    w["qd0"] = detail::vectorJson(p.qd0.size() ? p.qd0 : Eigen::VectorXd::Zero(model.nq));
    w["joint_damping"] = detail::vectorJson(p.damping.size() ? p.damping : Eigen::VectorXd::Zero(model.nq));
    w["duration"] = p.duration;
    w["log_rate"] = p.log_rate;
    solverJson(w["solver"], p.solver);
  }

 private:
  std::string robot_file_;
};

std::vector<Figure> passiveRobotFigures(const RunData& run) {
  std::vector<Figure> figs;
  const auto joints = jointsWithPrefix(run, "q_");
  Figure f{run.experiment + "_joints", run.experiment + ": joint motion", 1, 1, {}};
  std::vector<int> q, qd, tip;
  for (const auto& j : joints) {
    if (run.col("q_" + j) >= 0) q.push_back(run.col("q_" + j));
    if (run.col("qd_" + j) >= 0) qd.push_back(run.col("qd_" + j));
  }
  for (const char* n : {"tip_x", "tip_y", "tip_z"})
    if (run.col(n) >= 0) tip.push_back(run.col(n));
  auto noPrefix = [](const std::string& p) { return [p](const std::string& n) { return stripPrefix(n, p); }; };
  if (!q.empty()) f.panels.push_back(timePanel(run, q, "joint angles", "joint angle", noPrefix("q_")));
  if (!qd.empty()) f.panels.push_back(timePanel(run, qd, "joint velocities", "joint velocity", noPrefix("qd_")));
  if (!tip.empty())
    f.panels.push_back(timePanel(run, tip, "tip position (world frame)", "tip position", noPrefix("tip_")));
  grid(f, f.panels.size(), 1);
  if (!f.panels.empty()) figs.push_back(f);

  const int ek = run.col("kinetic_energy"), ep = run.col("potential_energy"), et = run.col("total_energy");
  if (et >= 0 || ek >= 0 || ep >= 0) {
    Figure e{run.experiment + "_energy", run.experiment + ": energy", 1, 1, {}};
    std::vector<int> cols;
    for (int c : {ek, ep, et})
      if (c >= 0) cols.push_back(c);
    e.panels.push_back(timePanel(run, cols, "kinetic, potential and total energy", "energy"));
    if (et >= 0 && run.data.rows() > 0) {
      // Energy drift E(t) − E(0): zero for a conservative run, the integration error otherwise.
      Series s = timeSeries(run, et, "E(t) − E(0)");
      s.offset = run.data(0, et);
      Panel drift;
      drift.title = "change of the total energy since t = 0";
      drift.xlabel = axisLabel("time", run.unit(run.time()));
      drift.ylabel = axisLabel("E(t) − E(0)", run.unit(et));
      drift.series.push_back(s);
      e.panels.push_back(drift);
    }
    grid(e, e.panels.size(), 1);
    figs.push_back(e);
  }
  return figs;
}

}  // namespace

PassiveRobotSetup readPassiveRobotSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys(
      {"experiment", "robot", "initial_state", "joint_damping", "joint_limits", "duration", "log_rate", "solver"});
  PassiveRobotSetup s;
  const YamlValue robot_node = root.required("robot", "robot description file, relative to this file");
  s.robot_file = robot_node.asPath();
  try {
    s.model = multibody::loadRobot(s.robot_file);
  } catch (const InputError& e) {
    robot_node.fail(std::string("cannot load robot: ") + e.what());
  }
  const multibody::Model& model = s.model;
  systems::PassiveRobotParams& p = s.params;
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
  p.joint_limits = readJointLimits(root["joint_limits"]);
  readDurationAndLogRate(root, p.duration, p.log_rate);
  p.solver = readSolver(root["solver"], p.solver);
  root.validate([&] { p.validate(model); });
  return s;
}

ExperimentType passiveRobotExperimentType() {
  ExperimentType t;
  t.name = "passive_robot";
  t.description = "a rigid robot moving under gravity without actuation (energy conservation check)";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    return std::make_unique<PassiveRobotExperiment>(readPassiveRobotSetup(root, c.name));
  };
  t.figures = passiveRobotFigures;
  t.key_signal = [](const RunData& run) -> std::optional<KeySignal> {
    const auto q = jointsWithPrefix(run, "q_");
    if (q.empty()) return std::nullopt;
    return timeKeySignal(run, run.col("q_" + q[0]), "angle of " + q[0]);
  };
  return t;
}

}  // namespace jointsim::experiments
