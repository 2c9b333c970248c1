// FMU description: the variables of an experiment, their JSON form (resources/jointsim_fmu.json) and
// modelDescription.xml (FMI 2.0 Co-Simulation).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

namespace jointsim::fmi {

namespace {

/// All 17 significant digits: the XML start values read back as the same doubles.
std::string number(double v) { return formatNumber(v, 17); }

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
          out += ' ';
        else
          out += c;
    }
  }
  return out;
}

const char* causalityName(Causality c) {
  switch (c) {
    case Causality::Input: return "input";
    case Causality::Output: return "output";
    case Causality::Parameter: return "parameter";
  }
  return "output";
}

Causality parseCausality(const std::string& s, const std::string& where) {
  if (s == "input") return Causality::Input;
  if (s == "output") return Causality::Output;
  if (s == "parameter") return Causality::Parameter;
  throw InputError(where + ": causality '" + s + "', expected input, output or parameter");
}

/// SI base-unit exponents (kg, m, s, A, rad) of the units jointsim's signals use.
struct BaseUnit {
  int kg = 0, m = 0, s = 0, A = 0, rad = 0;
};
bool baseUnit(const std::string& unit, BaseUnit& b) {
  static const std::map<std::string, BaseUnit> units = {
      {"rad", {0, 0, 0, 0, 1}},         {"rad/s", {0, 0, -1, 0, 1}}, {"rad/s2", {0, 0, -2, 0, 1}},
      {"m", {0, 1, 0, 0, 0}},           {"m/s", {0, 1, -1, 0, 0}},   {"s", {0, 0, 1, 0, 0}},
      {"A", {0, 0, 0, 1, 0}},           {"V", {1, 2, -3, -1, 0}},    {"N.m", {1, 2, -2, 0, 0}},
      {"N", {1, 1, -2, 0, 0}},          {"W", {1, 2, -3, 0, 0}},     {"J", {1, 2, -2, 0, 0}},
      {"kg.m2", {1, 2, 0, 0, 0}},       {"Hz", {0, 0, -1, 0, 0}},    {"N.m/rad", {1, 2, -2, 0, -1}},
      {"N.m.s/rad", {1, 2, -1, 0, -1}}, {"Ohm", {1, 2, -3, -2, 0}},  {"1", {0, 0, 0, 0, 0}},
      {"1/s", {0, 0, -1, 0, 0}},        {"kg", {1, 0, 0, 0, 0}},     {"N/m", {1, 0, -2, 0, 0}},
      {"N.s/m", {1, 0, -1, 0, 0}},      {"H", {1, 2, -2, -2, 0}},    {"N.m/A", {1, 2, -2, -1, 0}},
      {"V.s/rad", {1, 2, -2, -1, -1}},  {"s/rad", {0, 0, 1, 0, -1}}, {"A.s/rad", {0, 0, 1, 1, -1}},
      {"A/rad", {0, 0, 0, 1, -1}},      {"V/A", {1, 2, -3, -2, 0}},  {"V/(A.s)", {1, 2, -4, -2, 0}}};
  auto it = units.find(unit);
  if (it == units.end()) return false;
  b = it->second;
  return true;
}

}  // namespace

std::string fmuUnit(const std::string& unit) {
  static const std::pair<const char*, const char*> ascii[] = {{"·", "."},   {"²", "2"}, {"³", "3"},
                                                              {"Ω", "Ohm"}, {"µ", "u"}, {"°", "deg"}};
  std::string out = unit;
  for (const auto& [from, to] : ascii)
    for (size_t at = out.find(from); at != std::string::npos;
         at = out.find(from, at + std::char_traits<char>::length(to)))
      out.replace(at, std::char_traits<char>::length(from), to);
  return out;
}

namespace {

// Every number of the document with its key path (a.b, a[0], a[0][1]) and its FMI name under the structured
// naming convention (a.b, a[0], a[0,1]).
void collectNumbers(const nlohmann::ordered_json& j, const std::string& path, const std::string& name,
                    std::vector<Variable>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      collectNumbers(it.value(), path.empty() ? it.key() : path + "." + it.key(),
                     name.empty() ? it.key() : name + "." + it.key(), out);
  } else if (j.is_array()) {
    const bool nested = !name.empty() && name.back() == ']';
    for (size_t i = 0; i < j.size(); ++i) {
      const std::string index = std::to_string(i);
      collectNumbers(j[i], path + "[" + index + "]",
                     nested ? name.substr(0, name.size() - 1) + "," + index + "]" : name + "[" + index + "]", out);
    }
  } else if (j.is_number()) {
    Variable v;
    v.name = name;
    v.causality = Causality::Parameter;
    v.key = path;
    v.start = j.get<double>();
    v.description = "experiment file key " + path + " (as --set " + path + "=VALUE)";
    out.push_back(v);
  }
}

}  // namespace

