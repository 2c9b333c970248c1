// `jointsim agreement PREDICTED MEASURED --pair P=M ...`: how well a run reproduces a measured log, pair by pair
// (report/agreement.hpp; docs/replay.md): RMS error in % of the measured range, bias, correlation, best-fit lag;
// optionally a JSON file and one figure per pair. Exit status 0, or 2 for unreadable files, missing columns or
// bad options (InputError).
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/report/agreement.hpp"

namespace jointsim::cli {

namespace {
/// A run folder (summary.json of `jointsim run`) stands for its CSV log.
std::string runCsv(const std::string& path) {
  if (!io::isDirectory(path)) return path;
  const std::string summary = path + "/summary.json";
  if (!io::isRegularFile(summary))
    throw InputError(path + ": a folder without summary.json: give the run's CSV log or a `jointsim run` folder");
  const auto j = io::parseJson(io::readBoundedFile(summary), summary);
  if (!j.contains("csv") || !j["csv"].is_string()) throw InputError(summary + ": no CSV log recorded (a failed run?)");
  std::string csv = j["csv"].get<std::string>();
  if (!csv.empty() && csv[0] != '/' && !io::isRegularFile(csv)) {  // relative to the folder when not to the cwd
    const std::string name = csv.substr(csv.find_last_of('/') + 1);
    csv = path + "/" + name;
  }
  return csv;
}
}  // namespace

void addAgreementCommand(CLI::App& app) {
  struct Options {
    std::string predicted, measured, json, fig_dir, gnuplot;
    std::vector<std::string> pairs, joints;
    report::AgreementOptions agreement;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "agreement", "How well a run reproduces a measured log: RMS error in % of the measured range, correlation and "
                   "best-fit lag per signal pair (docs/replay.md)");
  cmd->add_option("predicted", opt->predicted, "The run: its CSV log or its `jointsim run` folder")->required();
  cmd->add_option("measured", opt->measured, "The measured log (CSV; time = column time or t_s, else the first)")
      ->required();
  cmd->add_option("--pair", opt->pairs,
                  "PREDICTED=MEASURED column names (repeat, or use {joint}, {j}, {i} with --joint-names), e.g. "
                  "'current_{joint}=i_actual_{j}'")
      ->required()
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--joint-names", opt->joints, "Joint names for {joint} (comma-separated or repeated), in order")
      ->delimiter(',');
  cmd->add_option("--time-offset", opt->agreement.time_offset,
                  "Log time of the run's t = 0 [s] (the replay's start_time; default 0)");
  cmd->add_option("--max-lag", opt->agreement.max_lag, "Lags searched, +- [s] (default 0.05; 0: none)");
  cmd->add_option("--from", opt->agreement.t_begin, "Compare measured samples from this log time [s]");
  cmd->add_option("--to", opt->agreement.t_end, "... up to this log time [s]");
  cmd->add_option("--json", opt->json, "Also write the figures as JSON to this file");
  cmd->add_option("--figures", opt->fig_dir, "Write one figure per pair into this folder (gnuplot)");
  cmd->add_option("--gnuplot", opt->gnuplot, "gnuplot executable (default: gnuplot on PATH)");
  cmd->callback([opt] {
    std::vector<report::SignalPair> pairs;
    for (const std::string& p : opt->pairs)
      for (auto& e : report::SignalPair::expand(p, opt->joints, "--pair")) pairs.push_back(std::move(e));
    const io::CsvTable pred = io::readCsv(runCsv(opt->predicted)), meas = io::readCsv(opt->measured);
    const report::AgreementResult r = report::agreement(pred, meas, pairs, opt->agreement);
    std::fputs(report::formatAgreement(r).c_str(), stdout);
    if (!opt->json.empty()) io::writeFileAtomically(opt->json, report::agreementJson(r));
    if (!opt->fig_dir.empty()) {
      const auto figs = report::plotAgreement(pred, meas, r, opt->agreement, opt->fig_dir, opt->gnuplot);
      std::printf("%zu figure%s written to %s\n", figs.size(), figs.size() == 1 ? "" : "s", opt->fig_dir.c_str());
    }
    std::fflush(stdout);
  });
}

}  // namespace jointsim::cli
