// `jointsim run`: placeholder until the experiment runner lands (see below).
#include "cli_common.hpp"

namespace jointsim::cli {
void addRunCommand(CLI::App&) {}
}  // namespace jointsim::cli