namespace {

// Which outputs depend directly on which inputs (FMI ModelStructure): measured as the FMU behaves after its build (all
// inputs at their start values, fmi2GetReal right after fmi2SetReal): an input changed by two different amounts at the
// start state changes the output without a step. Inputs act on the other outputs only through the states.
void directDependencies(const sim::Plant& plant, FmuDescription& d) {
  std::vector<size_t> inputs;
  for (size_t i = 0; i < d.variables.size(); ++i)
    if (d.variables[i].causality == Causality::Input) inputs.push_back(i);
  std::vector<int> port(d.variables.size(), -1);
  for (size_t i : inputs) port[i] = sim::inputIndex(plant, d.variables[i].port);
  sim::CvodeOptions options;
  sim::Simulator base(plant, options);
  for (size_t i : inputs) plant.setInput(base.plantState(), port[i], d.variables[i].start);
  const Eigen::VectorXd s0 = base.signals();
  for (auto& v : d.variables)
    if (v.causality == Causality::Output) v.depends_known = true;
  for (size_t i : inputs) {
    for (const double delta : {0.37, -0.61}) {
      sim::Simulator probe(base);
      plant.setInput(probe.plantState(), port[i],
                     d.variables[i].start + delta * (1.0 + std::abs(d.variables[i].start)));
      const Eigen::VectorXd s1 = probe.signals();
      for (auto& v : d.variables)
        if (v.causality == Causality::Output && s1[v.signal] != s0[v.signal] &&
            (v.depends.empty() || v.depends.back() != static_cast<int>(i)))
          v.depends.push_back(static_cast<int>(i));
    }
  }
}

}  // namespace

