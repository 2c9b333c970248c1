#pragma once
/// \file
/// Comparison of two CSV logs (`jointsim compare`, golden regression tests; docs/regression.md).
///
/// The logs are aligned on time: the time column is the column named `time` (any unit, e.g. `time[s]`) or,
/// when there is none, the first column. Every row of A whose time lies in the time range of B is compared
/// with B at that time: with B's own row when B has a sample at the same time (|Δt| ≤ 1e-9 × the time
/// span; no interpolation, so logs on the same grid are compared sample by sample, also across steps at
/// events), else with B interpolated linearly between its neighbouring samples.
///
/// Tolerance, per column: with S = the peak magnitude max |x| of the column over the compared rows of A and B's
/// rows in the same interval (finite values only), every compared sample must satisfy
///     |a(t) − b(t)| ≤ atol + rtol · S.
/// Scaling by the peak rather than by the pointwise magnitude means that a large signal crossing zero is
/// not held to an absolute tolerance near the crossing, and a column's verdict depends on one number that
/// the report prints. Discrete columns (friction modes, start flags) are compared in the same way: their
/// peak is 1 or 2, so any change of state at a compared sample fails.
///
/// With a time tolerance δ > 0 (default 0), a sample of A passes when it lies within the tolerance of the
/// band [min b, max b] of B over [t − δ, t + δ] (B interpolated at both ends plus its samples in between):
/// a "tube" that accepts events shifted by up to δ.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointsim/io/csv_reader.hpp"

namespace jointsim::report {

using io::CsvTable;

/// Options of compareTables().
struct CompareOptions {
  double rtol = 1e-6;           ///< relative tolerance, times the column's peak magnitude
  double atol = 1e-12;          ///< absolute tolerance, in the column's unit
  double time_tolerance = 0.0;  ///< δ [s] of the tube (0: compare at the same time only)
  /// Columns to compare, by name with or without `[unit]`; empty: every column of A except time. A named
  /// column must exist in both files.
  std::vector<std::string> columns;
  /// The first and last times of A and B may differ by at most this [s]; negative (default): one mean
  /// sample interval of the coarser log. Larger differences make the files incompatible (InputError).
  double time_range_tolerance = -1.0;
};

/// Verdict on one column.
struct ColumnComparison {
  std::string name;            ///< header of the column in A
  int column_a = -1;           ///< column index in A
  int column_b = -1;           ///< column index in B
  double peak = 0.0;           ///< S: peak magnitude of the column over the compared samples
  double tolerance = 0.0;      ///< atol + rtol · S
  double max_deviation = 0.0;  ///< largest |a − b| (distance to B's band with a time tolerance); +inf on NaN mismatch
  double time = 0.0;           ///< time of A's sample where it occurs [s]
  double value_a = 0.0;        ///< A's value there
  double value_b = 0.0;        ///< B's value there (exact, interpolated, or the nearest band edge)
  int line_a = 0;              ///< 1-based line of that sample in A's file
  bool pass = true;            ///< max_deviation ≤ tolerance
};

/// Result of a comparison.
struct CompareResult {
  std::string path_a, path_b;
  std::string time_column;             ///< header of A's time column
  Eigen::Index rows_compared = 0;      ///< rows of A inside B's time range
  Eigen::Index rows_interpolated = 0;  ///< of which B had no sample at the same time
  double t_begin = 0.0, t_end = 0.0;   ///< time range of the compared rows [s]
  std::vector<ColumnComparison> columns;
  std::vector<std::string> only_in_b;  ///< columns of B that were not compared (not in A)
  CompareOptions options;              ///< the options used (time_range_tolerance resolved)

  /// Number of columns out of tolerance.
  int failed() const;
  bool pass() const { return failed() == 0; }
};

/// Compares the columns of `b` with those of `a` (see the file comment). Throws InputError when the files
/// are incompatible: no data rows, time not non-decreasing, time ranges that differ by more than the time
/// range tolerance or do not overlap, a requested column (or, by default, a column of A) missing in either
/// file, the same column with different units, or invalid tolerances.
CompareResult compareTables(const CsvTable& a, const CsvTable& b, const CompareOptions& options = {});

/// Reads both files (readCsv, non-finite values allowed) and compares them. Throws InputError on an
/// unreadable file or incompatible files.
CompareResult compareCsvFiles(const std::string& path_a, const std::string& path_b, const CompareOptions& options = {});

/// Human-readable report: header lines (files, rows, tolerances), one line per column (name, max |a − b|,
/// tolerance, their ratio, time, a, b there, ok/FAIL; only the failing columns when `failures_only`), and a
/// final verdict line ("all M columns within tolerance" or "N of M columns differ beyond tolerance: ...").
std::string formatComparison(const CompareResult& result, bool failures_only = false);

}  // namespace jointsim::report
