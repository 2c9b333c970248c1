// The registry of experiment types: the one table every front end reads (registry.hpp).
#include "jointsim/experiments/registry.hpp"

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/types.hpp"

namespace jointsim::experiments {
namespace {

std::vector<ExperimentType>& table() {
  // One row per built-in type; a new type is a source file in src/experiments/types/ and a row here.
  static std::vector<ExperimentType> types{
      passiveRobotExperimentType(),  //
      jointRigExperimentType(),      //
      trackingExperimentType(),      //
      driveChainExperimentType(),    //
      robotR3AxisExperimentType(),   //
      robotR3FullExperimentType(),   //
      clampingExperimentType(),      //
  };
  return types;
}

}  // namespace

const std::vector<ExperimentType>& experimentTypes() { return table(); }

const ExperimentType* findExperimentType(const std::string& name) {
  for (const auto& t : table())
    if (t.name == name) return &t;
  return nullptr;
}

void registerExperimentType(ExperimentType type) {
  if (type.name.empty() || !type.load) throw InputError("experiment type: a name and a loader are required");
  if (findExperimentType(type.name)) throw InputError("experiment type '" + type.name + "' is already registered");
  table().push_back(std::move(type));
}

std::string experimentTypeNames(bool with_faults_only) {
  std::vector<std::string> names;
  for (const auto& t : table())
    if (!with_faults_only || t.accepts_faults) names.push_back(t.name);
  return join(names, ", ");
}

}  // namespace jointsim::experiments
