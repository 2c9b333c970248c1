#include "jointsim/experiments/config.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "experiments/config_internal.hpp"
#include "io/yaml_node.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::experiments {

using io::YamlValue;

sim::CvodeOptions readSolver(const YamlValue& node, sim::CvodeOptions o) {
  if (!node.defined()) return o;
  node.expectMap("a solver mapping {method, rtol, atol, max_step, max_order, stability_limit_detection}");
  node.allowKeys({"method", "rtol", "atol", "max_step", "max_order", "stability_limit_detection", "max_num_steps",
                  "input_jumps", "max_gamma_change", "step", "jacobian_every", "jacobian_defect", "analytic_jacobian",
                  "oscillations"});
  const char* const methods = "bdf, adams or rosenbrock (fixed step)";
  if (node.has("method")) {
    const std::string m = node["method"].asString(methods);
    if (m == "adams")
      o.method = sim::Method::Adams;
    else if (m == "bdf")
      o.method = sim::Method::BDF;
    else if (m == "rosenbrock")
      o.method = sim::Method::Rosenbrock;
    else
      node["method"].failExpected(methods);
  }
  // step, jacobian_every, jacobian_defect and oscillations belong to the fixed-step method; with CVODE's methods they
  // are checked
  // and kept but unused, so that `--set solver.method=bdf` turns a fixed-step file into a CVODE run (as a solver
  // switch in Simulink keeps the fixed-step size).
  o.fixed_step = node["step"].asDouble(o.fixed_step, "a fixed step in s (0: the control period)");
  if (!(o.fixed_step >= 0.0) || !std::isfinite(o.fixed_step))
    node["step"].failExpected("a fixed step >= 0 s (0: the control period)");
  if (node.has("oscillations")) {
    const char* const expected = "resolve (rows of the drive trains' oscillatory states with γ = 1 − 1/√2) or damp";
    const std::string v = node["oscillations"].asString(expected);
    if (v != "resolve" && v != "damp") node["oscillations"].failExpected(expected);
    o.resolve_oscillations = v == "resolve";
  }
  const char* const every_expected = "a number of steps from 1 to 1e6, or adaptive";
  if (node.has("jacobian_every")) {
    const YamlValue& e = node["jacobian_every"];
    if (e.isScalar() && e.asString(every_expected) == "adaptive") {
      // Kept while it describes the steps (CvodeOptions::jacobian_defect), renewed at least every 1e6 steps.
      o.jacobian_every = sim::kAdaptiveJacobianEvery;
      if (!(o.jacobian_defect > 0.0))
        o.jacobian_defect = o.resolve_oscillations ? sim::kResolveJacobianDefect : sim::kAdaptiveJacobianDefect;
    } else {
      const long every = e.asInt(every_expected);
      if (every < 1 || every > 1000000) e.failExpected(every_expected);
      o.jacobian_every = static_cast<int>(every);
    }
  }
  if (node.has("jacobian_defect")) {
    const char* const expected = "a relative linearisation defect > 0 that refreshes the Jacobian (default 0.2)";
    o.jacobian_defect = node["jacobian_defect"].asDouble(expected);
    if (!(o.jacobian_defect > 0.0) || !std::isfinite(o.jacobian_defect)) node["jacobian_defect"].failExpected(expected);
    // Alone it means adaptive (with jacobian_every 1 it would never act); beside a number of steps both apply.
    if (!node.has("jacobian_every")) o.jacobian_every = sim::kAdaptiveJacobianEvery;
  }
  if (o.resolve_oscillations) {
    // Rows taken with γ = 1 − 1/√2 tolerate a Jacobian off by 17 % (CvodeOptions::resolve_oscillations).
    if (o.jacobian_defect > sim::kResolveMaxJacobianDefect)
      node[node.has("jacobian_defect") ? "jacobian_defect" : "oscillations"].failExpected(
          "a defect of at most " + formatNumber(sim::kResolveMaxJacobianDefect) +
          " with oscillations: resolve (adaptive gives " + formatNumber(sim::kResolveJacobianDefect) + ")");
    if (o.jacobian_every > 1 && o.jacobian_defect == 0.0)
      node[node.has("jacobian_every") ? "jacobian_every" : "oscillations"].failExpected(
          "1 or adaptive with oscillations: resolve (a Jacobian kept without the "
          "defect test diverges)");
  }
  o.rtol = node["rtol"].asDouble(o.rtol, "a relative tolerance > 0");
  if (!(o.rtol > 0)) node["rtol"].failExpected("a relative tolerance > 0");
  o.atol = node["atol"].asDouble(o.atol, "an absolute tolerance > 0");
  if (!(o.atol > 0)) node["atol"].failExpected("an absolute tolerance > 0");
  o.max_step = node["max_step"].asDouble(o.max_step, "a step in s (0 = unlimited)");
  if (o.max_step < 0) node["max_step"].failExpected("a step >= 0 s");
  if (node.has("max_order"))
    o.max_order = static_cast<int>(node["max_order"].asInt("an order 1..5 (BDF) or 1..12 (Adams)"));
  o.max_gamma_change = node["max_gamma_change"].asDouble(o.max_gamma_change, "a relative change of h·β₀ > 0");
  if (!(o.max_gamma_change > 0) || !std::isfinite(o.max_gamma_change))
    node["max_gamma_change"].failExpected("a relative change of h·β₀ > 0");
  if (node.has("max_num_steps")) o.max_num_steps = node["max_num_steps"].asInt("a positive step count");
  if (node.has("stability_limit_detection"))
    o.stability_limit_detection = node["stability_limit_detection"].asBool("true or false");
  if (node.has("analytic_jacobian")) o.analytic_jacobian = node["analytic_jacobian"].asBool("true or false");
  if (node.has("input_jumps")) {
    const std::string j = node["input_jumps"].asString("keep_history or restart");
    if (j == "keep_history")
      o.input_jump = sim::CvodeOptions::InputJump::KeepHistory;
    else if (j == "restart")
      o.input_jump = sim::CvodeOptions::InputJump::Restart;
    else
      node["input_jumps"].failExpected("keep_history or restart");
  }
  return o;
}

