#pragma once
/// \file
/// Batch runs and fault-injection sweeps (the library side of `jointsim batch`). A sweep file names a base
/// experiment and a set of runs: an explicit list, a grid of `--set`-style overrides, and fault scenarios
/// (systems/faults.hpp) applied to chosen joints. Each run executes in its own child process (a crash or a
/// solver failure only fails that run) and writes into `<output_dir>/<run name>/`; `manifest.csv` lists
/// every run with its overrides, status, wall time and output folder (RFC 4180 CSV), and is rewritten atomically
/// as runs finish (at the start, at the end, and in between as often as costs at most ~10 % of the batch's time), so
/// an interrupted batch leaves a consistent manifest. Re-running skips runs whose folder already holds a
/// summary.json with status "ok", the same settings (experiment, overrides, faults), input files whose content
/// hashes still match the summary's and its output files as written (resume). A batch holds a lock on its output
/// folder (a shard: on its own manifest): a second batch into the same folder is refused (InputError). `shard_index/shard_count` selects every
/// shard_count-th run starting at shard_index, so a scheduler's job array can spread one sweep over many
/// machines sharing a file system; each shard writes `manifest.shard-I-of-N.csv`, and `collect` rebuilds
/// the full `manifest.csv` from the run folders. Format: docs/batch.md.

#include <string>
#include <vector>

#include "jointsim/io/yaml.hpp"
#include "jointsim/systems/faults.hpp"

namespace jointsim::experiments {

/// The most runs one sweep file may define (explicit, grid, sampled and fault runs together).
constexpr size_t kMaxSweepRuns = 100000;
/// The most override strings a sweep may hold in all (each run's, the common `set` counted once per run).
constexpr size_t kMaxSweepOverrides = 2000000;

struct BatchRun {
  std::string name;                    ///< unique; also the run's folder name
  std::vector<std::string> overrides;  ///< "key.path=value", the sweep's common overrides first
  std::vector<systems::Fault> faults;
  std::string design;            ///< sampled runs: "monte_carlo" or "latin_hypercube" (empty otherwise)
  long seed = -1;                ///< sampled runs: the design's seed (-1 otherwise)
  std::string describe() const;  ///< overrides and faults joined by "; "
};

struct Sweep {
  std::string name;
  std::string file;        ///< the sweep file (for messages)
  std::string experiment;  ///< base experiment file (absolute or relative to the working directory)
  std::vector<BatchRun> runs;
};

/// Reads a sweep file. Throws InputError (file:line: key.path: ...) on bad input, duplicate run names,
/// an empty sweep, or more than kMaxSweepRuns runs / kMaxSweepOverrides overrides (counted before any run is made).
Sweep loadSweep(const std::string& path);
/// A sweep from YAML (or JSON) text; `name` stands for its file in messages, and relative paths in it (the base
/// experiment) are relative to name's folder (e.g. "/work/my_sweep (dict)" for a sweep built in memory in /work).
Sweep loadSweepText(const std::string& text, const std::string& name);
/// A sweep from a parsed document read from `path` (for messages and relative paths).
Sweep loadSweepDocument(const io::YamlValue& root, const std::string& path);

struct BatchOptions {
  std::string output_dir;  ///< empty: out/<sweep name>/
  int jobs = 1;            ///< runs executed at the same time (>= 1)
  int shard_index = 0;     ///< this shard, 0 <= index < count
  int shard_count = 1;
  bool progress = false;  ///< "runs done/failed/total" on stderr
};

struct BatchRecord {
  std::string run, status;  ///< status: ok, failed (solver), error (bad input or crash), pending (not run)
  double wall_time_s = 0.0, sim_time_s = 0.0, real_time_factor = 0.0;
  std::string output_dir, overrides;
  std::string jointsim_version, git_commit, started_utc;  ///< from the run's summary.json
  std::string inputs;                                     ///< "path=hash;..." of every input file the run read
  /// Labels for learning from a sweep (manifest columns fault_type, fault_joint, fault_severity, fault_onset_s,
  /// design, seed): the run's faults (several joined by ';'; a constant fault acts from t = 0 s) and, for a
  /// sampled run, its design and seed. Empty for a nominal run.
  std::string fault_type, fault_joint, fault_severity, fault_onset_s, design, seed;
  bool skipped = false;  ///< finished in an earlier invocation
};

struct BatchResult {
  std::string manifest_path;
  std::vector<BatchRecord> records;  ///< the runs of this shard, in sweep order
  int ok = 0, failed = 0, skipped = 0;
  double wall_time_s = 0.0;
  int interrupted = 0;      ///< the signal that stopped the batch (SIGINT/SIGTERM, forwarded to its runs), 0 if none
  int manifest_writes = 0;  ///< times the manifest was written (paced: rewriting costs at most ~10 % of the batch)
};

/// Indices of the runs of shard `index` of `count`: index, index + count, ...
std::vector<size_t> shardRuns(size_t n_runs, int index, int count);

/// Executes the shard's runs (skipping those already ok) with up to `jobs` child processes.
BatchResult runBatch(const Sweep& sweep, const BatchOptions& options);

/// Rebuilds `<output_dir>/manifest.csv` over all runs of the sweep from their folders (status pending for
/// runs not finished yet), e.g. after the shards of a job array have finished.
BatchResult collectBatch(const Sweep& sweep, const BatchOptions& options);

/// The batch's output folder for `output_dir` (empty: out/<sweep name>/).
std::string batchOutputDir(const Sweep& sweep, const std::string& output_dir);
/// The record of every run of the sweep from its folder under `output_dir` (as collectBatch, writing nothing).
std::vector<BatchRecord> batchRecords(const Sweep& sweep, const std::string& output_dir);
/// What a run's results depend on besides its input files (stored in <run>/run.settings; resume compares it):
/// "experiment: \"PATH\"\noverrides: [\"key=value\", ...]\nfaults: [\"description\", ...]\n" (JSON strings: unambiguous).
std::string runSettings(const Sweep& sweep, const BatchRun& run);

/// What `jointsim validate FILE` found: an experiment or sweep file checked completely without running it.
struct ValidationReport {
  std::string kind;                ///< "experiment" or "sweep"
  std::string name;                ///< experiment.name or sweep.name
  std::string type;                ///< the experiment type (of the sweep's base experiment for a sweep)
  int runs = 0;                    ///< runs of a sweep, each loaded with its overrides and faults (1 for an experiment)
  int states = 0, signals = 0;     ///< of the (base) experiment's plant
  double duration = 0.0;           ///< [s], of the (base) experiment
  std::vector<std::string> files;  ///< every file read (absolute paths, each once)
};
/// Checks `path` fully: an experiment file is loaded as `jointsim run` would load it (every key, every referenced
/// file; `overrides` as --set); a sweep file (top-level `sweep:`) is read and every one of its runs is loaded with
/// its overrides (then `overrides`) and faults. Nothing is simulated or written. InputError (naming the run of a
/// sweep, the file, the line and the key path) for the first problem found. A sweep's runs are checked in an order that
/// finds the likely errors first (the smallest and largest value of each override, each value of a grid axis), then
/// all of them. `progress`: "validated N of M runs, about T left" on stderr (for a terminal). A stop request
/// (SIGINT/SIGTERM) ends it with sim::Interrupted.
ValidationReport validateFile(const std::string& path, const std::vector<std::string>& overrides = {},
                              bool progress = false);

}  // namespace jointsim::experiments
