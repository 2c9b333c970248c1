#pragma once
/// \file
/// The one CSV reader: every CSV input of jointsim (logs, measured data, input profiles, trajectories, batch
/// manifests) is read here. A header line of column names (conventionally `name[unit]`), then rows; blank lines
/// are skipped and '#' starts a comment line; cells may be quoted (RFC 4180: "a ""b""" is a "b"). Errors name
/// the file, the line and the column: "data.csv:59:3: column 'motor_angle[rad]': expected a finite number, got 'nan'".

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim::io {

/// Rows of text cells.
struct CsvText {
  std::string path;                            ///< file it was read from (for messages)
  std::vector<std::string> header;             ///< column names as written (trimmed)
  std::vector<std::vector<std::string>> rows;  ///< cells of each data row (as many as the header)
  std::vector<int> lines;                      ///< 1-based file line of each data row
};

/// A numeric table.
struct CsvTable {
  std::string path;                 ///< file it was read from (for messages)
  std::vector<std::string> header;  ///< column names as written (trimmed)
  Eigen::MatrixXd data;             ///< rows × columns
  std::vector<int> lines;           ///< 1-based file line of each data row

  /// Index of the column called `name`: an exact header match, or a header `name[unit]` (any unit).
  /// -1 when absent.
  int find(const std::string& name) const;
  /// As find(); throws InputError "PATH:1: missing column 'NAME' (expected WHAT; columns are: ...)".
  int require(const std::string& name, const std::string& what) const;
  Eigen::Index rows() const { return data.rows(); }
  /// "PATH:LINE:COLUMN" of data row r, column c (1-based line and column), for messages.
  std::string where(Eigen::Index r, int c) const;
};

/// Reads a CSV file of text cells (read through io::readInputFile). Throws InputError on an unreadable or
/// empty file, an empty column name or a row with the wrong number of cells.
CsvText readCsvText(const std::string& path);

/// The times of column `col` of `table`, checked: at least 2 rows, strictly increasing, and (gap_factor > 0) no step
/// larger than gap_factor × the median step (a gap). InputError at `where(r)`, the location of data row r (default:
/// "PATH:LINE:COLUMN: column 'NAME'"): "...: time 0.004 s is not after the previous row's 0.008 s (time must
/// increase strictly)", "...: time step 0.05 s is more than 3x the median 0.008 s (a gap)".
std::vector<double> checkedTimes(const CsvTable& table, int col, double gap_factor = 0.0,
                                 const std::function<std::string(Eigen::Index)>& where = {});

/// Reads a numeric CSV file. As readCsvText, and throws InputError on a cell that is not a number or (when
/// `require_finite`) a NaN or infinite value — naming the file, line and column.
CsvTable readCsv(const std::string& path, bool require_finite = true);

}  // namespace jointsim::io
