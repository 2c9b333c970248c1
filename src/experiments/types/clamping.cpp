// `type: clamping`: the whole-robot clamping experiment of [Olsson2017] (systems/clamped_robot.hpp).
#include <set>

#include <algorithm>

#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;

// A 3×3 matrix: a scalar (times I), three numbers (diagonal) or three rows of three.
Eigen::Matrix3d readMatrix3(const YamlValue& v, const std::string& unit) {
  const std::string what = "a number, 3 diagonal entries or a 3×3 matrix in " + unit;
  if (!v.isSequence()) return v.asDouble(what) * Eigen::Matrix3d::Identity();
  if (v.size() == 3 && !v.at(0).isSequence()) {
    const auto d = v.asDoubles(3, what);
    return Eigen::Vector3d(d[0], d[1], d[2]).asDiagonal();
  }
  if (v.size() != 3) v.failExpected(what);
  Eigen::Matrix3d m;
  for (size_t r = 0; r < 3; ++r) {
    const auto row = v.at(r).asDoubles(3, "a row of 3 numbers in " + unit);
    for (size_t c = 0; c < 3; ++c) m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c];
  }
  return m;
}

// Reads the axis keys of `n` into `a` (used for `axis_defaults` and for each axis).
void readAxis(const YamlValue& n, systems::ClampingAxisParams& a) {
  if (n.has("ratio")) a.ratio = n["ratio"].asDouble("gear ratio r = motor angle / gear output angle (-)");
  if (n.has("inertia")) a.inertia = n["inertia"].asDouble("motor inertia J in kg·m²");
  if (n.has("c")) a.c = n["c"].asDouble("ElastoBacklash stiffness c in N·m/rad (motor side)");
  if (n.has("d")) a.d = n["d"].asDouble("ElastoBacklash damping d in N·m·s/rad (motor side)");
  if (n.has("b")) a.b = n["b"].asDouble("total backlash b in rad (motor side)");
  if (const YamlValue f = n["friction"]; f.defined()) {
    f.expectMap("a mapping {tau_pos: [[w in rad/s, tau in N·m], ...], peak}");
    f.allowKeys({"tau_pos", "peak"});
    if (const YamlValue t = f["tau_pos"]; t.defined()) {
      t.expectSequence("a friction table [[w in rad/s, tau in N·m], ...]");
      a.tau_pos.clear();
      for (size_t i = 0; i < t.size(); ++i) {
        const auto r = t.at(i).asDoubles(2, "a table row [w in rad/s, tau in N·m]");
        a.tau_pos.push_back({r[0], r[1]});
      }
    }
    if (f.has("peak")) a.peak = f["peak"].asDouble("stiction factor peak (-), >= 1");
  }
  if (const YamlValue o = n["orthogonal"]; o.defined()) {
    o.expectMap("a mapping {c: N·m/rad, d: N·m·s/rad}");
    o.allowKeys({"c", "d"});
    if (o.has("c")) a.c_orth = o["c"].asDouble("orthogonal stiffness c_orth in N·m/rad (0 = rigid)");
    if (o.has("d")) a.d_orth = o["d"].asDouble("orthogonal damping d_orth in N·m·s/rad");
  }
  if (const YamlValue c = n["controller"]; c.defined()) {
    c.expectMap("a mapping {kp: 1/s, ks: N·m·s/rad, Ts: s, ratio: -}");
    c.allowKeys({"kp", "ks", "Ts", "ratio"});
    if (c.has("kp")) a.kp = c["kp"].asDouble("position gain kp in 1/s");
    if (c.has("ks")) a.ks = c["ks"].asDouble("speed PI gain ks in N·m·s/rad");
    if (c.has("Ts")) a.Ts = c["Ts"].asDouble("PI time constant Ts in s");
    if (c.has("ratio")) a.controller_ratio = c["ratio"].asDouble("reference scaling ratio (-)");
  }
  if (const YamlValue p = n["path"]; p.defined()) {
    p.expectMap("a mapping {q_pos: rad, qd_max: rad/s, qdd_max: rad/s², segment_time: s, segments}");
    p.allowKeys({"q_pos", "qd_max", "qdd_max", "segment_time", "segments"});
    if (p.has("q_pos")) a.path.q_pos = p["q_pos"].asDouble("swing amplitude q_pos in rad (arm side)");
    if (p.has("qd_max")) a.path.qd_max = p["qd_max"].asDouble("speed limit qd_max in rad/s");
    if (p.has("qdd_max")) a.path.qdd_max = p["qdd_max"].asDouble("acceleration limit qdd_max in rad/s²");
    if (p.has("segment_time")) a.path.segment_time = p["segment_time"].asDouble("segment slot length in s");
    if (p.has("segments")) a.path.segments = static_cast<int>(p["segments"].asInt("number of segments (>= 1)"));
  }
}