systems::JointLimitSettings readJointLimits(const YamlValue& node) {
  systems::JointLimitSettings s;
  if (!node.defined()) return s;
  const char* const modes = "ignore, warn or stop";
  const YamlValue mode = node.isMap() ? node["mode"] : node;
  if (node.isMap()) {
    node.allowKeys({"mode", "stiffness", "damping"});
    if (!mode.defined()) node.fail(std::string("missing key 'mode' (") + modes + ")");
  }
  const std::string m = mode.asString(modes);
  if (m == "ignore")
    s.mode = systems::JointLimitMode::Ignore;
  else if (m == "warn")
    s.mode = systems::JointLimitMode::Warn;
  else if (m == "stop")
    s.mode = systems::JointLimitMode::Stop;
  else
    mode.failExpected(modes);
  if (node.isMap()) {
    s.stiffness = node["stiffness"].asDouble(s.stiffness, "an end-stop stiffness in N·m/rad");
    s.damping = node["damping"].asDouble(s.damping, "an end-stop damping in N·m·s/rad");
    if (!(s.stiffness > 0) || !std::isfinite(s.stiffness))
      node["stiffness"].failExpected("a finite stiffness > 0 N·m/rad");
    if (!(s.damping >= 0) || !std::isfinite(s.damping)) node["damping"].failExpected("a finite damping >= 0 N·m·s/rad");
    if (s.mode != systems::JointLimitMode::Stop && (node["stiffness"].defined() || node["damping"].defined()))
      node.fail("stiffness and damping belong to mode stop (the end stops)");
  }
  return s;
}

