#include "jointsim/io/csv_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/input_files.hpp"

namespace jointsim::io {
namespace {

/// One record with RFC 4180 quoting; unquoted cells are trimmed.
std::vector<std::string> splitRecord(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false, was_quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        cells.back() += '"', ++i;
      else if (c == '"')
        quoted = false;
      else
        cells.back() += c;
    } else if (c == '"' && trim(cells.back()).empty()) {
      quoted = was_quoted = true;
      cells.back().clear();
    } else if (c == ',') {
      if (!was_quoted) cells.back() = trim(cells.back());
      cells.emplace_back();
      was_quoted = false;
    } else if (c != '\r' && !(was_quoted && (c == ' ' || c == '\t'))) {
      cells.back() += c;
    }
  }
  if (!was_quoted) cells.back() = trim(cells.back());
  return cells;
}

std::string location(const std::string& path, int line) { return path + ":" + std::to_string(line); }

}  // namespace

int CsvTable::find(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  const std::string base = columnBaseName(name);
  for (size_t i = 0; i < header.size(); ++i)
    if (columnBaseName(header[i]) == base) return static_cast<int>(i);
  return -1;
}

int CsvTable::require(const std::string& name, const std::string& what) const {
  const int i = find(name);
  if (i >= 0) return i;
  throw InputError(path + ":1: missing column '" + name + "' (expected " + what +
                   "; the columns are: " + join(header, ", ") + ")");
}

std::string CsvTable::where(Eigen::Index r, int c) const {
  return location(path, lines[static_cast<size_t>(r)]) + ":" + std::to_string(c + 1);
}

CsvText readCsvText(const std::string& path) {
  std::istringstream in(readInputFile(path, "CSV file"));
  CsvText t;
  t.path = path;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    std::vector<std::string> cells = splitRecord(s);
    if (t.header.empty()) {
      for (size_t i = 0; i < cells.size(); ++i)
        if (cells[i].empty())
          throw InputError(location(path, line_no) + ": empty column name in the header (column " +
                           std::to_string(i + 1) + ")");
      t.header = std::move(cells);
      continue;
    }
    if (cells.size() != t.header.size())
      throw InputError(location(path, line_no) + ": expected " + std::to_string(t.header.size()) +
                       " cells as in the header, got " + std::to_string(cells.size()));
    t.rows.push_back(std::move(cells));
    t.lines.push_back(line_no);
  }
  if (t.header.empty()) throw InputError(path + ": empty CSV file, expected a header line of column names");
  return t;
}

CsvTable readCsv(const std::string& path, bool require_finite) {
  CsvText text = readCsvText(path);
  CsvTable t;
  t.path = path;
  t.header = std::move(text.header);
  t.lines = std::move(text.lines);
  const auto cols = static_cast<Eigen::Index>(t.header.size());
  t.data.resize(static_cast<Eigen::Index>(text.rows.size()), cols);
  for (size_t r = 0; r < text.rows.size(); ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) {
      const std::string& cell = text.rows[r][static_cast<size_t>(c)];
      char* end = nullptr;
      const double x = std::strtod(cell.c_str(), &end);
      const std::string where = location(path, t.lines[r]) + ":" + std::to_string(c + 1) + ": column '" +
                                t.header[static_cast<size_t>(c)] + "': ";
      if (cell.empty() || end == cell.c_str() || *end != '\0')
        throw InputError(where + "expected a number, got '" + printable(cell, 80) + "'");
      if (require_finite && !std::isfinite(x))
        throw InputError(where + "expected a finite number, got '" + printable(cell, 80) + "'");
      t.data(static_cast<Eigen::Index>(r), c) = x;
    }
  }
  return t;
}

std::vector<double> checkedTimes(const CsvTable& table, int col, double gap_factor,
                                 const std::function<std::string(Eigen::Index)>& where_fn) {
  auto where = [&](Eigen::Index r) {
    return where_fn ? where_fn(r) : table.where(r, col) + ": column '" + table.header[static_cast<size_t>(col)] + "'";
  };
  std::vector<double> times;
  for (Eigen::Index r = 0; r < table.rows(); ++r) {
    const double t = table.data(r, col);
    if (!times.empty() && !(t > times.back()))
      throw InputError(where(r) + ": time " + formatNumber(t, 6) + " s is not after the previous row's " +
                       formatNumber(times.back(), 6) + " s (time must increase strictly)");
    times.push_back(t);
  }
  if (times.size() < 2)
    throw InputError(table.path + ": expected at least 2 data rows, got " + std::to_string(times.size()));
  if (gap_factor > 0.0) {
    std::vector<double> dt(times.size() - 1);
    for (size_t k = 1; k < times.size(); ++k) dt[k - 1] = times[k] - times[k - 1];
    std::vector<double> sorted = dt;
    std::sort(sorted.begin(), sorted.end());
    const size_t m = sorted.size();
    const double median = (m % 2 == 1) ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
    for (size_t k = 0; k < dt.size(); ++k)
      if (dt[k] > gap_factor * median)
        throw InputError(where(static_cast<Eigen::Index>(k + 1)) + ": time step " + formatNumber(dt[k], 6) +
                         " s is more than " + formatNumber(gap_factor, 6) + "x the median " + formatNumber(median, 6) +
                         " s (a gap)");
  }
  return times;
}

}  // namespace jointsim::io
