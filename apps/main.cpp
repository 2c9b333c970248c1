// jointsim command-line interface: parses arguments and dispatches to library calls.
// Exit status: 0 success, 1 simulation/solver failure, 2 bad input (files, keys, values, options),
// 3 data that cannot identify a requested parameter (jointsim identify), 128 + N when stopped by signal N
// (130 for SIGINT, 143 for SIGTERM: the run stops at its next step and leaves an "interrupted" summary).
#include <csignal>
#include <exception>
#include <filesystem>
#include <iostream>
#include <new>
#include <string>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/common/version.hpp"
#include "jointsim/sim/simulate.hpp"

namespace {
// One line per message, control bytes escaped, at most this many bytes of the message (a 10 MB bad CSV line is
// not echoed whole).
constexpr size_t kMaxMessage = 2000;

}  // namespace

namespace jointsim::cli {
std::string& programName() {
  static std::string name = "jointsim";
  return name;
}
}  // namespace jointsim::cli

int main(int argc, char** argv) {
  if (argc > 0 && argv[0] && *argv[0]) jointsim::cli::programName() = argv[0];
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
  jointsim::cli::addAgreementCommand(app);
  jointsim::cli::addPlotCommand(app);
  jointsim::cli::addViewCommand(app);
  jointsim::cli::addFmuCommand(app);
  jointsim::cli::addValidateCommand(app);
  // SIGINT and SIGTERM ask the running simulation to stop instead of killing the process, so temporary files are
  // removed and the summary says "interrupted"; a blocking wait (jointsim batch) returns and forwards the signal.
  jointsim::installStopSignalHandlers();
  // A file-size limit (ulimit -f) is a full disk for this tool: writes fail with EFBIG and are reported (file and
  // reason, nothing half-written) instead of the process being killed with a temporary file left behind.
  std::signal(SIGXFSZ, SIG_IGN);
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
  } catch (const jointsim::sim::Interrupted& e) {
    std::cerr << "jointsim: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 128 + (e.signal() > 0 ? e.signal() : SIGINT);
  } catch (const jointsim::InputError& e) {
    std::cerr << "jointsim: error: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 2;
  } catch (const jointsim::UnidentifiableError& e) {
    std::cerr << "jointsim: cannot identify: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 3;
  } catch (const jointsim::Error& e) {
    std::cerr << "jointsim: failed: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the user gave that the system refuses (too long, a file where a folder is expected, no permission).
    std::cerr << "jointsim: error: " << jointsim::printable(e.path1().string(), kMaxMessage / 2) << ": "
              << e.code().message()
              << (e.path2().empty() ? std::string() : " (" + jointsim::printable(e.path2().string(), 200) + ")")
              << '\n';
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "jointsim: failed: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "jointsim: internal error: " << jointsim::printable(e.what(), kMaxMessage) << '\n';
    return 1;
  }
  return 0;
}
