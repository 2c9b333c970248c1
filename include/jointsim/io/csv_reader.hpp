#pragma once
/// \file
/// Reading numeric CSV tables (jointsim's own logs and measured data): a header line of column names
/// (conventionally `name[unit]`), then rows of numbers. Errors name the file and the line.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim::io {

struct CsvTable {
  std::string path;                  ///< file it was read from (for messages)
  std::vector<std::string> header;   ///< column names as written (trimmed)
  Eigen::MatrixXd data;              ///< rows × columns
  std::vector<int> lines;            ///< 1-based file line of each data row

  /// Index of the column called `name`: an exact header match, or a header `name[unit]` (any unit).
  /// -1 when absent.
  int find(const std::string& name) const;
  /// As find(); throws InputError "PATH:1: missing column 'NAME' (expected WHAT; columns are: ...)".
  int require(const std::string& name, const std::string& what) const;
  Eigen::Index rows() const { return data.rows(); }
};

/// Reads a CSV file. Blank lines are skipped; '#' starts a comment line. Throws InputError on an
/// unreadable file, an empty file, a row with the wrong number of cells, a cell that is not a number,
/// or (when `require_finite`) a NaN or infinite value — naming the file, line and column.
CsvTable readCsv(const std::string& path, bool require_finite = true);

/// The column's base name: "motor_angle[rad]" -> "motor_angle".
std::string columnBaseName(const std::string& header);

}  // namespace jointsim::io