void allowAxisKeys(const YamlValue& n, bool with_joint) {
  if (with_joint)
    n.allowKeys({"joint", "ratio", "inertia", "c", "d", "b", "friction", "orthogonal", "controller", "path"});
  else
    n.allowKeys({"ratio", "inertia", "c", "d", "b", "friction", "orthogonal", "controller", "path"});
}

}  // namespace

ClampingExperimentSetup readClampingSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "robot", "clamp", "coupling", "axis_defaults", "axes", "load", "initial_posture",
                  "duration", "log_rate", "curves", "solver"});
  ClampingExperimentSetup out;
  systems::ClampingSetup& s = out.setup;
  s.name = name;
  const YamlValue robot_node = root.required("robot", "robot description file, relative to this file");
  const std::string robot_path = out.robot_file = robot_node.asPath();
  try {
    s.arm = multibody::loadRobot(robot_path);
  } catch (const InputError& e) {
    robot_node.fail(std::string("cannot load robot: ") + e.what());
  }
  // Clamp.
  if (const YamlValue c = root["clamp"]; c.defined()) {
    c.expectMap("a mapping {frame, c_lin, d_lin, c_rot, d_rot}");
    c.allowKeys({"frame", "c_lin", "d_lin", "c_rot", "d_rot"});
    if (c.has("frame")) {
      s.clamp.frame = c["frame"].asString("a frame name of the robot");
      if (!s.arm.hasFrame(s.clamp.frame))
        c["frame"].fail("no frame named '" + s.clamp.frame + "' in robot '" + s.arm.name + "'");
    }
    if (c.has("c_lin")) s.clamp.c_lin = readMatrix3(c["c_lin"], "N/m");
    if (c.has("d_lin")) s.clamp.d_lin = readMatrix3(c["d_lin"], "N·s/m");
    if (c.has("c_rot")) s.clamp.c_rot = readMatrix3(c["c_rot"], "N·m/rad");
    if (c.has("d_rot")) s.clamp.d_rot = readMatrix3(c["d_rot"], "N·m·s/rad");
  }
  // Axes: defaults, then one entry per joint.
  systems::ClampingAxisParams defaults;
  if (const YamlValue d = root["axis_defaults"]; d.defined()) {
    d.expectMap("a mapping of axis parameters applied to every axis");
    allowAxisKeys(d, false);
    readAxis(d, defaults);
  }
  const YamlValue axes = root.required("axes", "one axis per joint: {joint, ratio, c, d, b, friction, ...}");
  axes.expectSequence("a list of axes");
  std::set<std::string> seen;
  for (size_t k = 0; k < axes.size(); ++k) {
    const YamlValue n = axes.at(k);
    n.expectMap("an axis mapping {joint, ratio, inertia, c, d, b, friction, orthogonal, controller, path}");
    allowAxisKeys(n, true);
    systems::ClampingAxisParams a = defaults;
    const YamlValue jn = n.required("joint", "name of the joint this axis drives");
    a.joint = jn.asString("a joint name");
    try {
      s.arm.jointIndex(a.joint);
    } catch (const InputError& e) {
      jn.fail(e.what());
    }
    if (!seen.insert(a.joint).second) jn.fail("joint '" + a.joint + "' already has an axis");
    readAxis(n, a);
    n.validate([&] { a.validate(); });
    s.axes.push_back(a);
  }
  if (static_cast<int>(s.axes.size()) != s.arm.nq)
    axes.failExpected("one axis per movable joint of '" + s.arm.name + "' (" + std::to_string(s.arm.nq) + ")");
  // Which axes swing (the others hold their start angle).
  if (const YamlValue l = root["load"]; l.defined()) {
    std::set<std::string> loaded;
    if (l.isSequence()) {
      for (size_t i = 0; i < l.size(); ++i) {
        const std::string j = l.at(i).asString("a joint name");
        if (!seen.count(j)) l.at(i).fail("no axis drives joint '" + j + "'");
        loaded.insert(j);
      }
    } else if (l.asString("'all' or a list of joint names") != "all") {
      l.failExpected("'all' or a list of joint names");
    } else {
      loaded = seen;
    }
    for (auto& a : s.axes)
      if (!loaded.count(a.joint)) a.path.q_pos = 0.0;
  }
  // Coupling (e.g. the wrist).
  if (const YamlValue c = root["coupling"]; c.defined()) {
    c.expectMap("a mapping {joints: [names], matrix: irb140_wrist | rows}");
    c.allowKeys({"joints", "matrix"});
    const YamlValue j = c.required("joints", "the coupled joints, in matrix order");
    j.expectSequence("a list of joint names");
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string name_j = j.at(i).asString("a joint name");
      if (!seen.count(name_j)) j.at(i).fail("no axis drives joint '" + name_j + "'");
      for (const auto& prev : s.coupled_joints)
        if (prev == name_j) j.at(i).fail("joint '" + name_j + "' appears twice in the coupling");
      s.coupled_joints.push_back(name_j);
    }
    const YamlValue m = c.required("matrix", "irb140_wrist or a square matrix (rows), q_joint = G φ_gear_output");
    const auto n = static_cast<Eigen::Index>(s.coupled_joints.size());
    if (!m.isSequence()) {
      if (m.asString("irb140_wrist or a list of rows") != "irb140_wrist")
        m.failExpected("irb140_wrist or a list of rows");
      if (n != 3) j.failExpected("3 joints for irb140_wrist");
      s.coupling = drive::CouplingMatrix::irb140Wrist();
    } else {
      if (static_cast<Eigen::Index>(m.size()) != n) m.failExpected(std::to_string(n) + " rows (one per coupled joint)");
      s.coupling.resize(n, n);
      for (Eigen::Index r = 0; r < n; ++r) {
        const auto row = m.at(static_cast<size_t>(r)).asDoubles(static_cast<size_t>(n), std::to_string(n) + " numbers");
        for (Eigen::Index cc = 0; cc < n; ++cc) s.coupling(r, cc) = row[static_cast<size_t>(cc)];
      }
    }
    try {
      drive::CouplingMatrix check(s.coupling);
    } catch (const InputError& e) {
      m.fail(e.what());
    }
  }
  if (const YamlValue p = root["initial_posture"]; p.defined()) {
    const auto q = p.asDoubles(static_cast<size_t>(s.arm.nq), "one joint angle in rad per joint");
    s.q0 = Eigen::Map<const Eigen::VectorXd>(q.data(), static_cast<Eigen::Index>(q.size()));
  }
  double log_rate = 1000.0;
  readDurationAndLogRate(root, s.duration, log_rate);
  s.log_interval = 1.0 / log_rate;
  out.curves = root["curves"].defined() ? root["curves"].asBool() : true;
  s.solver = readSolver(root["solver"], s.solver);
  root.validate([&] { s.validate(); });
  return out;
}

