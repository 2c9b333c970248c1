// Experiment files (every registered type): load through the registry, then run in memory under a tight
// budget, so that loaders and the models they build both see the mutated values.
#include <algorithm>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  const std::string path = fuzz::writeInput("config/experiments/fuzz.yaml", data, size);
  try {
    auto experiment = experiments::loadExperiment(path);
    experiments::RunLimits limits = experiment->limits();
    limits.steps = std::min(limits.steps, 3000L);
    limits.log_rows = std::min(limits.log_rows, 20000L);
    limits.wall_time = 1.0;
    experiment->setLimits(limits);
    experiments::runInMemory(*experiment);
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