systems::JointLimitMonitor jointLimitMonitor(const multibody::Model& model, const sim::Plant& plant,
                                             const systems::JointLimitSettings& settings) {
  std::vector<int> columns;
  const auto& names = plant.signalNames();
  for (const auto& joint : model.joint_names) {
    int column = -1;
    for (size_t k = 0; k < names.size() && column < 0; ++k)
      if (names[k].rfind("q_" + joint + "[", 0) == 0) column = static_cast<int>(k) + 1;  // time is column 0
    columns.push_back(column);
  }
  return systems::JointLimitMonitor(model, std::move(columns), settings);
}

void readDurationAndLogRate(const YamlValue& root, double& duration, double& log_rate) {
  const YamlValue d = root.required("duration", "simulated time in s");
  duration = d.asDouble("a time in s");
  if (!(duration > 0)) d.failExpected("a time > 0 s");
  log_rate = root["log_rate"].asDouble(log_rate, "a rate in Hz");
  if (!(log_rate > 0)) root["log_rate"].failExpected("a rate > 0 Hz");
}

control::Profile readProfile(const YamlValue& node, const std::string& unit) {
  node.expectMap("a profile mapping {type: constant|step|ramp|triangle|sine|piecewise|csv, ...}");
  const YamlValue type = node.required("type", "profile type");
  const std::string t = type.asString("a profile type");
  auto num = [&](const char* key, const std::string& what) { return node.required(key, what).asDouble(what); };
  auto opt = [&](const char* key, double fallback, const std::string& what) {
    return node[key].asDouble(fallback, what);
  };
  try {
    if (t == "constant") {
      node.allowKeys({"type", "value"});
      return control::Profile::constant(num("value", "a value in " + unit));
    }
    if (t == "step") {
      node.allowKeys({"type", "initial", "final", "time"});
      return control::Profile::step(opt("initial", 0.0, "a value in " + unit), num("final", "a value in " + unit),
                                    num("time", "a time in s"));
    }
    if (t == "ramp") {
      node.allowKeys({"type", "offset", "slope", "t0", "t1"});
      return control::Profile::ramp(opt("offset", 0.0, "a value in " + unit), num("slope", "a slope in " + unit + "/s"),
                                    opt("t0", 0.0, "a time in s"), opt("t1", -1.0, "a time in s"));
    }
    if (t == "triangle") {
      node.allowKeys({"type", "amplitude", "period", "offset"});
      return control::Profile::triangle(num("amplitude", "an amplitude in " + unit), num("period", "a period in s"),
                                        opt("offset", 0.0, "a value in " + unit));
    }
    if (t == "sine") {
      node.allowKeys({"type", "amplitude", "frequency", "phase", "offset", "until"});
      return control::Profile::sine(num("amplitude", "an amplitude in " + unit), num("frequency", "a frequency in Hz"),
                                    opt("phase", 0.0, "a phase in rad"), opt("offset", 0.0, "a value in " + unit),
                                    opt("until", std::numeric_limits<double>::infinity(), "a time in s"));
    }
    if (t == "piecewise") {
      node.allowKeys({"type", "times", "values", "hold"});
      const bool hold = node.has("hold") && node["hold"].asBool("true or false");
      return control::Profile::piecewise(node.required("times", "times in s").asDoubles(0, "a list of times in s"),
                                         node.required("values", "values").asDoubles(0, "a list of values in " + unit),
                                         hold);
    }
    if (t == "csv") {
      node.allowKeys({"type", "file", "column"});
      return control::Profile::csv(node.required("file", "CSV file, relative to this file").asPath(),
                                   node["column"].asString("", "a column name"));
    }
  } catch (const InputError& e) {
    node.relocate(e);
  }
  type.failExpected("a profile type (constant, step, ramp, triangle, sine, piecewise, csv)");
}