namespace {

class ClampingExperiment : public PlantExperiment<systems::ClampedRobot> {
 public:
  explicit ClampingExperiment(ClampingExperimentSetup s)
      : PlantExperiment(std::move(s.setup)), robot_file_(std::move(s.robot_file)), curves_(s.curves) {}
  std::optional<ArmKinematics> arm() const override {
    // The rigid arm; each joint's angle is the `<joint>.joint_angle` column of the axis driving it.
    const systems::ClampingSetup& s = plant_.setup();
    ArmKinematics a;
    a.model = &s.arm;
    for (const auto& j : s.arm.joint_names) a.angle_columns.push_back(j + ".joint_angle");
    a.tcp_frame = s.arm.frameIndex(s.clamp.frame.empty() ? s.arm.tip_frame : s.clamp.frame);
    a.clamped = true;
    a.q0 = s.q0;
    return a;
  }
  void observe(const Eigen::VectorXd& row) override {
    if (!curves_) return;
    // Time, then motor angle and torque of every axis.
    curve_rows_.push_back(row[0]);
    for (int k = 0; k < plant_.axisCount(); ++k) {
      curve_rows_.push_back(row[1 + plant_.motorAngleSignal(k)]);
      curve_rows_.push_back(row[1 + plant_.motorTorqueSignal(k)]);
    }
  }
  std::vector<ExtraTable> extraTables() const override {
    // One identify-ready clamping curve per axis: time[s], motor_angle[rad], motor_torque[N·m].
    std::vector<ExtraTable> out;
    if (!curves_) return out;
    const int n = plant_.axisCount();
    const auto stride = static_cast<Eigen::Index>(1 + 2 * n);
    const Eigen::Index rows = static_cast<Eigen::Index>(curve_rows_.size()) / stride;
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> all(
        curve_rows_.data(), rows, stride);
    for (int k = 0; k < n; ++k) {
      ExtraTable t;
      t.suffix = safeFileName(plant_.setup().axes[static_cast<size_t>(k)].joint) + "_curve";
      t.table.columns = {"time[s]", "motor_angle[rad]", "motor_torque[N·m]"};
      t.table.values.resize(rows, 3);
      t.table.values.col(0) = all.col(0);
      t.table.values.col(1) = all.col(1 + 2 * k);
      t.table.values.col(2) = all.col(2 + 2 * k);
      out.push_back(std::move(t));
    }
    return out;
  }
  std::string keyUnit(const std::string& key) const override {
    static const std::vector<std::pair<std::string, std::string>> units{{"axes[].ratio", "1"},
                                                                        {"axes[].inertia", "kg·m²"},
                                                                        {"axes[].c", "N·m/rad"},
                                                                        {"axes[].d", "N·m·s/rad"},
                                                                        {"axes[].b", "rad"},
                                                                        {"axes[].friction.peak", "1"},
                                                                        {"axes[].orthogonal.c", "N·m/rad"},
                                                                        {"axes[].orthogonal.d", "N·m·s/rad"},
                                                                        {"axes[].controller.kp", "1/s"},
                                                                        {"axes[].controller.ks", "N·m·s/rad"},
                                                                        {"axes[].controller.Ts", "s"},
                                                                        {"axes[].controller.ratio", "1"},
                                                                        {"axes[].path.q_pos", "rad"},
                                                                        {"axes[].path.qd_max", "rad/s"},
                                                                        {"axes[].path.qdd_max", "rad/s²"},
                                                                        {"axes[].path.segment_time", "s"},
                                                                        {"axis_defaults.ratio", "1"},
                                                                        {"axis_defaults.inertia", "kg·m²"},
                                                                        {"axis_defaults.c", "N·m/rad"},
                                                                        {"axis_defaults.d", "N·m·s/rad"},
                                                                        {"axis_defaults.b", "rad"},
                                                                        {"axis_defaults.friction.peak", "1"},
                                                                        {"axis_defaults.orthogonal.c", "N·m/rad"},
                                                                        {"axis_defaults.orthogonal.d", "N·m·s/rad"},
                                                                        {"axis_defaults.controller.kp", "1/s"},
                                                                        {"axis_defaults.controller.ks", "N·m·s/rad"},
                                                                        {"axis_defaults.controller.Ts", "s"},
                                                                        {"axis_defaults.controller.ratio", "1"},
                                                                        {"axis_defaults.path.q_pos", "rad"},
                                                                        {"axis_defaults.path.qd_max", "rad/s"},
                                                                        {"axis_defaults.path.qdd_max", "rad/s²"},
                                                                        {"axis_defaults.path.segment_time", "s"},
                                                                        {"clamp.c_lin", "N/m"},
                                                                        {"clamp.c_lin[]", "N/m"},
                                                                        {"clamp.c_lin[][]", "N/m"},
                                                                        {"clamp.d_lin", "N·s/m"},
                                                                        {"clamp.d_lin[]", "N·s/m"},
                                                                        {"clamp.d_lin[][]", "N·s/m"},
                                                                        {"clamp.c_rot", "N·m/rad"},
                                                                        {"clamp.c_rot[]", "N·m/rad"},
                                                                        {"clamp.c_rot[][]", "N·m/rad"},
                                                                        {"clamp.d_rot", "N·m·s/rad"},
                                                                        {"clamp.d_rot[]", "N·m·s/rad"},
                                                                        {"clamp.d_rot[][]", "N·m·s/rad"},
                                                                        {"initial_posture[]", "rad"}};
    const std::string p = detail::keyPattern(key);  // friction table rows [w rad/s, tau N·m]
    if (p == "axes[].friction.tau_pos[][]" || p == "axis_defaults.friction.tau_pos[][]")
      return key.substr(key.size() - 3) == "[0]" ? "rad/s" : "N·m";
    return detail::patternKeyUnit(key, units);
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult& r) const override {
    const auto& s = plant_.setup();
    w["robot_file"] = robot_file_;
    w["robot"] = s.arm.name;
    w["state_size"] = plant_.stateSize();
    w["dof_with_orthogonal_compliance"] = plant_.model().nq;
    w["events"] = r.events;
    w["duration"] = s.duration;
    w["log_interval"] = s.log_interval;
    solverJson(w["solver"], s.solver);
  }

