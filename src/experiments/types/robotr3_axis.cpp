// `type: robotr3_axis`: one RobotR3 axis on a 1-D load ([MSL, RobotR3.OneAxis]; systems/robotr3_axis.hpp).
#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robotr3_axis.hpp"
#include "jointsim/systems/robotr3_full.hpp"

namespace jointsim::experiments {

using io::YamlValue;

systems::RobotR3AxisSetup readRobotR3AxisSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "prefix", "motor", "gear", "controller", "load", "path", "stop_time", "log_interval",
                  "initial_friction_torque", "solver"});
  systems::RobotR3AxisSetup s;
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
      if (p == "one_axis")
        s.axis.motor = drive::OpAmpMotorParams::oneAxis();
      else if (p.size() == 13 && p.rfind("robotr3_axis", 0) == 0 && p[12] >= '1' && p[12] <= '6')
        s.axis.motor = drive::OpAmpMotorParams::robotR3Axis(p[12] - '0');
      else
        m["preset"].failExpected("one_axis or robotr3_axis1..6");
    }
    s.axis.motor.J = num(m, "J", s.axis.motor.J, "a rotor inertia in kg·m²");
    s.axis.motor.k = num(m, "k", s.axis.motor.k, "a motor constant in N·m/A");
    s.axis.motor.w = num(m, "w", s.axis.motor.w, "a current-loop frequency in rad/s");
    s.axis.motor.D = num(m, "D", s.axis.motor.D, "a damping ratio");
  }
  if (const YamlValue g = root["gear"]; g.defined()) {
    g.expectMap("a gear mapping {type, ratio, c, d, Rv0, Rv1, peak}");
    g.allowKeys({"type", "ratio", "c", "d", "Rv0", "Rv1", "peak"});
    if (g.has("type") && g["type"].asInt("1 (elastic); type 2 is not modelled yet") != 1)
      g["type"].failExpected("1 (the rigid type 2 is not modelled yet)");
    s.axis.ratio = num(g, "ratio", s.axis.ratio, "a gear ratio");
    s.axis.c = num(g, "c", s.axis.c, "a stiffness in N·m/rad");
    s.axis.d = num(g, "d", s.axis.d, "a damping in N·m·s/rad");
    s.axis.Rv0 = num(g, "Rv0", s.axis.Rv0, "a friction torque in N·m");
    s.axis.Rv1 = num(g, "Rv1", s.axis.Rv1, "a viscous coefficient in N·m·s/rad");
    s.axis.peak = num(g, "peak", s.axis.peak, "a stiction factor >= 1");
  }
  if (const YamlValue c = root["controller"]; c.defined()) {
    c.expectMap("a controller mapping {kp, ks, Ts}");
    c.allowKeys({"kp", "ks", "Ts"});
    s.axis.kp = num(c, "kp", s.axis.kp, "a gain in 1/s");
    s.axis.ks = num(c, "ks", s.axis.ks, "a gain in A·s/rad");
    s.axis.Ts = num(c, "Ts", s.axis.Ts, "a time constant in s");
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
  root.validate([&] { s.validate(); });
  return s;
}

