#pragma once
// Shared pieces of the jointsim command-line front end (a thin layer over the library).
#include <string>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

namespace jointsim::cli {

/// Parses "v1,v2,...,vn" into a vector; throws InputError naming `option` on a bad number.
Eigen::VectorXd parseList(const std::string& text, const std::string& option);
/// As parseList, and checks the count (`what` names the expected entries, e.g. "one per joint").
Eigen::VectorXd parseList(const std::string& text, const std::string& option, Eigen::Index expected,
                          const std::string& what);

/// The command as the user typed it (argv[0], e.g. "./build/jointsim"), for "what next" hints; "jointsim" if unset.
std::string& programName();

void addDynamicsCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addIdentifyCommand(CLI::App& app);
void addBatchCommand(CLI::App& app);
void addCompareCommand(CLI::App& app);
void addAgreementCommand(CLI::App& app);
void addPlotCommand(CLI::App& app);
void addViewCommand(CLI::App& app);
void addFmuCommand(CLI::App& app);
void addValidateCommand(CLI::App& app);
/// `jointsim identify clamping` and `jointsim identify friction` (added to the `identify` subcommand).
void addIdentifyClampingCommand(CLI::App& identify);
void addIdentifyFrictionCommand(CLI::App& identify);
void addIdentifyCurrentsCommand(CLI::App& identify);

}  // namespace jointsim::cli