FmuDescription describe(experiments::Experiment& experiment, const ExportOptions& options,
                        const std::string& model_identifier) {
  FmuDescription d;
  d.model_identifier = model_identifier;
  d.experiment_type = experiment.type();
  d.stop_time = experiment.simulateOptions().t_end;
  d.step_size = options.step_size;
  if (experiment.config().contains("experiment") && experiment.config()["experiment"].contains("description") &&
      experiment.config()["experiment"]["description"].is_string())
    d.description = experiment.config()["experiment"]["description"].get<std::string>();

  sim::Plant& plant = experiment.plant();
  std::set<std::string> names;
  auto add = [&](Variable v) {
    if (!names.insert(v.name).second) throw InputError("FMU export: variable '" + v.name + "' given twice");
    d.variables.push_back(std::move(v));
  };

  // Inputs: the plant's input ports (sim::InputPort) that the --inputs specs select. A spec is MODE (every group's
  // input of that mode, e.g. "voltage" for every joint, "setpoint" for q, qd and qdd) or GROUP:MODE (one joint).
  const std::vector<sim::InputPort> ports = plant.inputPorts();
  {
    auto start_state = plant.makeState();
    plant.start(*start_state, 0.0, plant.initialState());  // the inputs' values at the start
    std::map<std::string, std::string> mode_of_group;
    for (const std::string& spec : options.inputs) {
      const auto colon = spec.find(':');
      const std::string group = colon == std::string::npos ? std::string() : spec.substr(0, colon);
      const std::string mode = colon == std::string::npos ? spec : spec.substr(colon + 1);
      std::set<std::string> modes, groups;
      int matched = 0;
      for (size_t i = 0; i < ports.size(); ++i) {
        const sim::InputPort& p = ports[i];
        const std::string p_mode = p.mode.empty() ? p.name : p.mode;
        modes.insert(p_mode);
        if (!p.group.empty()) groups.insert(p.group);
        if (p_mode != mode || (!group.empty() && p.group != group)) continue;
        ++matched;
        if (!p.group.empty()) {
          std::string& given = mode_of_group[p.group];
          if (!given.empty() && given != mode)
            throw InputError("FMU export: " + p.group + " has two command ports as inputs (" + given + " and " + mode +
                             ")");
          given = mode;
        }
        Variable v;
        const std::string suffix = p.group.empty() ? p.name : p.name.substr(p.group.size() + 1);
        v.name = p.group.empty() ? (p.name == "command" ? std::string("cmd_input") : "cmd_" + p.name)
                                 : "cmd_" + suffix + "_" + p.group;
        v.causality = Causality::Input;
        v.unit = fmuUnit(p.unit);
        v.description = p.description;
        v.start = plant.input(*start_state, static_cast<int>(i));
        v.port = p.name;
        add(v);
      }
      if (matched == 0) {
        if (!group.empty() && groups.count(group) == 0)
          throw InputError("FMU export: input '" + spec + "': no joint '" + group + "' (the plant's are " +
                           join(std::vector<std::string>(groups.begin(), groups.end()), ", ") + ")");
        throw InputError(
            "FMU export: input '" + spec + "': " + plant.name() + " has no input of mode '" + mode + "'" +
            (group.empty() ? "" : " at " + group) + " (its modes: " +
            (modes.empty() ? std::string("none") : join(std::vector<std::string>(modes.begin(), modes.end()), ", ")) +
            ")");
      }
    }
  }

  // Outputs.
  const auto& signals = plant.signalNames();
  std::vector<int> chosen;
  if (options.outputs.empty()) {
    for (size_t i = 0; i < signals.size(); ++i) chosen.push_back(static_cast<int>(i));
  } else {
    for (const std::string& o : options.outputs) chosen.push_back(sim::signalIndex(plant, o));
  }
  for (int i : chosen) {
    Variable v;
    std::tie(v.name, v.unit) = splitColumn(signals[static_cast<size_t>(i)]);
    v.unit = fmuUnit(v.unit);
    v.causality = Causality::Output;
    v.signal = i;
    v.description = "signal " + signals[static_cast<size_t>(i)];
    add(v);
  }

  // Drive parameters of a robot with drives: the faults that apply to each drive, at their neutral values.
  if (const systems::RobotSystem* robot = experiment.robotSystem()) {
    for (const systems::DriveSpec& drive : robot->drives()) {
      for (const std::string& type_name : systems::faultTypeNames()) {
        systems::Fault f;
        f.type = systems::faultTypeFromString(type_name);
        f.joint = drive.joint;
        if (!f.parameterFault())
          continue;  // intermittent sensor faults and bearing ripple have time laws, no neutral value
        if (!systems::faultApplies(drive, f.type)) continue;
        const bool offset = f.type == systems::FaultType::BacklashAdd || f.type == systems::FaultType::SensorBias;
        Variable v;
        v.name = "drives." + drive.joint + "." + type_name;
        v.causality = Causality::Parameter;
        v.unit = offset ? "rad" : "1";
        v.start = offset ? 0.0 : 1.0;
        v.key = drive.joint;
        v.fault = type_name;
        // The severity ranges of checkFault (faults.hpp): a factor in (0, 100], a backlash in [0, 0.5] rad, a bias
        // within ±π rad.
        if (f.type == systems::FaultType::BacklashAdd) {
          v.min = 0.0;
          v.max = 0.5;
        } else if (f.type == systems::FaultType::SensorBias) {
          v.min = -kPi;
          v.max = kPi;
        } else {
          v.max = 100.0;
        }
        v.description =
            "drive of " + drive.joint + ": " + type_name + (offset ? " [rad]" : " (factor on the robot file's value)");
        add(v);
      }
    }
  }

  // Parameters: the experiment file's numbers, but for `duration` (the importer sets the stop time; the DefaultExperiment
  // carries it).
  // Parameters of the drives' components (their parameter tables, drive/parameters.hpp): every scalar with its unit
  // and range, applied as the experiment file's drives: key ("+drives.JOINT.COMPONENT.KEY=VALUE"). Table rows
  // (keys with an index, e.g. table friction's tau_pos[1][1]) are not offered: an override cannot add list entries.
  const systems::RobotSystem* robot = experiment.robotSystem();
  if (robot != nullptr) {
    for (const systems::DriveSpec& drive : robot->drives())
      for (const std::string& component : systems::driveComponents())
        for (const drive::ParameterInfo& p : systems::driveParameterTable(drive, component)) {
          if (p.key.find('[') != std::string::npos) continue;
          Variable v;
          v.name = "drives." + drive.joint + "." + component + "." + p.key;
          v.causality = Causality::Parameter;
          v.unit = fmuUnit(p.unit);
          v.start = p.value;
          v.key = "+" + v.name;  // the override that sets it
          if (!p.range.min_open && std::isfinite(p.range.min)) v.min = p.range.min;
          if (!p.range.max_open && std::isfinite(p.range.max)) v.max = p.range.max;
          v.description = "drive of " + drive.joint + ": " + component + " " + p.description + " [" + p.unit +
                          "], in " + p.range.text();
          add(v);
        }
  }

  // Parameters: the experiment file's numbers with a known unit, but for `duration` (the importer sets the stop time;
  // the DefaultExperiment carries it) and a robot's drives: (offered above from the tables).
  std::vector<Variable> params;
  collectNumbers(experiment.config(), "", "", params);
  for (auto& p : params) {
    if (p.key == "duration" || (robot != nullptr && p.key.rfind("drives.", 0) == 0)) continue;
    p.unit = fmuUnit(experiment.keyUnit(p.key));
    if (p.unit.empty()) {
      d.unoffered.push_back(p.key);
      continue;
    }
    add(std::move(p));
  }

  directDependencies(plant, d);
  return d;
}

