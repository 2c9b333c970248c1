#include "jointsim/experiments/runner.hpp"

#include <filesystem>
#include <sstream>

#include "io/yaml_reader.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/passive_robot.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;

Eigen::VectorXd readVector(const YamlValue& v, const std::string& what) {
  if (!v.defined()) return {};
  const auto values = v.asDoubles(0, what);
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

sim::CvodeOptions readSolver(const YamlValue& node, sim::CvodeOptions o) {
  if (!node.defined()) return o;
  node.expectMap("a solver mapping {method, rtol, atol, max_step, max_order, stability_limit_detection}");
  node.allowKeys({"method", "rtol", "atol", "max_step", "max_order", "stability_limit_detection", "max_num_steps"});
  if (node.has("method")) {
    const std::string m = node["method"].asString("adams or bdf");
    if (m == "adams") o.method = sim::Method::Adams;
    else if (m == "bdf") o.method = sim::Method::BDF;
    else node["method"].failExpected("adams or bdf");
  }
  o.rtol = node["rtol"].asDouble(o.rtol, "a relative tolerance > 0");
  if (!(o.rtol > 0)) node["rtol"].failExpected("a relative tolerance > 0");
  o.atol = node["atol"].asDouble(o.atol, "an absolute tolerance > 0");
  if (!(o.atol > 0)) node["atol"].failExpected("an absolute tolerance > 0");
  o.max_step = node["max_step"].asDouble(o.max_step, "a step in s (0 = unlimited)");
  if (o.max_step < 0) node["max_step"].failExpected("a step >= 0 s");
  if (node.has("max_order")) o.max_order = static_cast<int>(node["max_order"].asInt("an order 1..5 (BDF) or 1..12 (Adams)"));
  if (node.has("max_num_steps")) o.max_num_steps = node["max_num_steps"].asInt("a positive step count");
  if (node.has("stability_limit_detection"))
    o.stability_limit_detection = node["stability_limit_detection"].asBool("true or false");
  return o;
}

void writeSolverStats(io::JsonWriter& w, const sim::SolverStats& s) {
  w.beginObject();
  w.key("steps"); w.value(s.steps);
  w.key("rhs_evals"); w.value(s.rhs_evals);
  w.key("rhs_evals_jacobian"); w.value(s.rhs_evals_jacobian);
  w.key("jac_evals"); w.value(s.jac_evals);
  w.key("lin_setups"); w.value(s.lin_setups);
  w.key("error_test_failures"); w.value(s.error_test_failures);
  w.key("nonlinear_iterations"); w.value(s.nonlinear_iterations);
  w.key("nonlinear_conv_failures"); w.value(s.nonlinear_conv_failures);
  w.key("last_order"); w.value(s.last_order);
  w.key("last_step_s"); w.value(s.last_step);
  w.endObject();
}

void writeSolverOptions(io::JsonWriter& w, const sim::CvodeOptions& o) {
  w.beginObject();
  w.key("method"); w.value(o.method == sim::Method::BDF ? "bdf" : "adams");
  w.key("rtol"); w.value(o.rtol);
  w.key("atol"); w.value(o.atol);
  w.key("max_step"); w.value(o.max_step);
  w.key("max_order"); w.value(o.max_order);
  w.key("stability_limit_detection"); w.value(o.stability_limit_detection);
  w.endObject();
}

RunReport runPassiveRobot(const YamlValue& root, const std::string& config_path, const std::string& name,
                          const RunOptions& options) {
  root.allowKeys({"experiment", "robot", "initial_state", "joint_damping", "duration", "log_rate", "solver"});
  const YamlValue robot_node = root.required("robot", "robot description file, relative to this file");
  std::filesystem::path robot_path = robot_node.asString("a file path");
  if (robot_path.is_relative()) robot_path = std::filesystem::path(config_path).parent_path() / robot_path;
  multibody::Model model;
  try {
    model = multibody::loadRobot(robot_path.lexically_normal().string());
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
  const YamlValue duration = root.required("duration", "simulated time in s");
  p.duration = duration.asDouble("a time in s");
  if (!(p.duration > 0)) duration.failExpected("a time > 0 s");
  p.log_rate = root["log_rate"].asDouble(p.log_rate, "a rate in Hz");
  if (!(p.log_rate > 0)) root["log_rate"].failExpected("a rate > 0 Hz");
  p.solver = readSolver(root["solver"], p.solver);
  p.validate(model);

  RunReport report;
  report.experiment = name;
  const std::string dir = options.output_dir.empty() ? "out/" + name : options.output_dir;
  io::createDirectories(dir);
  report.csv_path = (std::filesystem::path(dir) / (name + ".csv")).string();
  report.summary_path = (std::filesystem::path(dir) / "summary.json").string();

  auto writeSummary = [&](const std::string& reason, double failed_at) {
    std::ostringstream os;
    io::JsonWriter w(os, true);
    w.beginObject();
    w.key("experiment"); w.value(name);
    w.key("type"); w.value("passive_robot");
    w.key("status"); w.value(report.status);
    if (!reason.empty()) {
      w.key("reason"); w.value(reason);
      w.key("failed_at_time_s"); w.value(failed_at);
    }
    w.key("sim_time_s"); w.value(report.sim_time_s);
    w.key("wall_time_s"); w.value(report.wall_time_s);
    w.key("real_time_factor"); w.value(report.real_time_factor);
    w.key("solver_stats"); writeSolverStats(w, report.stats);
    w.key("csv"); w.value(report.csv_path);
    w.key("parameters");
    w.beginObject();
    w.key("config_file"); w.value(config_path);
    w.key("robot_file"); w.value(robot_path.lexically_normal().string());
    w.key("robot"); w.value(model.name);
    w.key("joints"); w.beginArray(); for (const auto& j : model.joint_names) w.value(j); w.endArray();
    w.key("gravity"); w.value(Eigen::VectorXd(model.gravity));
    w.key("q0"); w.value(p.q0.size() ? p.q0 : Eigen::VectorXd::Zero(model.nq));
    w.key("qd0"); w.value(p.qd0.size() ? p.qd0 : Eigen::VectorXd::Zero(model.nq));
    w.key("joint_damping"); w.value(p.damping.size() ? p.damping : Eigen::VectorXd::Zero(model.nq));
    w.key("duration"); w.value(p.duration);
    w.key("log_rate"); w.value(p.log_rate);
    w.key("solver"); writeSolverOptions(w, p.solver);
    w.endObject();
    w.endObject();
    io::writeFileAtomically(report.summary_path, os.str());
  };

  io::CsvWriter csv(report.csv_path, passiveRobotColumns(model));
  try {
    const PassiveRobotResult r = simulatePassiveRobot(model, p, [&](const Eigen::VectorXd& row) { csv.writeRow(row); });
    report.stats = r.stats;
    report.sim_time_s = r.sim_time_s;
    report.wall_time_s = r.wall_time_s;
    report.real_time_factor = r.wall_time_s > 0 ? r.sim_time_s / r.wall_time_s : 0.0;
  } catch (const SolverError& e) {
    report.status = "failed";
    report.csv_path.clear();
    report.sim_time_s = e.time();
    writeSummary(e.what(), e.time());
    throw;  // the CsvWriter's destructor removes the partial log
  }
  csv.commit();
  report.status = "ok";
  writeSummary("", 0.0);
  return report;
}

}  // namespace

RunReport runExperimentFile(const std::string& config_path, const RunOptions& options) {
  const YamlValue root = YamlValue::loadFile(config_path);
  root.expectMap("an experiment description mapping");
  const YamlValue exp = root.required("experiment", "mapping {name, type}");
  exp.expectMap("a mapping {name, type}");
  exp.allowKeys({"name", "type", "description"});
  const std::string name = exp.required("name", "experiment name").asString("a name");
  if (name.empty() || name.find_first_of("/\\") != std::string::npos)
    exp["name"].failExpected("a non-empty name without path separators");
  const YamlValue type = exp.required("type", "experiment type");
  const std::string t = type.asString("an experiment type");
  if (t == "passive_robot") return runPassiveRobot(root, config_path, name, options);
  type.failExpected("an experiment type (known: passive_robot)");
}

}  // namespace jointsim::experiments
