// Placeholder, replaced by the implementation of `jointsim identify friction`.
#include "cli_common.hpp"

namespace jointsim::cli {
void addIdentifyFrictionCommand(CLI::App& identify) { identify.add_subcommand("friction", "(not implemented yet)"); }
}  // namespace jointsim::cli