nlohmann::ordered_json FmuDescription::toJson() const {
  nlohmann::ordered_json j;
  j["format"] = "jointsim FMU description 1";
  j["model_identifier"] = model_identifier;
  j["guid"] = guid;
  j["experiment_file"] = experiment_file;
  j["experiment_type"] = experiment_type;
  j["description"] = description;
  j["stop_time"] = stop_time;
  j["step_size"] = step_size;
  j["overrides"] = overrides;
  auto& vars = j["variables"] = nlohmann::ordered_json::array();
  for (const Variable& v : variables) {
    nlohmann::ordered_json x;
    x["name"] = v.name;
    x["causality"] = causalityName(v.causality);
    x["unit"] = v.unit;
    x["description"] = v.description;
    x["start"] = v.start;
    x["port"] = v.port;
    x["signal"] = v.signal;
    x["key"] = v.key;
    x["fault"] = v.fault;
    vars.push_back(std::move(x));
  }
  return j;
}

namespace {
// An index of the description: a JSON integer within int's range (a float or a huge number is malformed, not cast).
int indexField(const nlohmann::ordered_json& x, const char* key, const std::string& where) {
  const auto& v = x.at(key);
  if (v.is_number_integer()) {
    const auto n = v.is_number_unsigned()
                       ? static_cast<long long>(std::min<unsigned long long>(v.get<unsigned long long>(), 1ULL << 40))
                       : v.get<long long>();
    if (n >= -1 && n <= std::numeric_limits<int>::max()) return static_cast<int>(n);
  }
  throw InputError(where + ": malformed FMU description: " + key + " = " + v.dump() +
                   " (expected an integer index >= -1)");
}
}  // namespace

