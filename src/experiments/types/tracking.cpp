// `type: tracking`: a robot with drives (systems/robot_system.hpp) following a joint trajectory under its
// drive controllers, continuous or sampled; the UR5 digital twin of [Raviola2023].
#include <filesystem>

#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/control/trajectory_yaml.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

namespace jointsim::experiments {

using io::YamlValue;

namespace {

// The numbers below a component's mapping as table keys: nested mappings joined with '.', list entries as [i]
// ("positive.alpha0", "tau_pos[1][1]").
void flattenNumbers(const YamlValue& node, const std::string& key, const std::string& joint,
                    const std::string& component, std::vector<systems::DriveParameterChange>& out) {
  if (node.isMap()) {
    for (const std::string& k : node.keys())
      flattenNumbers(node[k], key.empty() ? k : key + "." + k, joint, component, out);
  } else if (node.isSequence()) {
    for (size_t i = 0; i < node.size(); ++i)
      flattenNumbers(node.at(i), key + "[" + std::to_string(i) + "]", joint, component, out);
  } else {
    systems::DriveParameterChange c;
    c.joint = joint;
    c.component = component;
    c.key = key;
    c.value = node.asDouble("a number in the unit of the component's parameter " + key);
    c.where = node.file() + ":" + std::to_string(node.line()) + ": " + node.path();
    out.push_back(c);
  }
}

std::vector<systems::DriveParameterChange> readDriveChanges(const YamlValue& drives) {
  std::vector<systems::DriveParameterChange> out;
  if (!drives.defined()) return out;
  drives.expectMap("a mapping {JOINT: {motor|transmission|friction|sensors: {KEY: VALUE}}}");
  for (const std::string& joint : drives.keys()) {
    const YamlValue d = drives[joint];
    d.expectMap("a mapping {motor|transmission|friction|sensors: {KEY: VALUE}} of the drive's parameters to change");
    d.allowKeys({"motor", "transmission", "friction", "sensors"});
    for (const std::string& component : systems::driveComponents()) {
      const YamlValue c = d[component];
      if (!c.defined()) continue;
      c.expectMap("a mapping {KEY: VALUE} of parameters of the " + component + " (keys of its parameter table)");
      flattenNumbers(c, "", joint, component, out);
    }
  }
  return out;
}

}  // namespace

TrackingSetup readTrackingSetup(const YamlValue& root, const std::string& name,
                                const std::vector<systems::Fault>& faults) {
  (void)name;
  root.allowKeys({"experiment", "robot", "drives", "trajectory", "initial_state", "duration", "log_rate", "solver",
                  "check_limits", "joint_limits", "control", "relative_replay"});
  const std::vector<systems::DriveParameterChange> changes = readDriveChanges(root["drives"]);
  TrackingSetup s;
  const std::string base_dir = std::filesystem::path(root.file()).parent_path().string();
  const YamlValue robot = root.required("robot", "robot-with-drives file, relative to this file");
  s.robot_file = robot.asPath();
  try {
    s.robot = std::make_shared<systems::RobotSystem>(systems::loadRobotWithDrives(s.robot_file, faults, changes));
  } catch (const InputError& e) {
    const std::string m = e.what();
    if (!changes.empty() && m.rfind(root.file() + ":", 0) == 0) throw;  // a change of the drives: names its own line
    robot.fail(std::string("cannot load robot: ") + m);
  }
  systems::RobotSystem& sys = *s.robot;
  const int n = sys.dof();
  s.joint_limits = readJointLimits(root["joint_limits"]);
  sys.setJointLimits(s.joint_limits);
  if (const YamlValue c = root["control"]; c.defined()) {
    c.expectMap("a mapping {rate: Hz, current_rate: Hz, seed}");
    c.allowKeys({"rate", "current_rate", "seed"});
    const YamlValue rate = c.required("rate", "control sampling rate in Hz");
    s.control_rate = rate.asDouble("a rate in Hz");
    if (!(s.control_rate > 0.0)) rate.failExpected("a rate > 0 Hz");
    const long seed = c["seed"].defined() ? c["seed"].asInt("an integer seed") : 1;
    const YamlValue current = c["current_rate"];
    const double current_rate = current.defined() ? current.asDouble("a rate in Hz") : 0.0;
    if (current.defined() && !(current_rate > 0.0)) current.failExpected("a rate > 0 Hz");
    try {
      sys.setSampledControl(s.control_rate, static_cast<unsigned>(seed), current_rate);
    } catch (const InputError& e) {
      (current.defined() ? current : rate).fail(e.what());
    }
  }
  s.trajectory = control::trajectoryFromYaml(root.required("trajectory", "the reference trajectory"), n, base_dir);
  const bool check = !root.has("check_limits") || root["check_limits"].asBool("true or false");
  if (check) {
    try {
      control::checkLimits(*s.trajectory, sys.model().joint_names, sys.model().limits);
    } catch (const InputError& e) {
      root["trajectory"].fail(e.what());
    }
  }
  const YamlValue duration_node = root["duration"];
  s.duration = duration_node.asDouble(s.trajectory->duration(), "a time in s");
  if (!(s.duration > 0)) duration_node.failExpected("a time > 0 s");
  s.log_rate = root["log_rate"].asDouble(500.0, "a rate in Hz");
  if (!(s.log_rate > 0)) root["log_rate"].failExpected("a rate > 0 Hz");
  s.solver = readSolver(root["solver"], sim::stiffDriveSolver(1e-6, 1e-9));
  if (s.solver.max_step == 0.0) s.solver.max_step = 1.0 / s.log_rate;

  sys.setTrajectory(s.trajectory);
  // A measured log is replayed relative to the twin by default (RobotSystem::setRelativeReplay).
  const bool is_log = root["trajectory"]["type"].asString("a trajectory type") == "log";
  sys.setRelativeReplay(root["relative_replay"].defined() ? root["relative_replay"].asBool("true or false") : is_log);
  Eigen::VectorXd q0(n), tmp1(n), tmp2(n);
  s.trajectory->evaluate(0.0, q0, tmp1, tmp2);
  s.trajectory->startPositions(q0);  // a replayed log: the measured first positions, when it has them
  if (const YamlValue init = root["initial_state"]; init.defined()) {
    init.expectMap("a mapping {q}");
    init.allowKeys({"q"});
    const auto v = init["q"].asDoubles(static_cast<size_t>(n), std::to_string(n) + " joint positions in rad");
    q0 = Eigen::Map<const Eigen::VectorXd>(v.data(), n);
  }
  sys.setInitialPositions(q0);
  return s;
}

namespace {

class TrackingExperiment : public Experiment {
 public:
  explicit TrackingExperiment(TrackingSetup s) : s_(std::move(s)), max_err_(Eigen::VectorXd::Zero(s_.robot->dof())) {
    setJointLimits(jointLimitMonitor(s_.robot->model(), *s_.robot, s_.joint_limits));
  }
  sim::Plant& plant() override { return *s_.robot; }
  const systems::RobotSystem* robotSystem() const override { return s_.robot.get(); }
  std::optional<ArmKinematics> arm() const override {
    const multibody::Model& m = s_.robot->model();
    ArmKinematics a;
    a.model = &m;
    for (const auto& j : m.joint_names) a.angle_columns.push_back("q_" + j);
    a.tcp_frame = m.frameIndex(m.tip_frame);
    return a;
  }
  std::string keyUnit(const std::string& key) const override {
    const std::string p = detail::keyPattern(key);
    if (p.rfind("drives.", 0) == 0) {  // drives.JOINT.COMPONENT.KEY: the unit of the component's table
      const auto a = p.find('.', 7), b = a == std::string::npos ? a : p.find('.', a + 1);
      if (b == std::string::npos) return {};
      const std::string joint = key.substr(7, a - 7), component = key.substr(a + 1, b - a - 1);
      for (const systems::DriveSpec& d : s_.robot->drives())
        if (d.joint == joint) {
          try {
            return detail::tableKeyUnit(systems::driveParameterTable(d, component), key.substr(b + 1));
          } catch (const InputError&) {
            return {};
          }
        }
      return {};
    }
    static const std::pair<const char*, const char*> units[] = {
        {"initial_state.q[]", "rad"},
        {"control.rate", "Hz"},
        {"control.current_rate", "Hz"},
        {"control.seed", "1"},
        // point_to_point
        {"trajectory.start[]", "rad"},
        {"trajectory.segments[].target[]", "rad"},
        {"trajectory.segments[].velocity", "rad/s"},
        {"trajectory.segments[].acceleration", "rad/s²"},
        {"trajectory.segments[].duration", "s"},
        {"trajectory.segments[].dwell", "s"},
        // fourier (control/trajectory.hpp: the sine and cosine coefficients a, b in rad/s)
        {"trajectory.base_frequency", "Hz"},
        {"trajectory.harmonics", "1"},
        {"trajectory.offset[]", "rad"},
        {"trajectory.a[][]", "rad/s"},
        {"trajectory.b[][]", "rad/s"},
        {"trajectory.fade_in", "s"},
        {"trajectory.duration", "s"},
        // csv, log
        {"trajectory.gap_factor", "1"},
        // kinematic_ptp
        {"trajectory.q_begin[]", "rad"},
        {"trajectory.q_end[]", "rad"},
        {"trajectory.qd_max[]", "rad/s"},
        {"trajectory.qdd_max[]", "rad/s²"},
        {"trajectory.start_time", "s"},
        {"trajectory.rest_speed", "rad/s"}};
    for (const auto& [k, u] : units)
      if (p == k) return u;
    return detail::commonKeyUnit(key);
  }
  sim::SimulateOptions simulateOptions() const override {
    return sim::SimulateOptions::atRate(s_.duration, s_.log_rate, s_.solver);
  }
  void observe(const Eigen::VectorXd& row) override {
    // Per joint the row holds [q_set, q, ...] at columns 1 + 11 k (after the time).
    for (Eigen::Index k = 0; k < max_err_.size(); ++k)
      max_err_[k] = std::max(max_err_[k], std::abs(row[1 + 11 * k] - row[2 + 11 * k]));
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult&) const override {
    const systems::RobotSystem& sys = *s_.robot;
    w["robot_file"] = s_.robot_file;
    w["robot"] = sys.model().name;
    w["joints"] = sys.model().joint_names;
    w["trajectory"] = s_.trajectory->describe();
    w["state_size"] = sys.stateSize();
    auto& drives = w["drives"] = nlohmann::ordered_json::array();
    for (const auto& d : sys.drives())
      drives.push_back({{"joint", d.joint},
                        {"transmission", d.transmission->type()},
                        {"ratio", d.transmission->ratio()},
                        {"friction", d.friction ? d.friction->type() : std::string("none")},
                        {"electrics", d.electrics}});
    w["max_tracking_error_rad"] = detail::vectorJson(max_err_);
    w["control_rate_hz"] = s_.control_rate;
    w["relative_replay"] = s_.robot->relativeReplay();
    if (s_.robot->sampled() && s_.robot->currentRate() != s_.control_rate)
      w["current_rate_hz"] = s_.robot->currentRate();
    w["duration"] = s_.duration;
    w["log_rate"] = s_.log_rate;
    solverJson(w["solver"], s_.solver);
  }

