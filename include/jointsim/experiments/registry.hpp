#pragma once
/// \file
/// The registry of experiment types: one table of rows (name, one-line description, YAML loader, figures)
/// that `jointsim run`, `jointsim plot`, the CLI help and the unknown-type error all read. A new type is one
/// source file (its loader, its Experiment, its figures) and one row; a program can also register its own
/// types at run time (tests/experiments/test_registry.cpp registers a mass–spring–damper).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/figures.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::experiments {

/// What a loader gets besides the document.
struct LoadContext {
  std::string name;                    ///< experiment.name (validated: a non-empty name without path separators)
  std::string file;                    ///< the experiment file
  std::vector<systems::Fault> faults;  ///< faults to inject (only types with accepts_faults get any)
};

/// Loads the document (with --set overrides applied; `root` is the whole file) into a runnable experiment.
/// Throws InputError naming the file, line and key path.
using ExperimentLoader =
    std::function<std::unique_ptr<Experiment>(const io::YamlValue& root, const LoadContext& context)>;

struct ExperimentType {
  std::string name;         ///< the `experiment.type` value, e.g. "joint_rig"
  std::string description;  ///< one line for the CLI help
  ExperimentLoader load;
  FigureFunction figures;        ///< optional: without it (or when it returns none) every column against time
  KeySignalFunction key_signal;  ///< optional: the signal overlaid across a sweep's runs
  bool accepts_faults = false;   ///< drive faults (systems/faults.hpp) apply to this type
};

/// Every registered type: the built-in ones, then those added by registerExperimentType, in that order.
const std::vector<ExperimentType>& experimentTypes();
/// The type called `name`, or null.
const ExperimentType* findExperimentType(const std::string& name);
/// Adds a type (InputError when the name is taken or the loader missing).
void registerExperimentType(ExperimentType type);
/// "passive_robot, joint_rig, ..." — the registered names.
std::string experimentTypeNames(bool with_faults_only = false);

}  // namespace jointsim::experiments