FmuDescription FmuDescription::fromJson(const nlohmann::ordered_json& j, const std::string& where) {
  FmuDescription d;
  try {
    if (j.value("format", "") != "jointsim FMU description 1")
      throw InputError(where + ": not a jointsim FMU description (key format)");
    d.model_identifier = j.at("model_identifier").get<std::string>();
    d.guid = j.at("guid").get<std::string>();
    d.experiment_file = j.at("experiment_file").get<std::string>();
    d.experiment_type = j.at("experiment_type").get<std::string>();
    d.description = j.at("description").get<std::string>();
    d.stop_time = j.at("stop_time").get<double>();
    d.step_size = j.at("step_size").get<double>();
    d.overrides = j.at("overrides").get<std::vector<std::string>>();
    for (const auto& x : j.at("variables")) {
      Variable v;
      v.name = x.at("name").get<std::string>();
      v.causality = parseCausality(x.at("causality").get<std::string>(), where);
      v.unit = x.at("unit").get<std::string>();
      v.description = x.at("description").get<std::string>();
      v.start = x.at("start").get<double>();
      v.port = x.at("port").get<std::string>();
      v.signal = indexField(x, "signal", where);
      v.key = x.at("key").get<std::string>();
      v.fault = x.at("fault").get<std::string>();
      d.variables.push_back(std::move(v));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(where + ": malformed FMU description: " + e.what());
  }
  return d;
}

std::string FmuDescription::modelDescriptionXml() const {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"" << xmlEscape(model_identifier) << "\" guid=\""
    << xmlEscape(guid) << "\" description=\"" << xmlEscape(description)
    << "\" generationTool=\"jointsim\" variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">\n"
    << "  <CoSimulation modelIdentifier=\"" << xmlEscape(model_identifier)
    << "\" canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\""
       " maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\""
       " canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\""
       " providesDirectionalDerivative=\"false\"/>\n";
  std::set<std::string> units;
  for (const Variable& v : variables)
    if (!v.unit.empty()) units.insert(v.unit);
  if (!units.empty()) {
    x << "  <UnitDefinitions>\n";
    for (const std::string& u : units) {
      BaseUnit b;
      x << "    <Unit name=\"" << xmlEscape(u) << "\"";
      if (baseUnit(u, b)) {
        x << "><BaseUnit";
        if (b.kg) x << " kg=\"" << b.kg << "\"";
        if (b.m) x << " m=\"" << b.m << "\"";
        if (b.s) x << " s=\"" << b.s << "\"";
        if (b.A) x << " A=\"" << b.A << "\"";
        if (b.rad) x << " rad=\"" << b.rad << "\"";
        x << "/></Unit>\n";
      } else {
        x << "/>\n";
      }
    }
    x << "  </UnitDefinitions>\n";
  }
  // The categories of the instance's log messages (fmi::Instance; fmi2SetDebugLogging selects among them).
  x << "  <LogCategories>\n"
       "    <Category name=\"logInfo\" description=\"progress: loading the experiment, settings that apply\"/>\n"
       "    <Category name=\"logWarning\" description=\"a setting ignored or changed\"/>\n"
       "    <Category name=\"logError\" description=\"a call refused or failed (with the simulated time and "
       "component of a solver failure)\"/>\n"
       "  </LogCategories>\n";
  x << "  <DefaultExperiment startTime=\"0\" stopTime=\"" << number(stop_time) << "\" stepSize=\"" << number(step_size)
    << "\"/>\n  <ModelVariables>\n";
  for (size_t i = 0; i < variables.size(); ++i) {
    const Variable& v = variables[i];
    x << "    <ScalarVariable name=\"" << xmlEscape(v.name) << "\" valueReference=\"" << i << "\" description=\""
      << xmlEscape(v.description) << "\" causality=\"" << causalityName(v.causality) << "\"";
    switch (v.causality) {
      case Causality::Input:
        x << " variability=\"continuous\">\n      <Real start=\"" << number(v.start) << "\"";
        break;
      case Causality::Output: x << " variability=\"continuous\" initial=\"calculated\">\n      <Real"; break;
      case Causality::Parameter:
        x << " variability=\"fixed\" initial=\"exact\">\n      <Real start=\"" << number(v.start) << "\"";
        break;
    }
    if (!v.unit.empty()) x << " unit=\"" << xmlEscape(v.unit) << "\"";
    if (std::isfinite(v.min)) x << " min=\"" << number(v.min) << "\"";
    if (std::isfinite(v.max)) x << " max=\"" << number(v.max) << "\"";
    x << "/>\n    </ScalarVariable>\n";
  }
  x << "  </ModelVariables>\n  <ModelStructure>\n";
  std::ostringstream outputs;
  for (size_t i = 0; i < variables.size(); ++i)
    if (variables[i].causality == Causality::Output) {
      outputs << "      <Unknown index=\"" << i + 1 << "\"";
      if (variables[i].depends_known) {
        outputs << " dependencies=\"";
        for (size_t k = 0; k < variables[i].depends.size(); ++k)
          outputs << (k ? " " : "") << variables[i].depends[k] + 1;
        outputs << "\"";
      }
      outputs << "/>\n";
    }
  if (!outputs.str().empty()) {
    x << "    <Outputs>\n" << outputs.str() << "    </Outputs>\n";
    x << "    <InitialUnknowns>\n" << outputs.str() << "    </InitialUnknowns>\n";
  }
  x << "  </ModelStructure>\n</fmiModelDescription>\n";
  return x.str();
}

}  // namespace jointsim::fmi
