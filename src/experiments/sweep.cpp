// Reading a sweep file (docs/batch.md): its runs from `runs`, `grid`, `sample` and `faults`, with their overrides.
#include "jointsim/experiments/batch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "experiments/sweep_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/sampling.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;

std::string scalarText(const YamlValue& v, const std::string& what) { return v.scalarText(what); }

// Run and sweep names name folders: safe names only (common/text.hpp).
std::string sanitize(const std::string& s) { return safeFileName(s); }

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// `set: {key.path: value, ...}` as "key.path=value" strings, in file order.
std::vector<std::string> readSet(const YamlValue& node) {
  std::vector<std::string> out;
  if (!node.defined()) return out;
  node.expectMap("a mapping {key.path: value, ...} of overrides");
  for (const auto& k : node.keys()) out.push_back(k + "=" + scalarText(node[k], "a scalar value for " + k));
  return out;
}

}  // namespace

std::string BatchRun::describe() const {
  std::string s;
  for (const auto& o : overrides) s += (s.empty() ? "" : "; ") + o;
  for (const auto& f : faults) s += (s.empty() ? "" : "; ") + std::string("fault ") + systems::describe(f);
  return s;
}

Sweep loadSweep(const std::string& path) { return loadSweepDocument(YamlValue::loadFile(path), path); }

Sweep loadSweepText(const std::string& text, const std::string& name) {
  return loadSweepDocument(YamlValue::loadString(text, name), name);
}