 private:
  TrackingSetup s_;
  Eigen::VectorXd max_err_;
};

std::vector<Figure> trackingFigures(const RunData& run) {
  std::vector<Figure> figs;
  const auto joints = jointsWithPrefix(run, "q_set_");
  if (joints.empty()) return figs;
  // Tracking error q_set − q, in mrad (or µrad) when small.
  double max_err = 0;
  for (const auto& j : joints) {
    const int cs = run.col("q_set_" + j), cq = run.col("q_" + j);
    if (cs >= 0 && cq >= 0 && run.data.rows())
      max_err = std::max(max_err, (run.data.col(cs) - run.data.col(cq)).cwiseAbs().maxCoeff());
  }
  const Scaled err = readableUnit("rad", max_err);
  Figure e{run.experiment + "_tracking_error", run.experiment + ": tracking error per joint", 1, 1, {}};
  Figure tq{run.experiment + "_torques", run.experiment + ": gear torque vs. inverse-dynamics reference", 1, 1, {}};
  Figure q{run.experiment + "_joint_angles", run.experiment + ": joint angles, set point and actual", 1, 1, {}};
  Figure cur{run.experiment + "_currents", run.experiment + ": motor currents", 1, 1, {}};
  const std::string time_label = axisLabel("time", run.unit(run.time()));
  for (const auto& j : joints) {
    const int cs = run.col("q_set_" + j), cq = run.col("q_" + j);
    if (cq >= 0) {
      Panel p;
      p.title = j;
      p.xlabel = time_label;
      p.ylabel = axisLabel("q_set − q", err.unit);
      Series s = timeSeries(run, cs, "q_set − q");
      s.y_minus = cq;
      s.factor = err.factor;
      p.series.push_back(s);
      e.panels.push_back(p);
      Panel a;
      a.title = j;
      a.xlabel = time_label;
      a.ylabel = axisLabel("joint angle", run.unit(cq));
      a.series.push_back(timeSeries(run, cs, "q_set", 1, LineStyle::Dashed));
      a.series.push_back(timeSeries(run, cq, "q"));
      q.panels.push_back(a);
    }
    std::vector<Series> torques;
    const int cg = run.col("gear_torque_" + j), ci = run.col("id_torque_" + j), cf = run.col("friction_torque_" + j);
    if (cg >= 0) torques.push_back(timeSeries(run, cg, "gear torque"));
    if (ci >= 0) torques.push_back(timeSeries(run, ci, "inverse dynamics (reference)", 1, LineStyle::Dashed));
    if (cf >= 0) torques.push_back(timeSeries(run, cf, "friction torque"));
    if (!torques.empty()) {
      Panel p;
      p.title = j;
      p.xlabel = time_label;
      p.ylabel = axisLabel("torque", run.unit(cg >= 0 ? cg : ci >= 0 ? ci : cf));
      p.series = torques;
      tq.panels.push_back(p);
    }
    const int cc = run.col("current_" + j), cr = run.col("current_ref_" + j);
    if (cc >= 0) {
      Panel p;
      p.title = j;
      p.xlabel = time_label;
      p.ylabel = axisLabel("motor current", run.unit(cc));
      if (cr >= 0) p.series.push_back(timeSeries(run, cr, "reference", 1, LineStyle::Dashed));
      p.series.push_back(timeSeries(run, cc, "current"));
      cur.panels.push_back(p);
    }
  }
  for (Figure* f : {&e, &tq, &q, &cur})
    if (!f->panels.empty()) {
      grid(*f, f->panels.size());
      figs.push_back(*f);
    }
  return figs;
}

std::optional<KeySignal> trackingKeySignal(const RunData& run) {
  const auto joints = jointsWithPrefix(run, "q_set_");
  if (joints.empty() || run.col("q_" + joints[0]) < 0 || run.data.rows() == 0) return std::nullopt;
  const int cs = run.col("q_set_" + joints[0]), cq = run.col("q_" + joints[0]);
  KeySignal k;
  k.x = run.name(run.time());
  k.y = "q_set_" + joints[0];
  k.y_minus = "q_" + joints[0];
  const Scaled s = readableUnit("rad", (run.data.col(cs) - run.data.col(cq)).cwiseAbs().maxCoeff());
  k.factor = s.factor;
  k.xlabel = axisLabel("time", run.unit(run.time()));
  k.ylabel = axisLabel("q_set − q", s.unit);
  k.what = "tracking error of " + joints[0];
  return k;
}

}  // namespace

ExperimentType trackingExperimentType() {
  ExperimentType t;
  t.name = "tracking";
  t.description = "a robot with drives following a joint trajectory under its controllers (the UR5 digital twin)";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    return std::make_unique<TrackingExperiment>(readTrackingSetup(root, c.name, c.faults));
  };
  t.figures = trackingFigures;
  t.key_signal = trackingKeySignal;
  t.accepts_faults = true;
  return t;
}

}  // namespace jointsim::experiments
