// Sweep files of `jointsim batch`: the sweep loader, its run names and overrides, and loading the base
// experiment of every run with its overrides and faults (what batch does before starting a run).
#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/experiments/experiment.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  const std::string path = fuzz::writeInput("config/sweeps/fuzz.yaml", data, size);
  try {
    const experiments::Sweep sweep = experiments::loadSweep(path);
    size_t loaded = 0;
    for (const auto& run : sweep.runs) {
      if (!isSafeName(run.name)) __builtin_trap();  // a run name becomes a folder name
      if (++loaded > 3) break;                      // a few runs are enough to exercise overrides and faults
      try {
        experiments::loadExperiment(sweep.experiment, run.overrides, run.faults);
      } catch (const Error& e) {
        fuzz::note(e);
      }
    }
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
