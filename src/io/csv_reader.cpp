#include "jointsim/io/csv_reader.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "jointsim/common/error.hpp"

namespace jointsim::io {
namespace {
std::string trim(std::string s) {
  s.erase(0, s.find_first_not_of(" \t\r"));
  const size_t last = s.find_last_not_of(" \t\r");
  s.erase(last == std::string::npos ? 0 : last + 1);
  return s;
}
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}
}  // namespace

std::string columnBaseName(const std::string& header) {
  const size_t br = header.find('[');
  return trim(br == std::string::npos ? header : header.substr(0, br));
}

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
  std::string cols;
  for (const auto& h : header) cols += (cols.empty() ? "" : ", ") + h;
  throw InputError(path + ":1: missing column '" + name + "' (expected " + what + "; the columns are: " + cols + ")");
}

CsvTable readCsv(const std::string& path, bool require_finite) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open CSV file for reading");
  CsvTable t;
  t.path = path;
  std::string line;
  int line_no = 0;
  std::vector<double> values;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    if (t.header.empty()) {
      t.header = split(s);
      for (size_t i = 0; i < t.header.size(); ++i)
        if (t.header[i].empty())
          throw InputError(path + ":" + std::to_string(line_no) + ": empty column name in the header (column " +
                           std::to_string(i + 1) + ")");
      continue;
    }
    const auto cells = split(s);
    if (cells.size() != t.header.size())
      throw InputError(path + ":" + std::to_string(line_no) + ": expected " + std::to_string(t.header.size()) +
                       " cells as in the header, got " + std::to_string(cells.size()));
    for (size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      const double x = std::strtod(cells[c].c_str(), &end);
      if (cells[c].empty() || end == cells[c].c_str() || *end != '\0')
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" + t.header[c] +
                         "': expected a number, got '" + cells[c] + "'");
      if (require_finite && !std::isfinite(x))
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" + t.header[c] +
                         "': expected a finite number, got '" + cells[c] + "'");
      values.push_back(x);
    }
    t.lines.push_back(line_no);
  }
  if (t.header.empty()) throw InputError(path + ": empty CSV file, expected a header line of column names");
  const Eigen::Index cols = static_cast<Eigen::Index>(t.header.size());
  const Eigen::Index rows = static_cast<Eigen::Index>(t.lines.size());
  t.data = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(values.data(), rows,
                                                                                                     cols);
  return t;
}

}  // namespace jointsim::io