 private:
  std::string robot_file_;
  bool curves_ = true;
  std::vector<double> curve_rows_;
};

/// Axis names of the columns `<axis>.motor_angle` that have a motor torque.
std::vector<std::string> clampingAxes(const RunData& run) {
  std::vector<std::string> axes;
  for (int c : run.where([](const std::string& n) { return endsWith(n, ".motor_angle"); })) {
    const std::string a = run.name(c).substr(0, run.name(c).size() - 12);
    if (run.col(a + ".motor_torque") >= 0) axes.push_back(a);
  }
  return axes;
}

std::vector<Figure> clampingFigures(const RunData& run) {
  std::vector<Figure> figs;
  Figure curves{run.experiment + "_clamping_curves",
                run.experiment + ": clamping curves (motor torque against motor angle)",
                1,
                1,
                {}};
  Figure torques{run.experiment + "_axis_torques", run.experiment + ": torques per axis", 1, 1, {}};
  for (const auto& a : clampingAxes(run)) {
    const int ma = run.col(a + ".motor_angle"), mt = run.col(a + ".motor_torque");
    const int st = run.col(a + ".spring_torque"), ft = run.col(a + ".friction_torque");
    Panel p;
    p.title = a + (run.span(ma) == 0 ? " (not driven)" : "");
    p.xlabel = axisLabel("motor angle", run.unit(ma));
    p.ylabel = axisLabel("torque", run.unit(mt));
    p.time_axis = false;
    p.key = Key::top_left;
    p.series.push_back(xySeries(run, ma, mt, "motor torque"));
    if (st >= 0) p.series.push_back(xySeries(run, ma, st, "spring torque", LineStyle::Dashed));
    curves.panels.push_back(p);
    std::vector<int> cols{mt};
    if (st >= 0) cols.push_back(st);
    if (ft >= 0) cols.push_back(ft);
    torques.panels.push_back(
        timePanel(run, cols, a, "torque", [&](const std::string& n) { return stripPrefix(n, a + "."); }));
  }
  for (Figure* f : {&curves, &torques})
    if (!f->panels.empty()) {
      grid(*f, f->panels.size());
      figs.push_back(*f);
    }
  // The clamp: displacement and rotation of the held frame, force and moment.
  Figure clamp{run.experiment + "_clamp", run.experiment + ": clamp displacement, rotation and load", 1, 1, {}};
  auto clampPanel = [&](std::initializer_list<const char*> names, const std::string& title, const std::string& q) {
    std::vector<int> cols;
    for (const char* n : names)
      if (run.col(n) >= 0) cols.push_back(run.col(n));
    if (cols.empty()) return;
    double m = 0;
    for (int c : cols) m = std::max(m, run.maxAbs(c));
    const Scaled s = readableUnit(run.unit(cols.front()), m);
    Panel p;
    p.title = title;
    p.xlabel = axisLabel("time", run.unit(run.time()));
    p.ylabel = axisLabel(q, s.unit);
    for (int c : cols) {
      const bool norm = endsWith(run.name(c), "displacement") || endsWith(run.name(c), "rotation");
      p.series.push_back(timeSeries(run, c, stripPrefix(run.name(c), "clamp."), s.factor,
                                    norm ? LineStyle::Emphasis : LineStyle::Line));
    }
    clamp.panels.push_back(p);
  };
  clampPanel({"clamp.dx", "clamp.dy", "clamp.dz", "clamp.displacement"}, "displacement (world frame)", "displacement");
  clampPanel({"clamp.rx", "clamp.ry", "clamp.rz", "clamp.rotation"}, "rotation vector (frame axes)", "rotation");
  clampPanel({"clamp.force"}, "force magnitude", "force");
  clampPanel({"clamp.moment"}, "moment magnitude", "moment");
  grid(clamp, clamp.panels.size(), 2);
  if (!clamp.panels.empty()) figs.push_back(clamp);
  return figs;
}

std::optional<KeySignal> clampingKeySignal(const RunData& run) {
  // The clamping curve of the first axis that moves (else the first axis).
  std::string first;
  for (int c : run.where([](const std::string& n) { return endsWith(n, ".motor_angle"); })) {
    const std::string a = run.name(c).substr(0, run.name(c).size() - 12);
    if (first.empty()) first = a;
    if (run.span(c) > 0) {
      first = a;
      break;
    }
  }
  const int ma = run.col(first + ".motor_angle"), mt = run.col(first + ".motor_torque");
  if (first.empty() || ma < 0 || mt < 0) return std::nullopt;
  KeySignal k;
  k.x = first + ".motor_angle";
  k.y = first + ".motor_torque";
  k.xlabel = axisLabel("motor angle", run.unit(ma));
  k.ylabel = axisLabel("motor torque", run.unit(mt));
  k.what = "clamping curve of " + first;
  return k;
}

}  // namespace

ExperimentType clampingExperimentType() {
  ExperimentType t;
  t.name = "clamping";
  t.description = "a whole robot with its flange clamped, axes swinging against it: clamping curves per axis";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    ClampingExperimentSetup s = readClampingSetup(root, c.name);
    // Faults: constant parameter faults on an axis's drive, through its parameter table.
    for (const systems::Fault& f : c.faults) {
      auto axis = std::find_if(s.setup.axes.begin(), s.setup.axes.end(),
                               [&](const systems::ClampingAxisParams& a) { return a.joint == f.joint; });
      if (axis == s.setup.axes.end())
        throw InputError("fault " + systems::describe(f) + ": no axis drives joint '" + f.joint + "'");
      const std::string what = "clamping axis '" + f.joint + "'";
      *axis = axis->withParameters(systems::tableFaultChanges(axis->parameters(), f, what));
    }
    try {
      return std::make_unique<ClampingExperiment>(std::move(s));
    } catch (const InputError& e) {
      root.relocate(e);  // e.g. a clamp frame on the fixed base
    }
  };
  t.accepts_faults = true;
  t.figures = clampingFigures;
  t.key_signal = clampingKeySignal;
  return t;
}

}  // namespace jointsim::experiments
