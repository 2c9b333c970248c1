#include "experiments/config_common.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/io/output.hpp"

namespace jointsim::experiments::detail {

using io::YamlValue;

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
  auto opt = [&](const char* key, double fallback, const std::string& what) { return node[key].asDouble(fallback, what); };
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
                                         node.required("values", "values").asDoubles(0, "a list of values in " + unit), hold);
    }
    if (t == "csv") {
      node.allowKeys({"type", "file", "column"});
      return control::Profile::csv(node.required("file", "CSV file, relative to this file").asPath(),
                                   node["column"].asString("", "a column name"));
    }
  } catch (const InputError& e) {
    if (std::string(e.what()).rfind(node.file(), 0) == 0) throw;  // already located
    node.fail(e.what());
  }
  type.failExpected("a profile type (constant, step, ramp, triangle, sine, piecewise, csv)");
}

void applyOverrides(YAML::Node root, const std::vector<std::string>& overrides, const std::string& file) {
  for (const std::string& o : overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set " + o + ": expected key.path=value");
    const std::string path = o.substr(0, eq), value = o.substr(eq + 1);
    // Split "a.b[2].c" into a, b, 2, c.
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
    YAML::Node node = root;
    std::string walked;
    for (size_t k = 0; k < parts.size(); ++k) {
      const std::string& p = parts[k];
      walked += (walked.empty() ? "" : ".") + p;
      YAML::Node child;
      if (node.IsMap() && node[p].IsDefined()) {
        child = node[p];
      } else if (node.IsSequence() && !p.empty() && p.find_first_not_of("0123456789") == std::string::npos &&
                 std::stoul(p) < node.size()) {
        child = node[std::stoul(p)];
      } else {
        throw InputError("--set " + o + ": " + file + " has no key '" + walked + "'");
      }
      node.reset(child);
    }
    if (!node.IsScalar() && !node.IsNull())
      throw InputError("--set " + o + ": '" + path + "' in " + file + " is not a scalar");
    node = value;
  }
}

void writeYamlAsJson(io::JsonWriter& w, const YAML::Node& node) {
  if (node.IsMap()) {
    w.beginObject();
    for (const auto& kv : node) {
      w.key(kv.first.as<std::string>());
      writeYamlAsJson(w, kv.second);
    }
    w.endObject();
  } else if (node.IsSequence()) {
    w.beginArray();
    for (const auto& item : node) writeYamlAsJson(w, item);
    w.endArray();
  } else if (node.IsScalar()) {
    const std::string& s = node.Scalar();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (!s.empty() && end && *end == '\0' && std::isfinite(v)) {
      w.value(v);
    } else if (s == "true" || s == "false") {
      w.value(s == "true");
    } else {
      w.value(s);
    }
  } else {
    w.null();
  }
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

RunReport runAndRecord(const std::string& name, const std::string& type, const RunOptions& options,
                       const std::vector<std::string>& columns,
                       const std::function<SimulationOutcome(const std::function<void(const Eigen::VectorXd&)>&)>& simulate,
                       const std::function<void(io::JsonWriter&)>& write_parameters, double t_end) {
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
    w.key("type"); w.value(type);
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
    w.key("columns"); w.beginArray(); for (const auto& c : columns) w.value(c); w.endArray();
    w.key("parameters");
    write_parameters(w);
    w.endObject();
    io::writeFileAtomically(report.summary_path, os.str());
  };

  io::CsvWriter csv(report.csv_path, columns);
  try {
    // Progress on stderr (RunOptions::progress, set by the CLI when stderr is a terminal): from 2 s of wall
    // time on, at most 4 updates per second; the first column of every row is the simulated time.
    const auto start = std::chrono::steady_clock::now();
    auto last = start;
    bool shown = false;
    const SimulationOutcome r = simulate([&](const Eigen::VectorXd& row) {
      csv.writeRow(row);
      if (!options.progress) return;
      const auto now = std::chrono::steady_clock::now();
      const double wall = std::chrono::duration<double>(now - start).count();
      if (wall < 2.0 || std::chrono::duration<double>(now - last).count() < 0.25) return;
      last = now;
      shown = true;
      const double t = row[0], rtf = t / wall;
      if (t_end > 0.0 && rtf > 0.0)
        std::fprintf(stderr, "\r  %s: t = %.4g / %.4g s (%3.0f %%), real-time factor %.3g, ETA %.1f s   ", name.c_str(), t,
                     t_end, 100.0 * t / t_end, rtf, (t_end - t) / rtf);
      else
        std::fprintf(stderr, "\r  %s: t = %.4g s, real-time factor %.3g   ", name.c_str(), t, rtf);
      std::fflush(stderr);
    });
    if (shown) std::fprintf(stderr, "\n");
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

}  // namespace jointsim::experiments::detail