void solverJson(nlohmann::ordered_json& out, const sim::CvodeOptions& o) {
  const char* method = o.method == sim::Method::BDF ? "bdf" : o.method == sim::Method::Adams ? "adams" : "rosenbrock";
  out = {{"method", method},
         {"rtol", o.rtol},
         {"atol", o.atol},
         {"max_step", o.max_step},
         {"max_order", o.max_order},
         {"stability_limit_detection", o.stability_limit_detection},
         {"max_gamma_change", o.max_gamma_change}};
  if (o.analytic_jacobian) out["analytic_jacobian"] = true;
  if (o.method == sim::Method::Rosenbrock) {
    out["step"] = o.fixed_step;
    if (o.jacobian_defect > 0.0 && o.jacobian_every == sim::kAdaptiveJacobianEvery)
      out["jacobian_every"] = "adaptive";
    else
      out["jacobian_every"] = o.jacobian_every;
    if (o.jacobian_defect > 0.0) out["jacobian_defect"] = o.jacobian_defect;
    out["oscillations"] = o.resolve_oscillations ? "resolve" : "damp";
  }
}

void solverStatsJson(nlohmann::ordered_json& out, const sim::SolverStats& s) {
  out = {{"steps", s.steps},
         {"rhs_evals", s.rhs_evals},
         {"rhs_evals_jacobian", s.rhs_evals_jacobian},
         {"jac_evals", s.jac_evals},
         {"jac_reused", s.jac_reused},
         {"lin_setups", s.lin_setups},
         {"error_test_failures", s.error_test_failures},
         {"nonlinear_iterations", s.nonlinear_iterations},
         {"nonlinear_conv_failures", s.nonlinear_conv_failures},
         {"last_order", s.last_order},
         {"last_step_s", s.last_step},
         {"split_steps", s.split_steps},
         {"retaken_steps", s.retaken_steps},
         {"damped_steps", s.damped_steps}};
}

namespace detail {

std::vector<std::string> keyParts(const std::string& path) {
  std::vector<std::string> parts;
  std::string cur;
  for (const char ch : path) {
    if (ch == '.' || ch == '[' || ch == ']') {
      if (!cur.empty()) parts.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) parts.push_back(cur);
  return parts;
}

void applyOverrides(const io::YamlValue& root, const std::vector<std::string>& overrides) {
  const std::string& file = root.file();
  for (const std::string& o : overrides) {
    // "+key.path=value" may add mapping keys the file lacks (the experiment's loader then checks them as if they
    // were written in the file); "key.path=value" only replaces an existing scalar.
    const bool add = !o.empty() && o[0] == '+';
    const std::string spec = add ? o.substr(1) : o;
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("override " + o + ": expected key.path=value or +key.path=value");
    const std::string path = spec.substr(0, eq), value = spec.substr(eq + 1);
    const std::vector<std::string> parts = keyParts(path);
    if (parts.empty()) throw InputError("override " + o + ": expected key.path=value or +key.path=value");
    YAML::Node node = io::yamlNode(root);
    std::string walked;
    for (const std::string& p : parts) {
      walked += (walked.empty() ? "" : ".") + p;
      const bool index = !p.empty() && p.size() < 10 && p.find_first_not_of("0123456789") == std::string::npos;
      YAML::Node child;
      if (node.IsMap() && node[p].IsDefined()) {
        child = node[p];
      } else if (node.IsSequence() && index && std::stoul(p) < node.size()) {
        child = node[std::stoul(p)];
      } else if (add && !index && (node.IsMap() || node.IsNull())) {
        node[p] = YAML::Node(YAML::NodeType::Null);  // a null node becomes a mapping
        child = node[p];
      } else if (add) {
        throw InputError(file, 0, walked,
                         "override " + o + ": cannot add '" + walked + "'" +
                             (index ? " (list entries cannot be added)" : " (its parent is not a mapping)"));
      } else {
        throw InputError(file, 0, walked,
                         "override " + o + ": the file has no key '" + walked + "'" +
                             (node.IsMap() || node.IsNull() ? " (to add it, override +" + spec + ")" : ""));
      }
      node.reset(child);
    }
    if (!node.IsScalar() && !node.IsNull())
      throw InputError(file, 0, path, "override " + o + ": '" + path + "' is not a scalar");
    node = value;
  }
}

namespace {

/// Bounds on the copy of a document into the summary: YAML aliases can make a small file expand without
/// bound (an "alias bomb"), and deep nesting would recurse deeply.
constexpr long kMaxJsonValues = 200000;
constexpr int kMaxJsonDepth = 64;

nlohmann::ordered_json nodeToJson(const YAML::Node& node, const io::YamlValue& root, long& budget, int depth) {
  if (--budget < 0 || depth > kMaxJsonDepth)
    throw InputError(root.file() + ": the document is nested deeper than " + std::to_string(kMaxJsonDepth) +
                     " levels or expands to more than " + std::to_string(kMaxJsonValues) +
                     " values (YAML aliases?); expected an experiment description");
  if (node.IsMap()) {
    nlohmann::ordered_json out = nlohmann::ordered_json::object();
    for (const auto& kv : node) out[io::keyText(kv.first, root)] = nodeToJson(kv.second, root, budget, depth + 1);
    return out;
  }
  if (node.IsSequence()) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const auto& item : node) out.push_back(nodeToJson(item, root, budget, depth + 1));
    return out;
  }
  if (node.IsScalar()) {
    const std::string& s = node.Scalar();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (!s.empty() && end && *end == '\0' && std::isfinite(v)) return v;
    if (s == "true" || s == "false") return s == "true";
    return s;
  }
  return nullptr;
}
}  // namespace

