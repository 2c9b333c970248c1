// `jointsim run EXPERIMENT.yaml [-o DIR]`: runs an experiment file and reports where its outputs went.
#include <cstdio>
#include <filesystem>
#include <memory>

#include <unistd.h>

#include "cli_common.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/registry.hpp"

namespace jointsim::cli {

void addRunCommand(CLI::App& app) {
  struct Options {
    std::string config, output_dir;
    std::vector<std::string> overrides;
    long max_steps = -1;
    double max_wall_time = -1.0;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("run", "Run an experiment YAML file; writes DIR/<name>.csv and DIR/summary.json");
  std::string types = "Experiment types (experiment.type):";
  for (const auto& t : experiments::experimentTypes()) types += "\n  " + t.name + ": " + t.description;
  cmd->footer(types);
  cmd->add_option("experiment", opt->config, "Experiment description (.yaml)")->required();
  cmd->add_option("-o,--output-dir", opt->output_dir, "Output directory (default: out/<experiment name>/)");
  cmd->add_option("--set", opt->overrides, "Override a scalar of the experiment file: key.path=value (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--max-steps", opt->max_steps,
                  "Budget of solver steps for the run (0: none; default: the file's limits.steps)");
  cmd->add_option("--max-wall-time", opt->max_wall_time,
                  "Budget of wall-clock time for the run [s] (0: none; default: the file's limits.wall_time)");
  cmd->callback([opt] {
    experiments::RunOptions options;
    options.output_dir = opt->output_dir;
    options.overrides = opt->overrides;
    options.progress = ::isatty(2) != 0;  // progress on stderr only when a person is watching
    options.max_steps = opt->max_steps;
    options.max_wall_time = opt->max_wall_time;
    const experiments::RunReport r = experiments::runExperimentFile(opt->config, options);
    std::printf("%s: %s\n  log:     %s\n  summary: %s\n  simulated %.6g s in %.3g s wall time: real-time factor %.4g\n"
                "  solver: %ld steps, %ld RHS evaluations, %ld error-test failures\n",
                r.experiment.c_str(), r.status.c_str(), r.csv_path.c_str(), r.summary_path.c_str(), r.sim_time_s,
                r.wall_time_s, r.real_time_factor, r.stats.steps, r.stats.rhs_evals, r.stats.error_test_failures);
    if (r.period_wall.periods > 0)
      std::printf("  control period wall time: p50 %.3g µs, p99 %.3g µs, max %.3g µs (%ld periods)\n",
                  1e6 * r.period_wall.p50_s, 1e6 * r.period_wall.p99_s, 1e6 * r.period_wall.max_s,
                  r.period_wall.periods);
    if (r.stats.split_steps > 0)
      std::printf("  fixed step: shortened %ld time(s) to follow a growing mode (solver.step too long there)\n",
                  r.stats.split_steps);
    if (r.stats.retaken_steps > 0)
      std::printf("  fixed step: retook %ld step(s) that ran into a growing mode unseen at their start\n",
                  r.stats.retaken_steps);
    if (r.stats.damped_steps > 0)
      std::printf("  fixed step: took %ld step(s) with the oscillations damped (oscillations: resolve: a real mode the "
                  "scaled rows would not follow)\n",
                  r.stats.damped_steps);
    if (!r.csv_path.empty())
      std::printf("  next:    read the log (one column per signal, SI units) or draw it: %s plot %s\n",
                  programName().c_str(), std::filesystem::path(r.csv_path).parent_path().string().c_str());
    for (const auto& w : r.warnings) std::fprintf(stderr, "jointsim: warning: %s\n", printable(w, 2000).c_str());
  });
}

}  // namespace jointsim::cli
