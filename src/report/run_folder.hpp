#pragma once
// Reading the folders `jointsim run` and `jointsim batch` write, for the report layer's front ends (`jointsim plot`,
// `jointsim view`): a run folder (summary.json and the CSV log it names) and a sweep folder (manifest.csv).
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "jointsim/experiments/figures.hpp"

namespace jointsim::report {

/// A run folder: summary.json and the CSV log it names, as the figure builders see them.
struct RunFolder {
  experiments::RunData data;
  std::string dir, csv;  ///< absolute paths
};

/// Reads RUN_DIR/summary.json and the CSV log it names (DIR/<experiment>.csv, else the file the summary names).
/// InputError for a missing or malformed summary, a run without a log (a failed run: its reason), an unsafe
/// experiment name or an unreadable CSV.
RunFolder loadRunFolder(const std::string& run_dir);

/// A folder given to `jointsim plot` or `jointsim view`: its absolute path and whether it is a run folder
/// (summary.json) or else a sweep folder (manifest.csv). InputError for a missing folder or one that is neither.
struct OutputFolder {
  std::string path;
  bool is_run = false;
};
OutputFolder outputFolder(const std::string& dir);

/// One row of a sweep's manifest.csv.
struct ManifestRow {
  std::string run, status, output_dir, overrides;
  double wall_time_s = NAN, sim_time_s = NAN, real_time_factor = NAN;
  /// The non-empty cells after the first seven columns (version, commit, inputs, fault_type, design, seed, ...).
  std::vector<std::pair<std::string, std::string>> extra;
};

/// Reads a manifest.csv of `jointsim batch`: InputError for a wrong header, an unsafe run name or no rows.
std::vector<ManifestRow> readManifest(const std::string& path);

/// The run folder of a manifest row: output_dir as written (absolute, or relative to the working directory),
/// else relative to the sweep folder, else SWEEP_DIR/<its last component> or SWEEP_DIR/<run>.
std::optional<std::string> runFolder(const std::string& sweep_dir, const ManifestRow& row);

/// The signal of a run overlaid across a sweep: its type's key signal (registry), else its first column.
std::optional<experiments::KeySignal> keySignal(const experiments::RunData& run);

}  // namespace jointsim::report