void removeKey(const io::YamlValue& map, const std::string& key) {
  YAML::Node node = io::yamlNode(map);
  if (node.IsMap()) node.remove(key);
}

nlohmann::ordered_json yamlToJson(const io::YamlValue& value) {
  long budget = kMaxJsonValues;
  return nodeToJson(io::yamlNode(value), value, budget, 0);
}

nlohmann::ordered_json vectorJson(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(v[i]);
  return out;
}

std::string keyPattern(const std::string& key) {
  std::string out;
  bool in_index = false;
  for (const char c : key) {
    if (c == '[') in_index = true;
    if (c == ']') in_index = false;
    if (!in_index || c == '[') out += c;
  }
  return out;
}

std::string profileKeyUnit(const std::string& pattern, const std::string& prefix, const std::string& unit) {
  if (pattern.rfind(prefix, 0) != 0) return {};
  const std::string k = pattern.substr(prefix.size());
  for (const char* v : {"value", "initial", "final", "offset", "amplitude", "values[]"})
    if (k == v) return unit;
  if (k == "slope") return unit + "/s";
  for (const char* v : {"time", "t0", "t1", "period", "until", "times[]"})
    if (k == v) return "s";
  if (k == "frequency") return "Hz";
  if (k == "phase") return "rad";
  return {};
}

std::string patternKeyUnit(const std::string& key, const std::vector<std::pair<std::string, std::string>>& units,
                           const std::vector<std::pair<std::string, std::string>>& profiles) {
  const std::string p = keyPattern(key);
  for (const auto& [k, u] : units)
    if (p == k) return u;
  for (const auto& [prefix, u] : profiles)
    if (std::string unit = profileKeyUnit(p, prefix, u); !unit.empty()) return unit;
  return commonKeyUnit(key);
}

std::string commonKeyUnit(const std::string& key) {
  static const std::pair<const char*, const char*> units[] = {{"duration", "s"},
                                                              {"log_rate", "Hz"},
                                                              {"solver.rtol", "1"},
                                                              {"solver.atol", "1"},
                                                              {"solver.max_step", "s"},
                                                              {"solver.max_order", "1"},
                                                              {"solver.max_num_steps", "1"},
                                                              {"solver.max_gamma_change", "1"},
                                                              {"limits.steps", "1"},
                                                              {"limits.wall_time", "s"},
                                                              {"limits.log_rows", "1"},
                                                              {"joint_limits.stiffness", "N·m/rad"},
                                                              {"joint_limits.damping", "N·m·s/rad"}};
  for (const auto& [k, u] : units)
    if (key == k) return u;
  return {};
}

std::string tableKeyUnit(const std::vector<drive::ParameterInfo>& table, const std::string& key) {
  for (const auto& p : table)
    if (p.key == key || p.key == "positive." + key) return p.unit;
  return {};
}

}  // namespace detail
}  // namespace jointsim::experiments
