// `jointsim fmu FILE.yaml -o NAME.fmu [--inputs PORT,...] [--outputs SIGNAL,...] [--set key=value]`: exports an
// experiment (every type) as an FMI 2.0 Co-Simulation FMU (include/jointsim/fmi/fmu.hpp,
// docs/fmu.md). Exit status 2 for bad input (nothing written), 1 for other errors.
#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/fmi/fmu.hpp"

namespace jointsim::cli {

void addFmuCommand(CLI::App& app) {
  struct Options {
    std::string config, output;
    fmi::ExportOptions fmu;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("fmu", "Export an experiment (any type) as an FMI 2.0 Co-Simulation FMU");
  cmd->add_option("experiment", opt->config, "Experiment description (.yaml)")->required();
  cmd->add_option("-o,--output", opt->output, "The FMU file NAME.fmu (NAME, a C identifier, is its model identifier)")
      ->required();
  cmd->add_option("--inputs", opt->fmu.inputs,
                  "Command ports as inputs, comma-separated: PORT (every joint) or JOINT:PORT, PORT one of voltage, "
                  "current, motor_torque, motor_velocity, setpoint (tracking); command (joint_rig). Default: none")
      ->delimiter(',');
  cmd->add_option("--outputs", opt->fmu.outputs, "Signals as outputs, comma-separated (default: all)")->delimiter(',');
  cmd->add_option(
      "--set", opt->fmu.overrides,
      "Override a scalar of the experiment file: key.path=value, or +key.path=value to add a key (repeatable)");
  cmd->add_option("--step-size", opt->fmu.step_size, "Suggested communication step [s] (default 1e-3)");
  cmd->callback([opt] {
    const fmi::FmuDescription d = fmi::exportFmu(opt->config, opt->output, opt->fmu);
    int inputs = 0, outputs = 0, parameters = 0;
    for (const auto& v : d.variables) {
      inputs += v.causality == fmi::Causality::Input;
      outputs += v.causality == fmi::Causality::Output;
      parameters += v.causality == fmi::Causality::Parameter;
    }
    std::printf("%s: FMI 2.0 Co-Simulation FMU '%s' with %d inputs, %d outputs, %d parameters\n", opt->output.c_str(),
                d.model_identifier.c_str(), inputs, outputs, parameters);
    if (!d.unoffered.empty()) {
      std::string keys;
      for (const auto& k : d.unoffered) keys += (keys.empty() ? "" : ", ") + k;
      std::printf("  not offered as parameters (no known unit; they keep the file's values): %s\n", keys.c_str());
    }
  });
}

}  // namespace jointsim::cli
