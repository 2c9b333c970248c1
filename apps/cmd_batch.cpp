// `jointsim batch SWEEP.yaml [-j N] [--shard I/N] [-o DIR] [--collect] [--dataset FILE.h5]`: parallel runs of a
// sweep, and the results as one HDF5 data set.
#include <cstdio>
#include <memory>

#include <unistd.h>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/report/dataset.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::cli {

void addBatchCommand(CLI::App& app) {
  struct Options {
    std::string sweep, output_dir, shard = "0/1", dataset;
    int jobs = 1;
    bool collect = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "Run a sweep (grid, explicit runs, fault scenarios) in parallel; writes DIR/<run>/ and DIR/manifest.csv");
  cmd->add_option("sweep", opt->sweep, "Sweep description (.yaml), see docs/batch.md")->required();
  cmd->add_option("-j,--jobs", opt->jobs, "Runs executed at the same time (default 1)");
  cmd->add_option("--shard", opt->shard, "Run only every N-th run starting at I (I/N, 0 <= I < N), for job arrays");
  cmd->add_option("-o,--output-dir", opt->output_dir, "Output directory (default: out/<sweep name>/)");
  cmd->add_flag("--collect", opt->collect, "Run nothing; rebuild DIR/manifest.csv over all runs from their folders");
  cmd->add_option("--dataset", opt->dataset,
                  "Also write every run's log and the labels to one HDF5 file (FILE.h5, docs/batch.md); the whole "
                  "sweep: without --shard, or with --collect after the shards");
  cmd->callback([opt] {
    experiments::BatchOptions o;
    o.output_dir = opt->output_dir;
    o.jobs = opt->jobs;
    const size_t slash = opt->shard.find('/');
    try {
      if (slash == std::string::npos) throw std::invalid_argument("no slash");
      size_t used = 0;
      o.shard_index = std::stoi(opt->shard.substr(0, slash), &used);
      if (used != slash) throw std::invalid_argument("trailing");
      const std::string n = opt->shard.substr(slash + 1);
      o.shard_count = std::stoi(n, &used);
      if (used != n.size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw InputError("--shard: expected I/N (e.g. 0/4), got '" + opt->shard + "'");
    }
    o.progress = ::isatty(2) != 0;
    const experiments::Sweep sweep = experiments::loadSweep(opt->sweep);
    if (!opt->dataset.empty()) {
      report::checkDatasetPath(sweep, o.output_dir, opt->dataset);  // fails before any run
      if (o.shard_count > 1 && !opt->collect)
        throw InputError(
            "--dataset needs the whole sweep: use it with --collect once the shards are done, not with --shard " +
            opt->shard);
    }
    const experiments::BatchResult r =
        opt->collect ? experiments::collectBatch(sweep, o) : experiments::runBatch(sweep, o);
    std::printf("%s: %zu runs%s: %d ok, %d failed or in error, %d skipped (already ok)%s\n  manifest: %s\n",
                sweep.name.c_str(), r.records.size(),
                o.shard_count > 1 ? (" (shard " + opt->shard + " of " + std::to_string(sweep.runs.size()) + ")").c_str()
                                  : "",
                r.ok - r.skipped, r.failed, r.skipped, opt->collect ? " (collected)" : "", r.manifest_path.c_str());
    if (!opt->collect) std::printf("  wall time %.3g s with %d job(s)\n", r.wall_time_s, o.jobs);
    if (!opt->dataset.empty() && !r.interrupted) {
      const report::DatasetSummary d = report::writeDataset(sweep, o.output_dir, opt->dataset);
      std::printf("  dataset: %s (%d runs, %d with logs, %ld samples)\n", d.path.c_str(), d.runs, d.runs_with_data,
                  d.samples);
    }
    if (r.interrupted)
      throw sim::Interrupted(SolverError("batch interrupted (signal " + std::to_string(r.interrupted) +
                                             "); the interrupted runs run again when the batch is resumed",
                                         0.0, "INTERRUPTED"),
                             sim::SimulationResult{}, r.interrupted);
    if (r.failed > 0) throw Error(std::to_string(r.failed) + " run(s) failed; see the manifest and <run>/run.log");
  });
}

}  // namespace jointsim::cli
