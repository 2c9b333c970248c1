// Sweep files of `jointsim batch`: the sweep loader (explicit runs, grids, sampling designs, fault scenarios with
// their time laws), its run names and overrides, and what `jointsim validate` does with a run before a batch starts
// it: the base experiment loaded with the run's overrides and faults, then the run's checks (checkRunSettings: the
// log grid, the time events of the faults, e.g. the episodes of an intermittent fault). At most three runs per input
// (the first, the last and one chosen by the input), so that the fault scenarios after a long sampled design are
// reached and no input takes long.
#include <set>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/systems/faults.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  const std::string path = fuzz::writeInput("config/sweeps/fuzz.yaml", data, size);
  try {
    const experiments::Sweep sweep = experiments::loadSweep(path);
    const size_t n = sweep.runs.size();
    for (const auto& run : sweep.runs) {
      if (!isSafeName(run.name)) __builtin_trap();  // a run name becomes a folder name
      // A sampled run carries its design and seed (manifest labels), a listed or fault run neither.
      if (!run.design.empty() && run.design != "monte_carlo" && run.design != "latin_hypercube") __builtin_trap();
      if (run.design.empty() != (run.seed < 0)) __builtin_trap();
      for (const systems::Fault& f : run.faults) {
        try {
          systems::checkFault(f);  // the loader checked every fault with its time law: it passes again
        } catch (const InputError&) {
          __builtin_trap();
        }
      }
    }
    uint64_t hash = 1469598103934665603ull;  // FNV-1a of the input: which middle run is loaded
    for (size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 1099511628211ull;
    std::set<size_t> chosen;
    if (n > 0) chosen = {0, n - 1, static_cast<size_t>(hash % n)};
    for (const size_t i : chosen) {
      const experiments::BatchRun& run = sweep.runs[i];
      try {
        run.describe();
        experiments::runSettings(sweep, run);
        for (const systems::Fault& f : run.faults) systems::describe(f);
        auto e = experiments::loadExperiment(sweep.experiment, run.overrides, run.faults);
        experiments::checkRunSettings(*e);
      } catch (const Error& e) {
        fuzz::note(e);
      }
    }
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
