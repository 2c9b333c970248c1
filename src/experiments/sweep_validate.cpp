// Checking a sweep or experiment file without running it (`jointsim validate`): every run loaded, the likeliest
// failures first.
#include "jointsim/experiments/batch.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <csignal>

#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "experiments/sweep_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/sampling.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::experiments {

using io::YamlValue;
namespace fs = std::filesystem;

namespace {

// The order in which validate checks a sweep's runs: first those most likely to fail, so that an error is reported
// in seconds even in a 100,000-run sweep (each run is loaded in full, a few ms each); then all the others, in sweep
// order. First: run 0; for each override key and fault type, the runs with its smallest and largest numeric value;
// for each override or fault with few distinct values (a grid axis, a list), the first run that has each value.
std::vector<size_t> validationOrder(const Sweep& sweep) {
  const size_t n = sweep.runs.size();
  std::vector<size_t> order;
  std::vector<char> queued(n, 0);
  auto push = [&](size_t i) {
    if (i < n && !queued[i]) {
      queued[i] = 1;
      order.push_back(i);
    }
  };
  push(0);
  struct Extremes {
    double low = 0, high = 0;
    size_t at_low = 0, at_high = 0;
    bool any = false;
  };
  std::map<std::string, Extremes> extremes;
  std::map<std::string, std::map<std::string, size_t>> first;  // key -> value -> first run (capped per key)
  constexpr size_t kDistinct = 1000;
  auto see = [&](const std::string& key, const std::string& value, size_t i) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end != value.c_str() && *end == '\0' && std::isfinite(v)) {
      Extremes& x = extremes[key];
      if (!x.any || v < x.low) x.low = v, x.at_low = i;
      if (!x.any || v > x.high) x.high = v, x.at_high = i;
      x.any = true;
    }
    auto& values = first[key];
    if (values.size() < kDistinct) values.emplace(value, i);
  };
  for (size_t i = 0; i < n; ++i) {
    const BatchRun& run = sweep.runs[i];
    for (const std::string& o : run.overrides) {
      const size_t eq = o.find('=');
      see(o.substr(0, eq), eq == std::string::npos ? "" : o.substr(eq + 1), i);
    }
    for (const systems::Fault& f : run.faults) {
      const std::string type = systems::toString(f.type);
      see("fault " + type + " joint", f.joint, i);
      see("fault " + type + " value", formatShortest(f.value), i);
      see("fault " + type, systems::describe(f), i);
    }
  }
  for (const auto& [key, x] : extremes) {
    push(x.at_low);
    push(x.at_high);
  }
  for (const auto& [key, values] : first)
    if (values.size() < kDistinct)
      for (const auto& [value, i] : values) push(i);
  for (size_t i = 0; i < n; ++i) push(i);
  return order;
}

}  // namespace

ValidationReport validateFile(const std::string& path, const std::vector<std::string>& overrides, bool progress) {
  ValidationReport r;
  std::set<std::string> seen;
  auto note = [&](const Experiment& e) {
    for (const io::InputFile& f : e.inputs())
      if (seen.insert(f.path).second) r.files.push_back(f.path);
  };
  auto describeBase = [&](Experiment& e) {
    r.type = e.type();
    r.states = e.plant().stateSize();
    r.signals = static_cast<int>(e.plant().signalNames().size());
    r.duration = e.simulateOptions().t_end;
  };
  const YamlValue root = YamlValue::loadFile(path);
  if (root.isMap() && root.has("sweep")) {
    const Sweep sweep = loadSweep(path);
    r.kind = "sweep";
    r.name = sweep.name;
    if (seen.insert(std::filesystem::absolute(path).lexically_normal().string()).second)
      r.files.push_back(std::filesystem::absolute(path).lexically_normal().string());
    const std::vector<size_t> order = validationOrder(sweep);
    const auto start = std::chrono::steady_clock::now();
    auto last_shown = start;
    bool shown = false;
    for (size_t k = 0; k < order.size(); ++k) {
      const BatchRun& run = sweep.runs[order[k]];
      if (const int sig = stopRequested())
        throw sim::Interrupted(SolverError("validate interrupted (signal " + std::to_string(sig) + ") after " +
                                               std::to_string(r.runs) + " of " + std::to_string(sweep.runs.size()) +
                                               " runs",
                                           0.0, "INTERRUPTED", "validate"),
                               sim::SimulationResult{}, sig);
      if (progress) {  // a terminal: from 1 s on, at most 4 updates a second
        const auto now = std::chrono::steady_clock::now();
        if (std::chrono::duration<double>(now - start).count() > 1.0 &&
            std::chrono::duration<double>(now - last_shown).count() > 0.25) {
          const double per_run = std::chrono::duration<double>(now - start).count() / static_cast<double>(k);
          std::fprintf(stderr, "\r  validated %zu of %zu runs, about %s left   ", k, order.size(),
                       formatDuration(per_run * static_cast<double>(order.size() - k)).c_str());
          std::fflush(stderr);
          last_shown = now;
          shown = true;
        }
      }
      std::vector<std::string> o = run.overrides;
      o.insert(o.end(), overrides.begin(), overrides.end());
      std::unique_ptr<Experiment> e;
      try {
        e = loadExperiment(sweep.experiment, o, run.faults);
        checkRunSettings(*e);
      } catch (const InputError& err) {
        if (shown) std::fputc('\n', stderr);
        throw InputError(sweep.file + ": run '" + run.name + "': " + err.what());
      }
      if (r.runs == 0) describeBase(*e);
      note(*e);
      ++r.runs;
    }
    if (shown) std::fputc('\n', stderr);
    return r;
  }
  std::unique_ptr<Experiment> e = loadExperiment(path, overrides);
  checkRunSettings(*e);
  r.kind = "experiment";
  r.name = e->name();
  r.runs = 1;
  describeBase(*e);
  note(*e);
  return r;
}

}  // namespace jointsim::experiments