namespace {

// The plant: the RobotR3 robot configured as one axis on a load (systems::oneAxisRobot).
class RobotR3AxisExperiment : public PlantExperiment<systems::RobotR3Full> {
 public:
  using PlantExperiment::PlantExperiment;
  std::string keyUnit(const std::string& key) const override {
    return detail::patternKeyUnit(key, {{"motor.J", "kg·m²"},
                                        {"motor.k", "N·m/A"},
                                        {"motor.w", "rad/s"},
                                        {"motor.D", "1"},
                                        {"gear.ratio", "1"},
                                        {"gear.c", "N·m/rad"},
                                        {"gear.d", "N·m·s/rad"},
                                        {"gear.Rv0", "N·m"},
                                        {"gear.Rv1", "N·m·s/rad"},
                                        {"gear.peak", "1"},
                                        {"controller.kp", "1/s"},
                                        {"controller.ks", "A·s/rad"},
                                        {"controller.Ts", "s"},
                                        {"load.inertia", "kg·m²"},
                                        {"path.q_begin", "rad"},
                                        {"path.q_end", "rad"},
                                        {"path.qd_max", "rad/s"},
                                        {"path.qdd_max", "rad/s²"},
                                        {"path.start_time", "s"},
                                        {"path.swing_time", "s"},
                                        {"stop_time", "s"},
                                        {"log_interval", "s"},
                                        {"initial_friction_torque", "N·m"}});
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult& r) const override {
    w["end_time"] = plant_.endTime();
    w["events"] = r.events;
    solverJson(w["solver"], plant_.setup().solver);
  }
};

std::vector<Figure> robotR3AxisFigures(const RunData& run) {
  std::vector<Figure> figs;
  auto find = [&](const std::string& suffix) {
    const auto c = run.where([&](const std::string& n) { return endsWith(n, suffix); });
    return c.empty() ? -1 : c.front();
  };
  Figure f{run.experiment + "_axis", run.experiment + ": axis signals", 1, 1, {}};
  const int phi = find("initializeFlange.phi_flange"), w = find("initializeFlange.w_flange");
  const int i = find("motor.La.i"), iref = find("motor.i_ref"), v = find("motor.C.v");
  const int defl = find("gear.spring.phi_rel"), tf = find("bearingFriction.tau"), mode = find("bearingFriction.mode");
  if (phi >= 0) {
    Panel p = timePanel(run, {phi}, "load", "load angle", [](const std::string&) { return "load angle"; });
    if (w >= 0) {
      p.series.push_back(timeSeries(run, w, "load speed (right axis)"));
      p.series.back().y2 = true;
      p.y2label = axisLabel("load speed", run.unit(w));
    }
    f.panels.push_back(p);
  }
  if (i >= 0) {
    Panel p = timePanel(run, {i}, "motor current", "motor current", [](const std::string&) { return "current La.i"; });
    if (iref >= 0) p.series.push_back(timeSeries(run, iref, "reference i_ref", 1, LineStyle::Dashed));
    if (v >= 0) {
      p.series.push_back(timeSeries(run, v, "capacitor voltage C.v (right axis)"));
      p.series.back().y2 = true;
      p.y2label = axisLabel("voltage", run.unit(v));
    }
    f.panels.push_back(p);
  }
  if (defl >= 0)
    f.panels.push_back(timePanel(run, {defl}, "gear spring deflection", "deflection φ_rel",
                                 [](const std::string&) { return "gear.spring.phi_rel"; }));
  if (tf >= 0) {
    Panel p = timePanel(run, {tf}, "bearing friction", "friction torque",
                        [](const std::string&) { return "friction torque"; });
    if (mode >= 0) {
      p.series.push_back(timeSeries(run, mode, "mode (right axis)", 1, LineStyle::Steps));
      p.series.back().y2 = true;
      p.y2label = "mode (−1, 0, +1)";
      p.y2_step = 1;
    }
    f.panels.push_back(p);
  }
  grid(f, f.panels.size(), 2);
  if (!f.panels.empty()) figs.push_back(f);
  if (auto e = run.where([](const std::string& n) { return startsWith(n, "energy."); }); !e.empty()) {
    Figure ef{run.experiment + "_energy", run.experiment + ": energy bookkeeping", 1, 1, {}};
    ef.panels.push_back(timePanel(run, e, "integrated energies", "energy",
                                  [](const std::string& n) { return stripPrefix(n, "energy."); }));
    figs.push_back(ef);
  }
  return figs;
}

}  // namespace

ExperimentType robotR3AxisExperimentType() {
  ExperimentType t;
  t.name = "robotr3_axis";
  t.description = "one RobotR3 axis (op-amp motor, stick-slip friction, elastic gear) on a load: MSL OneAxis";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    systems::RobotR3AxisSetup s = readRobotR3AxisSetup(root, c.name);
    // Faults: constant parameter faults on the axis's drive (named by its prefix, `axis` for OneAxis), through the
    // parameter table of a RobotR3 type-1 axis with these values.
    for (const systems::Fault& f : c.faults) {
      if (f.joint != s.prefix)
        throw InputError("fault " + systems::describe(f) + ": the axis's drive is called '" + s.prefix + "', not '" +
                         f.joint + "'");
      const std::string what = "RobotR3 axis '" + s.prefix + "'";
      s.axis = s.axis.withParameters(systems::tableFaultChanges(s.axis.parameters(), f, what), what);
    }
    return std::make_unique<RobotR3AxisExperiment>(systems::oneAxisRobot(s));
  };
  t.accepts_faults = true;
  t.figures = robotR3AxisFigures;
  t.key_signal = [](const RunData& run) -> std::optional<KeySignal> {
    const auto c = run.where([](const std::string& n) { return endsWith(n, "phi_flange"); });
    if (c.empty()) return std::nullopt;
    return timeKeySignal(run, c[0], "load angle");
  };
  return t;
}

}  // namespace jointsim::experiments
