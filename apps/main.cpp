// jointsim command-line interface: parses arguments and dispatches to library calls.
// Exit status: 0 success, 1 simulation/solver failure, 2 bad input (files, keys, values, options),
// 3 data that cannot identify a requested parameter (jointsim identify).
#include <exception>
#include <iostream>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/common/version.hpp"

namespace {
// One line per message, control bytes escaped, at most this many bytes of the message (a 10 MB bad CSV line is
// not echoed whole).
constexpr size_t kMaxMessage = 2000;
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"jointsim — high-fidelity robot joint and multibody simulator"};
  app.require_subcommand(1);
  app.set_version_flag("--version",
                       std::string("jointsim ") + jointsim::version() +
                           (*jointsim::gitCommit() ? std::string(" (") + jointsim::gitCommit() + ")" : std::string()));
  jointsim::cli::addDynamicsCommand(app);
  jointsim::cli::addRunCommand(app);
  jointsim::cli::addIdentifyCommand(app);
  jointsim::cli::addBatchCommand(app);
  jointsim::cli::addCompareCommand(app);
  jointsim::cli::addPlotCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "jointsim: " << jointsim::printable(e.what(), kMaxMessage) << " (see jointsim --help)\n";
    return 2;
  } catch (const jointsim::InputError& e) {
    std::cerr << "jointsim: error: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 2;
  } catch (const jointsim::UnidentifiableError& e) {
    std::cerr << "jointsim: cannot identify: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 3;
  } catch (const jointsim::Error& e) {
    std::cerr << "jointsim: failed: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "jointsim: internal error: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 1;
  }
  return 0;
}
