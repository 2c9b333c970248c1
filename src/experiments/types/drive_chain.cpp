// `type: drive_chain`: a 1-D rotational chain of inertias and elements with exact MSL friction
// (systems/drive_chain.hpp); the Modelica Rotational examples of docs/validation.md.
#include <algorithm>
#include <map>

#include <nlohmann/json.hpp>

#include "experiments/config_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/config.hpp"
#include "jointsim/experiments/types.hpp"
#include "jointsim/systems/faults.hpp"

namespace jointsim::experiments {

using io::YamlValue;

namespace {
std::vector<std::array<double, 2>> readTable(const YamlValue& node, const std::string& what) {
  node.expectSequence(what);
  std::vector<std::array<double, 2>> t;
  for (size_t k = 0; k < node.size(); ++k) {
    const auto row = node.at(k).asDoubles(2, "a row [v, value]");
    if (!t.empty() && !(row[0] > t.back()[0])) node.at(k).failExpected("strictly increasing speeds");
    if (row[0] < 0.0) node.at(k).failExpected("a speed >= 0");
    t.push_back({row[0], row[1]});
  }
  if (t.empty()) node.failExpected(what + " with at least one row");
  return t;
}
}  // namespace

systems::DriveChainSetup readDriveChainSetup(const YamlValue& root, const std::string& name) {
  root.allowKeys({"experiment", "inertias", "elements", "duration", "log_rate", "solver"});
  systems::DriveChainSetup s;
  s.name = name;
  std::map<std::string, int> index;
  const YamlValue inertias = root.required("inertias", "list of inertias {name, J, phi, w}");
  inertias.expectSequence("a list of inertias");
  for (size_t k = 0; k < inertias.size(); ++k) {
    const YamlValue in = inertias.at(k);
    in.expectMap("an inertia {name, J, phi, w}");
    in.allowKeys({"name", "J", "phi", "w"});
    systems::ChainInertia c;
    c.name = in.required("name", "inertia name").asString("a name");
    const YamlValue J = in.required("J", "inertia in kg·m²");
    c.J = J.asDouble("an inertia in kg·m²");
    if (!(c.J > 0.0)) J.failExpected("an inertia > 0 kg·m²");
    c.phi0 = in["phi"].asDouble(0.0, "an angle in rad");
    c.w0 = in["w"].asDouble(0.0, "a speed in rad/s");
    if (index.count(c.name)) in["name"].fail("inertia '" + c.name + "' defined twice");
    index[c.name] = static_cast<int>(k);
    s.inertias.push_back(c);
  }
  auto node = [&](const YamlValue& v) {
    const std::string n = v.asString("an inertia name or 'ground'");
    if (n == "ground") return -1;
    if (!index.count(n)) v.fail("unknown inertia '" + n + "' (or 'ground')");
    return index[n];
  };
  const YamlValue elements = root.required("elements", "list of elements");
  elements.expectSequence("a list of elements");
  for (size_t k = 0; k < elements.size(); ++k) {
    const YamlValue el = elements.at(k);
    el.expectMap("an element {name, type, ...}");
    systems::ChainElement e;
    e.name = el.required("name", "element name").asString("a name");
    const YamlValue type =
        el.required("type", "spring_damper, elasto_backlash, clutch, brake, bearing_friction, gear or torque");
    const std::string t = type.asString("an element type");
    if (t == "torque") {
      el.allowKeys({"name", "type", "on", "profile"});
      e.type = systems::ChainElementType::TorqueSource;
      e.b = node(el.required("on", "the inertia driven"));
      e.torque = readProfile(el.required("profile", "torque profile in N·m"), "N·m");
    } else {
      e.a = node(el.required("from", "input flange: inertia name or ground"));
      e.b = node(el.required("to", "output flange: inertia name or ground"));
      if (t == "spring_damper" || t == "elasto_backlash") {
        e.type =
            t == "spring_damper" ? systems::ChainElementType::SpringDamper : systems::ChainElementType::ElastoBacklash;
        if (e.type == systems::ChainElementType::SpringDamper)
          el.allowKeys({"name", "type", "from", "to", "c", "d"});
        else
          el.allowKeys({"name", "type", "from", "to", "c", "d", "backlash"});
        e.c = el.required("c", "stiffness in N·m/rad").asDouble("a stiffness in N·m/rad");
        e.d = el["d"].asDouble(0.0, "a damping in N·m·s/rad");
        if (e.type == systems::ChainElementType::ElastoBacklash)
          e.backlash = el.required("backlash", "total backlash in rad").asDouble("a backlash in rad");
      } else if (t == "clutch" || t == "brake") {
        el.allowKeys({"name", "type", "from", "to", "fn_max", "normalized_force", "mu", "peak", "cgeo"});
        e.type = t == "clutch" ? systems::ChainElementType::Clutch : systems::ChainElementType::Brake;
        e.fn_max = el.required("fn_max", "maximum normal force in N").asDouble("a force in N");
        if (el.has("normalized_force")) e.normalized = readProfile(el["normalized_force"], "-");
        if (el.has("mu")) e.table = readTable(el["mu"], "a table [[v rad/s, mu], ...]");
        e.peak = el["peak"].asDouble(1.0, "a peak factor >= 1");
        e.cgeo = el["cgeo"].asDouble(1.0, "a geometry constant in m");
      } else if (t == "gear") {
        el.allowKeys({"name", "type", "from", "to", "ratio"});
        e.type = systems::ChainElementType::Gear;
        e.ratio = el.required("ratio", "gear ratio φ_from/φ_to").asDouble("a gear ratio");
      } else if (t == "bearing_friction") {
        el.allowKeys({"name", "type", "from", "to", "tau_pos", "peak"});
        e.type = systems::ChainElementType::BearingFriction;
        e.table =
            readTable(el.required("tau_pos", "table [[w rad/s, tau N·m], ...]"), "a table [[w rad/s, tau N·m], ...]");
        e.peak = el["peak"].asDouble(1.0, "a peak factor >= 1");
      } else {
        type.failExpected("spring_damper, elasto_backlash, clutch, brake, bearing_friction, gear or torque");
      }
    }
    s.elements.push_back(std::move(e));
  }
  readDurationAndLogRate(root, s.duration, s.log_rate);
  s.solver = readSolver(root["solver"], s.solver);
  root.validate([&] { s.validate(); });
  return s;
}

namespace {

class DriveChainExperiment : public PlantExperiment<systems::DriveChain> {
 public:
  using PlantExperiment::PlantExperiment;
  std::string keyUnit(const std::string& key) const override {
    const std::string p = detail::keyPattern(key);  // table rows [v rad/s, μ (clutch, brake) or f N·m (bearing)]
    if (p == "elements[].mu[][]") return key.substr(key.size() - 3) == "[0]" ? "rad/s" : "1";
    if (p == "elements[].tau_pos[][]") return key.substr(key.size() - 3) == "[0]" ? "rad/s" : "N·m";
    return detail::patternKeyUnit(key,
                                  {{"inertias[].J", "kg·m²"},
                                   {"inertias[].phi", "rad"},
                                   {"inertias[].w", "rad/s"},
                                   {"elements[].c", "N·m/rad"},
                                   {"elements[].d", "N·m·s/rad"},
                                   {"elements[].backlash", "rad"},
                                   {"elements[].fn_max", "N"},
                                   {"elements[].peak", "1"},
                                   {"elements[].cgeo", "m"},
                                   {"elements[].ratio", "1"}},
                                  {{"elements[].profile.", "N·m"}, {"elements[].normalized_force.", "1"}});
  }
  void describe(nlohmann::ordered_json& w, const sim::SimulationResult& r) const override {
    const auto& s = plant_.setup();
    w["events"] = r.events;
    w["duration"] = s.duration;
    w["log_rate"] = s.log_rate;
    solverJson(w["solver"], s.solver);
  }
};

std::vector<Figure> driveChainFigures(const RunData& run) {
  std::vector<Figure> figs;
  auto suffix = [&](const std::string& s) { return run.where([s](const std::string& n) { return endsWith(n, s); }); };
  auto owner = [](const std::string& n) { return n.substr(0, n.rfind('.')); };
  Figure in{run.experiment + "_inertias", run.experiment + ": inertias", 1, 1, {}};
  if (auto c = suffix(".phi"); !c.empty()) in.panels.push_back(timePanel(run, c, "angles", "angle", owner));
  if (auto c = suffix(".w"); !c.empty())
    in.panels.push_back(timePanel(run, c, "angular velocities", "angular velocity", owner));
  grid(in, in.panels.size(), 1);
  if (!in.panels.empty()) figs.push_back(in);
  Figure el{run.experiment + "_elements", run.experiment + ": elements", 1, 1, {}};
  if (auto c = suffix(".tau"); !c.empty()) el.panels.push_back(timePanel(run, c, "element torques", "torque", owner));
  if (auto c = suffix(".phi_rel"); !c.empty())
    el.panels.push_back(timePanel(run, c, "relative angles (to − from)", "relative angle", owner));
  if (auto c = suffix(".mode"); !c.empty()) {
    Panel p = timePanel(run, c, "friction modes (−1 backward, 0 stuck, +1 forward, 2 free)", "mode", owner);
    for (auto& s : p.series) s.style = LineStyle::ThickSteps;
    p.y_step = 1;
    p.y_min = -1.5;
    p.y_max = 2.5;
    el.panels.push_back(p);
  }
  grid(el, el.panels.size(), 1);
  if (!el.panels.empty()) figs.push_back(el);
  return figs;
}

}  // namespace

ExperimentType driveChainExperimentType() {
  ExperimentType t;
  t.name = "drive_chain";
  t.description = "a 1-D chain of inertias, springs, backlash, clutches and brakes with exact stick-slip friction";
  t.load = [](const YamlValue& root, const LoadContext& c) -> std::unique_ptr<Experiment> {
    systems::DriveChainSetup s = readDriveChainSetup(root, c.name);
    // Faults: constant parameter faults on an element, named by its name, through its parameter table.
    for (const systems::Fault& f : c.faults) {
      auto e = std::find_if(s.elements.begin(), s.elements.end(),
                            [&](const systems::ChainElement& el) { return el.name == f.joint; });
      if (e == s.elements.end())
        throw InputError("fault " + systems::describe(f) + ": the drive chain has no element '" + f.joint + "'");
      *e = e->withParameters(systems::tableFaultChanges(e->parameters(), f, "drive chain element '" + f.joint + "'"));
    }
    return std::make_unique<DriveChainExperiment>(std::move(s));
  };
  t.accepts_faults = true;
  t.figures = driveChainFigures;
  t.key_signal = [](const RunData& run) -> std::optional<KeySignal> {
    const auto w = run.where([](const std::string& n) { return endsWith(n, ".w"); });
    if (w.empty()) return std::nullopt;
    return timeKeySignal(run, w[0], run.name(w[0]));
  };
  return t;
}

}  // namespace jointsim::experiments
