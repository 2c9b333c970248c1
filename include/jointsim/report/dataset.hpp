#pragma once
/// \file
/// A sweep's results as one HDF5 data set for machine learning (`jointsim batch SWEEP.yaml --dataset FILE.h5`,
/// docs/batch.md "Data sets"). Layout (format "jointsim-dataset", version 1):
///
///     /                      attributes: format, format_version, sweep, sweep_file, experiment, jointsim_version,
///                                        created_utc, runs
///     /labels                one row per run, in sweep order (compound data set, a table):
///                              run, status, fault_type, fault_joint (fixed-length UTF-8 strings; several faults of one
///                              run joined by ';'), fault_severity (float64, the first fault's value in its unit; NaN
///                              for a nominal run), fault_onset_s (float64 [s], NaN for a nominal run), fault_count
///                              (int32), design (string), seed (int64, −1 when not sampled)
///     /runs/<run>/           one group per run; attributes: status, settings (experiment, overrides and faults as
///                              the batch stamps them), overrides, faults, inputs ("path=xxh3:…;…" of every file the
///                              run read), jointsim_version, git_commit, started_utc, sim_time_s, wall_time_s,
///                              summary_json (the run's summary.json), columns (the signal names in log order) and
///                              the label fields
///     /runs/<run>/<signal>   every column of the run's log as a 1-D float64 data set (time included, as `time`),
///                              its unit as the attribute `unit` (SI, e.g. "rad", "N·m"); gzip-compressed chunks
///
/// A run that did not finish (status other than ok) has its group and label row but no signal data sets unless its
/// log exists. The file is written under a temporary name beside the target and renamed into place when complete,
/// so an interrupted write never leaves a partial file under the target name.
///
/// HDF5 (the C library of Debian's libhdf5-dev) is used here, in the report layer, so that the layers the FMU
/// binary carries do not depend on it.

#include <string>

#include "jointsim/experiments/batch.hpp"

namespace jointsim::report {

struct DatasetSummary {
  std::string path;
  int runs = 0;            ///< label rows (every run of the sweep)
  int runs_with_data = 0;  ///< runs whose log was stored
  long samples = 0;        ///< rows of all stored logs together
};

/// Writes the results of `sweep` found in `output_dir` (empty: the batch's default, out/<sweep name>/) to `path`.
/// Throws InputError when checkDatasetPath refuses `path` (before anything is written), Error when the file cannot be
/// written (with the system's reason, e.g. "No space left on device"; nothing is left behind); a run's unreadable log
/// is an InputError naming the file and line; sim::Interrupted on a stop request (jointsim::requestStop). The HDF5
/// library runs in a child process (fork): a failure inside it cannot affect the calling process.
DatasetSummary writeDataset(const experiments::Sweep& sweep, const std::string& output_dir, const std::string& path);

/// Checks, before a batch runs, that `path` can be created: its folder exists and is a directory (InputError
/// "data set PATH: folder 'F' does not exist" otherwise), a file can be created in it (the reason otherwise, e.g.
/// "Read-only file system"), its name leaves room for the temporary name beside it, and an existing file there is an
/// HDF5 file (anything else is never replaced).
void checkDatasetPath(const std::string& path);
/// As above, and `path` is not inside the folder of one of the sweep's runs under `output_dir`.
void checkDatasetPath(const experiments::Sweep& sweep, const std::string& output_dir, const std::string& path);

}  // namespace jointsim::report
