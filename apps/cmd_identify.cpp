// `jointsim identify <clamping|friction> ...`: parameter identification with Ceres (jointsim::identify).
#include "cli_common.hpp"

namespace jointsim::cli {

void addIdentifyCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("identify", "Identify model parameters from measured data (Ceres fits)");
  cmd->require_subcommand(1);
  addIdentifyClampingCommand(*cmd);
  addIdentifyFrictionCommand(*cmd);
  addIdentifyCurrentsCommand(*cmd);
}

}  // namespace jointsim::cli