Sweep loadSweepDocument(const YamlValue& root, const std::string& path) {
  root.expectMap("a sweep mapping {sweep, runs, grid, sample, faults}");
  root.allowKeys({"sweep", "runs", "grid", "sample", "faults"});
  Sweep s;
  s.file = path;
  const YamlValue head = root.required("sweep", "mapping {name, experiment, set}");
  head.expectMap("a mapping {name, experiment, set}");
  head.allowKeys({"name", "experiment", "set"});
  s.name = head.required("name", "the sweep name").asString("a name");
  if (s.name.empty() || sanitize(s.name) != s.name)
    head["name"].failExpected("a name of letters, digits, '.', '-', '_'");
  s.experiment = head.required("experiment", "the base experiment file, relative to this file").asPath();
  if (!io::pathExists(s.experiment)) head["experiment"].fail("no such file: " + s.experiment);
  const std::vector<std::string> common = readSet(head["set"]);

  // Bounded work for any input: runs and override strings are counted before any is made (a 25 KB file once asked for
  // 100,000 runs x 500 sampled parameters: 4.4 GB before its first error).
  size_t total_runs = 0, total_overrides = 0;
  auto reserve = [&](double runs, double overrides_per_run, const YamlValue& where) {
    const double r = static_cast<double>(total_runs) + runs;
    const double o =
        static_cast<double>(total_overrides) + runs * (overrides_per_run + static_cast<double>(common.size()));
    if (r > static_cast<double>(kMaxSweepRuns))
      where.fail("the sweep would have " + formatNumber(r, 6) + " runs; at most " + std::to_string(kMaxSweepRuns) +
                 " runs per sweep file (split it, or use shards of several files)");
    if (o > static_cast<double>(kMaxSweepOverrides))
      where.fail("the sweep would hold " + formatNumber(o, 6) +
                 " overrides in all (runs x overrides per run, the common `set` included); at most " +
                 std::to_string(kMaxSweepOverrides));
    total_runs = static_cast<size_t>(r);
    total_overrides = static_cast<size_t>(o);
  };
  std::set<std::string> names;
  auto add = [&](BatchRun r, const YamlValue& where) {
    if (!names.insert(r.name).second) where.fail("duplicate run name '" + r.name + "'");
    r.overrides.insert(r.overrides.begin(), common.begin(), common.end());
    s.runs.push_back(std::move(r));
  };
  if (const YamlValue runs = root["runs"]; runs.defined()) {
    runs.expectSequence("a list of runs {name, set, faults}");
    reserve(static_cast<double>(runs.size()), 0.0, runs);
    for (size_t i = 0; i < runs.size(); ++i) {
      const YamlValue n = runs.at(i);
      n.expectMap("a run {name, set, faults}");
      n.allowKeys({"name", "set", "faults"});
      BatchRun r;
      r.name = n.required("name", "the run name").asString("a name");
      if (r.name.empty() || sanitize(r.name) != r.name)
        n["name"].failExpected("a name of letters, digits, '.', '-', '_'");
      r.overrides = readSet(n["set"]);
      reserve(0.0, static_cast<double>(r.overrides.size()), n);
      if (const YamlValue f = n["faults"]; f.defined()) {
        f.expectSequence("a list of faults {type, joint, value}");
        for (size_t k = 0; k < f.size(); ++k) r.faults.push_back(detail::readFault(f.at(k)));
      }
      add(std::move(r), n);
    }
  }
  if (const YamlValue grid = root["grid"]; grid.defined()) {
    grid.expectMap("a mapping {key.path: [values], ...}");
    std::vector<std::pair<std::string, std::vector<std::string>>> axes;
    for (const auto& k : grid.keys()) {
      const YamlValue v = grid[k];
      v.expectSequence("a list of values for " + k);
      if (v.size() == 0) v.failExpected("at least one value");
      std::vector<std::string> vals;
      for (size_t i = 0; i < v.size(); ++i) vals.push_back(scalarText(v.at(i), "a scalar value"));
      axes.emplace_back(k, vals);
    }
    double grid_runs = 1.0;
    for (const auto& axis : axes) grid_runs *= static_cast<double>(axis.second.size());
    if (!axes.empty()) reserve(grid_runs, static_cast<double>(axes.size()), grid);
    std::vector<size_t> idx(axes.size(), 0);
    while (!axes.empty()) {
      // Named by the values (last key component and value), so that editing the grid never gives an
      // existing folder other settings: e.g. grid-duration_0.5-rtol_1e-06.
      BatchRun r;
      r.name = "grid";
      for (size_t a = 0; a < axes.size(); ++a) {
        const std::string& key = axes[a].first;
        const size_t dot = key.find_last_of('.');
        r.name += "-" + sanitize((dot == std::string::npos ? key : key.substr(dot + 1)) + "_" + axes[a].second[idx[a]]);
        r.overrides.push_back(key + "=" + axes[a].second[idx[a]]);
      }
      add(std::move(r), grid);
      size_t a = 0;
      while (a < axes.size() && ++idx[a] == axes[a].second.size()) idx[a++] = 0;
      if (a == axes.size()) break;
    }
  }
  if (const YamlValue sample = root["sample"]; sample.defined()) {
    // Seeded random designs (experiments/sampling.hpp): runs sample-0 ... sample-(n-1), each with the sampled
    // values as overrides (%.17g: the run reads back exactly the sampled double).
    sample.expectMap("a mapping {design, runs, seed, parameters}");
    sample.allowKeys({"design", "runs", "seed", "parameters"});
    const YamlValue design_node = sample.required("design", "monte_carlo or latin_hypercube");
    SamplingDesign design{};
    try {
      design = samplingDesignFromString(design_node.asString("monte_carlo or latin_hypercube"));
    } catch (const InputError& e) {
      design_node.fail(e.what());
    }
    const YamlValue runs_node = sample.required("runs", "the number of runs");
    const long n = runs_node.asInt("a number of runs >= 1");
    if (n < 1 || n > 100000) runs_node.failExpected("a number of runs from 1 to 100000");
    const YamlValue seed_node = sample.required("seed", "an integer seed (the design is reproducible from it)");
    const long seed = seed_node.asInt("an integer seed >= 0");
    if (seed < 0) seed_node.failExpected("an integer seed >= 0");
    const YamlValue params = sample.required("parameters", "a mapping {key.path: {distribution, ...}}");
    params.expectMap("a mapping {key.path: {distribution, ...}}");
    std::vector<std::string> keys = params.keys();
    if (keys.empty()) params.failExpected("at least one parameter");
    std::vector<ParameterDistribution> dists;
    for (const std::string& k : keys) {
      const YamlValue d = params[k];
      d.expectMap("{distribution: uniform|log_uniform, low, high} or {distribution: normal, mean, std}");
      const YamlValue kind = d.required("distribution", "uniform, normal or log_uniform");
      const std::string kind_text = kind.asString("uniform, normal or log_uniform");
      ParameterDistribution p;
      if (kind_text == "uniform" || kind_text == "log_uniform") {
        d.allowKeys({"distribution", "low", "high"});
        p.kind =
            kind_text == "uniform" ? ParameterDistribution::Kind::Uniform : ParameterDistribution::Kind::LogUniform;
        p.a = d.required("low", "the lower bound").asDouble("a number");
        p.b = d.required("high", "the upper bound").asDouble("a number");
        if (!(p.b > p.a)) d["high"].failExpected("an upper bound above low = " + formatNumber(p.a));
        if (p.kind == ParameterDistribution::Kind::LogUniform && !(p.a > 0.0))
          d["low"].failExpected("a lower bound > 0 (log-uniform)");
      } else if (kind_text == "normal") {
        d.allowKeys({"distribution", "mean", "std"});
        p.kind = ParameterDistribution::Kind::Normal;
        p.a = d.required("mean", "the mean").asDouble("a number");
        p.b = d.required("std", "the standard deviation").asDouble("a number");
        if (!(p.b > 0.0)) d["std"].failExpected("a standard deviation > 0");
      } else {
        kind.failExpected("uniform, normal or log_uniform");
      }
      dists.push_back(p);
    }
    reserve(static_cast<double>(n), static_cast<double>(keys.size()), sample);
    const auto values = sampleDesign(design, static_cast<int>(n), dists, static_cast<std::uint64_t>(seed));
    const int width = static_cast<int>(std::to_string(n - 1).size());
    for (long i = 0; i < n; ++i) {
      BatchRun r;
      std::string index = std::to_string(i);
      r.name = "sample-" + std::string(static_cast<size_t>(width) - index.size(), '0') + index;
      r.design = design == SamplingDesign::LatinHypercube ? "latin_hypercube" : "monte_carlo";
      r.seed = seed;
      for (size_t j = 0; j < keys.size(); ++j)
        r.overrides.push_back(keys[j] + "=" + formatNumber(values[static_cast<size_t>(i)][j], 17));
      add(std::move(r), sample);
    }
  }
  if (const YamlValue faults = root["faults"]; faults.defined()) {
    faults.expectSequence("a list of fault scenarios {type, joints, values}");
    for (size_t i = 0; i < faults.size(); ++i) {
      const YamlValue n = faults.at(i);
      n.expectMap("a fault scenario {type, joints, values}");
      n.allowKeys({"type", "joints", "values", JOINTSIM_TIME_LAW_KEYS});
      systems::Fault proto;
      proto.type = detail::readFaultType(n.required("type", "a fault type"));
      detail::readTimeLaw(n, proto);
      const YamlValue joints = n.required("joints", "a list of joint names");
      joints.expectSequence("a list of joint names");
      const auto values = n.required("values", "a list of severities").asDoubles(0, "a list of numbers");
      if (values.empty()) n["values"].failExpected("at least one value");
      reserve(static_cast<double>(joints.size()) * static_cast<double>(values.size()), 0.0, n);
      // Run names: <type>-<joint>-<value>, with the onset and progression when given (so that scenarios differing
      // only in their time law get distinct names).
      std::string law;
      if (proto.onset > 0.0) law += "-at" + number(proto.onset);
      if (proto.progression != systems::Progression::Step)
        law += proto.progression == systems::Progression::Linear ? "-linear" : "-exponential";
      for (size_t j = 0; j < joints.size(); ++j) {
        const std::string joint = joints.at(j).asString("a joint name");
        for (double v : values) {
          systems::Fault f = proto;
          f.joint = joint;
          f.value = v;
          detail::checkAt(n, f);  // a severity out of range fails the sweep, not only its run
          BatchRun r;
          r.name = sanitize(std::string(systems::toString(f.type)) + "-" + joint + "-" + number(v) + law);
          r.faults.push_back(f);
          add(std::move(r), n);
        }
      }
    }
  }
  if (s.runs.empty()) root.fail("the sweep has no runs (give runs, grid or faults)");
  return s;
}

}  // namespace jointsim::experiments
