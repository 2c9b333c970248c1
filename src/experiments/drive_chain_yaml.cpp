// `type: drive_chain` experiment files (format in docs/experiments.md).
#include <map>

#include "experiments/config_common.hpp"
#include "experiments/tracking_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/drive_chain.hpp"

namespace jointsim::experiments::detail {

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

RunReport runDriveChain(const YamlValue& root, const std::string& config_path, const std::string& name,
                        const RunOptions& options) {
  root.allowKeys({"experiment", "inertias", "elements", "duration", "log_rate", "solver"});
  DriveChainSetup s;
  s.name = name;
  std::map<std::string, int> index;
  const YamlValue inertias = root.required("inertias", "list of inertias {name, J, phi, w}");
  inertias.expectSequence("a list of inertias");
  for (size_t k = 0; k < inertias.size(); ++k) {
    const YamlValue in = inertias.at(k);
    in.expectMap("an inertia {name, J, phi, w}");
    in.allowKeys({"name", "J", "phi", "w"});
    ChainInertia c;
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
    ChainElement e;
    e.name = el.required("name", "element name").asString("a name");
    const YamlValue type = el.required("type", "spring_damper, elasto_backlash, clutch, brake, bearing_friction, gear or torque");
    const std::string t = type.asString("an element type");
    if (t == "torque") {
      el.allowKeys({"name", "type", "on", "profile"});
      e.type = ChainElementType::TorqueSource;
      e.b = node(el.required("on", "the inertia driven"));
      e.torque = readProfile(el.required("profile", "torque profile in N·m"), "N·m");
    } else {
      e.a = node(el.required("from", "input flange: inertia name or ground"));
      e.b = node(el.required("to", "output flange: inertia name or ground"));
      if (t == "spring_damper" || t == "elasto_backlash") {
        e.type = t == "spring_damper" ? ChainElementType::SpringDamper : ChainElementType::ElastoBacklash;
        if (e.type == ChainElementType::SpringDamper) el.allowKeys({"name", "type", "from", "to", "c", "d"});
        else el.allowKeys({"name", "type", "from", "to", "c", "d", "backlash"});
        e.c = el.required("c", "stiffness in N·m/rad").asDouble("a stiffness in N·m/rad");
        e.d = el["d"].asDouble(0.0, "a damping in N·m·s/rad");
        if (e.type == ChainElementType::ElastoBacklash)
          e.backlash = el.required("backlash", "total backlash in rad").asDouble("a backlash in rad");
      } else if (t == "clutch" || t == "brake") {
        el.allowKeys({"name", "type", "from", "to", "fn_max", "normalized_force", "mu", "peak", "cgeo"});
        e.type = t == "clutch" ? ChainElementType::Clutch : ChainElementType::Brake;
        e.fn_max = el.required("fn_max", "maximum normal force in N").asDouble("a force in N");
        if (el.has("normalized_force")) e.normalized = readProfile(el["normalized_force"], "-");
        if (el.has("mu")) e.table = readTable(el["mu"], "a table [[v rad/s, mu], ...]");
        e.peak = el["peak"].asDouble(1.0, "a peak factor >= 1");
        e.cgeo = el["cgeo"].asDouble(1.0, "a geometry constant in m");
      } else if (t == "gear") {
        el.allowKeys({"name", "type", "from", "to", "ratio"});
        e.type = ChainElementType::Gear;
        e.ratio = el.required("ratio", "gear ratio φ_from/φ_to").asDouble("a gear ratio");
      } else if (t == "bearing_friction") {
        el.allowKeys({"name", "type", "from", "to", "tau_pos", "peak"});
        e.type = ChainElementType::BearingFriction;
        e.table = readTable(el.required("tau_pos", "table [[w rad/s, tau N·m], ...]"), "a table [[w rad/s, tau N·m], ...]");
        e.peak = el["peak"].asDouble(1.0, "a peak factor >= 1");
      } else {
        type.failExpected("spring_damper, elasto_backlash, clutch, brake, bearing_friction, gear or torque");
      }
    }
    s.elements.push_back(std::move(e));
  }
  readDurationAndLogRate(root, s.duration, s.log_rate);
  s.solver = readSolver(root["solver"], s.solver);
  try {
    s.validate();
  } catch (const InputError& e) {
    root.fail(e.what());
  }
  DriveChain chain(s);
  size_t events = 0;
  return runAndRecord(
      name, "drive_chain", options, chain.columns(),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        const ChainRunResult r = simulateDriveChain(chain, sink);
        events = r.events;
        return SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
      },
      [&](io::JsonWriter& w) {
        w.beginObject();
        w.key("config_file"); w.value(config_path);
        w.key("events"); w.value(static_cast<long>(events));
        w.key("duration"); w.value(s.duration);
        w.key("log_rate"); w.value(s.log_rate);
        w.key("solver"); writeSolverOptions(w, s.solver);
        w.key("config"); writeYamlAsJson(w, root.node());
        w.endObject();
      });
}

}  // namespace jointsim::experiments::detail
