// Placeholder, replaced by the implementation of `jointsim identify clamping`.
#include "cli_common.hpp"

namespace jointsim::cli {
void addIdentifyClampingCommand(CLI::App& identify) { identify.add_subcommand("clamping", "(not implemented yet)"); }
}  // namespace jointsim::cli
