#include "jointsim/report/compare.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/common/interpolate.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::report {

using io::CsvTable;
using io::readCsv;
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// The unit of "name[unit]" ("" when there is none).
std::string unitOf(const std::string& header) { return splitColumn(header).second; }

int timeColumn(const CsvTable& t) {
  for (size_t i = 0; i < t.header.size(); ++i)
    if (lower(columnBaseName(t.header[i])) == "time") return static_cast<int>(i);
  return 0;
}

/// Column of `t` matching `name`: exact header first, then the same base name.
int matchColumn(const CsvTable& t, const std::string& name) { return t.find(name); }

std::string columnList(const CsvTable& t) { return join(t.header, ", "); }

/// Display width of a UTF-8 string (code points; "N·m" is 3 wide).
size_t displayWidth(const std::string& s) {
  return static_cast<size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string padded(const std::string& s, size_t width) {
  const size_t w = displayWidth(s);
  return w >= width ? s : s + std::string(width - w, ' ');
}

std::string compareNum(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

/// Columns are matched by name (exact header, else base name without the unit): two columns of one file with
/// the same base name would make the match ambiguous (a table compared with itself could pair a column with
/// another one; found by fuzz_csv).
void checkDistinctNames(const CsvTable& t) {
  std::map<std::string, size_t> seen;
  for (size_t i = 0; i < t.header.size(); ++i) {
    const auto [it, fresh] = seen.emplace(columnBaseName(t.header[i]), i);
    if (!fresh)
      throw InputError(t.path + ": columns " + std::to_string(it->second + 1) + " and " + std::to_string(i + 1) +
                       " have the same name '" + printable(it->first) +
                       "'; the columns of a log must have distinct names");
  }
}

void checkTime(const CsvTable& t, int col) {
  if (t.rows() == 0) throw InputError(t.path + ": no data rows (only a header)");
  for (Eigen::Index r = 0; r < t.rows(); ++r) {
    const double x = t.data(r, col);
    if (!std::isfinite(x))
      throw InputError(t.path + ":" + std::to_string(t.lines[r]) + ": time column '" + t.header[col] +
                       "' is not finite");
    if (r > 0 && x < t.data(r - 1, col))
      throw InputError(t.path + ":" + std::to_string(t.lines[r]) + ": time column '" + t.header[col] + "' decreases (" +
                       compareNum(t.data(r - 1, col)) + " -> " + compareNum(x) + "); expected non-decreasing times");
  }
}

double meanInterval(const CsvTable& t, int col) {
  const Eigen::Index n = t.rows();
  return n > 1 ? (t.data(n - 1, col) - t.data(0, col)) / static_cast<double>(n - 1) : 0.0;
}

/// B's values around one time of A: the band [lo, hi] that A's value is held against.
struct Band {
  double lo, hi;
  bool finite;
};

class Sampler {
 public:
  Sampler(const CsvTable& b, int time_col, double eps)
      : b_(b), eps_(eps), t_(b.data.col(time_col).begin(), b.data.col(time_col).end()) {}

  bool interpolates(double t) const {
    const auto [first, last] = matchRange(t);
    return first == last;
  }

  /// Band of column `c` of B over [t − delta, t + delta] (delta ≥ 0).
  Band band(int c, double t, double delta) const {
    Band out{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), true};
    auto add = [&out](double x) {
      if (!std::isfinite(x)) {
        out.finite = false;
        return;
      }
      out.lo = std::min(out.lo, x);
      out.hi = std::max(out.hi, x);
    };
    if (delta <= 0.0) {
      const auto [first, last] = matchRange(t);
      if (first != last) {
        for (size_t k = first; k < last; ++k) add(b_.data(static_cast<Eigen::Index>(k), c));
      } else {
        add(interpolate(c, t));
      }
      return out;
    }
    const double t0 = std::max(t - delta, t_.front()), t1 = std::min(t + delta, t_.back());
    add(interpolate(c, t0));
    add(interpolate(c, t1));
    for (size_t k = static_cast<size_t>(std::lower_bound(t_.begin(), t_.end(), t0) - t_.begin());
         k < t_.size() && t_[k] <= t1; ++k)
      add(b_.data(static_cast<Eigen::Index>(k), c));
    return out;
  }

  /// Values of column c at B rows whose time matches t (for NaN/inf bookkeeping), or the interpolated value.
  std::vector<double> raw(int c, double t) const {
    const auto [first, last] = matchRange(t);
    std::vector<double> v;
    for (size_t k = first; k < last; ++k) v.push_back(b_.data(static_cast<Eigen::Index>(k), c));
    if (v.empty()) v.push_back(interpolate(c, t));
    return v;
  }

 private:
  /// Rows [first, last) of B with |t_B − t| ≤ eps.
  std::pair<size_t, size_t> matchRange(double t) const {
    const auto first = std::lower_bound(t_.begin(), t_.end(), t - eps_);
    auto last = first;
    while (last != t_.end() && *last <= t + eps_) ++last;
    return {static_cast<size_t>(first - t_.begin()), static_cast<size_t>(last - t_.begin())};
  }
  /// Linear interpolation of column c at t (held at B's range ends); at a repeated time, the last row.
  double interpolate(int c, double t) const {
    return interpolateLinear(
        t_.size(), [this](size_t i) { return t_[i]; },
        [this, c](size_t i) { return b_.data(static_cast<Eigen::Index>(i), c); }, t, Ends::Hold);
  }

  const CsvTable& b_;
  double eps_;
  std::vector<double> t_;
};

}  // namespace

int CompareResult::failed() const {
  return static_cast<int>(std::count_if(columns.begin(), columns.end(), [](const auto& c) { return !c.pass; }));
}

CompareResult compareTables(const CsvTable& a, const CsvTable& b, const CompareOptions& options) {
  auto bad = [](double x) { return !(x >= 0.0) || !std::isfinite(x); };
  if (bad(options.rtol))
    throw InputError("compare: rtol must be a finite number >= 0, got " + compareNum(options.rtol));
  if (bad(options.atol))
    throw InputError("compare: atol must be a finite number >= 0, got " + compareNum(options.atol));
  if (bad(options.time_tolerance))
    throw InputError("compare: time tolerance must be a finite number >= 0 s, got " +
                     compareNum(options.time_tolerance));
  if (!std::isfinite(options.time_range_tolerance))
    throw InputError("compare: time range tolerance must be finite, got " + compareNum(options.time_range_tolerance));

  CompareResult res;
  res.path_a = a.path;
  res.path_b = b.path;
  res.options = options;
  const int ta = timeColumn(a), tb = timeColumn(b);
  if (a.header.empty() || b.header.empty()) throw InputError("compare: a file without columns");
  res.time_column = a.header[ta];
  {
    const std::string ua = unitOf(a.header[ta]), ub = unitOf(b.header[tb]);
    if (!ua.empty() && !ub.empty() && ua != ub)
      throw InputError("incompatible files: time column '" + a.header[ta] + "' of " + a.path + " vs '" + b.header[tb] +
                       "' of " + b.path + " (different units)");
  }
  checkTime(a, ta);
  checkTime(b, tb);
  checkDistinctNames(a);
  checkDistinctNames(b);

  // Time ranges.
  const double a0 = a.data(0, ta), a1 = a.data(a.rows() - 1, ta);
  const double b0 = b.data(0, tb), b1 = b.data(b.rows() - 1, tb);
  const double span = std::max({a1 - a0, b1 - b0, std::abs(a0), std::abs(a1), 1e-300});
  const double eps = 1e-9 * span;
  double range_tol = options.time_range_tolerance;
  if (range_tol < 0.0) range_tol = std::max(meanInterval(a, ta), meanInterval(b, tb));
  res.options.time_range_tolerance = range_tol;
  const std::string ranges = a.path + " covers [" + compareNum(a0) + ", " + compareNum(a1) + "] s, " + b.path +
                             " covers [" + compareNum(b0) + ", " + compareNum(b1) + "] s";
  if (a1 < b0 - eps || b1 < a0 - eps) throw InputError("incompatible files: the time ranges do not overlap: " + ranges);
  if (std::abs(a0 - b0) > range_tol + eps || std::abs(a1 - b1) > range_tol + eps)
    throw InputError("incompatible files: the time ranges differ by more than " + compareNum(range_tol) +
                     " s: " + ranges);

  // Columns.
  std::vector<int> cols_a;
  if (options.columns.empty()) {
    for (int i = 0; i < static_cast<int>(a.header.size()); ++i)
      if (i != ta) cols_a.push_back(i);
  } else {
    for (const std::string& entry : options.columns) {
      std::stringstream ss(entry);
      for (std::string name; std::getline(ss, name, ',');) {
        name.erase(0, name.find_first_not_of(" \t"));
        name.erase(name.find_last_not_of(" \t") + 1);
        if (name.empty()) continue;
        const int i = matchColumn(a, name);
        if (i < 0)
          throw InputError(a.path + ": no column '" + name + "' to compare (the columns are: " + columnList(a) + ")");
        if (std::find(cols_a.begin(), cols_a.end(), i) == cols_a.end()) cols_a.push_back(i);
      }
    }
    if (cols_a.empty()) throw InputError("compare: --columns names no column");
  }
  std::vector<bool> used_b(b.header.size(), false);
  used_b[tb] = true;
  for (const int ia : cols_a) {
    ColumnComparison cc;
    cc.name = a.header[ia];
    cc.column_a = ia;
    cc.column_b = ia == ta ? tb : matchColumn(b, a.header[ia]);
    if (cc.column_b < 0)
      throw InputError("incompatible files: column '" + a.header[ia] + "' of " + a.path + " is missing in " + b.path +
                       " (its columns are: " + columnList(b) + "); select the columns to compare with --columns");
    const std::string ua = unitOf(a.header[ia]), ub = unitOf(b.header[cc.column_b]);
    if (!ua.empty() && !ub.empty() && ua != ub)
      throw InputError("incompatible files: column '" + a.header[ia] + "' of " + a.path + " is '" +
                       b.header[cc.column_b] + "' in " + b.path + " (different units)");
    used_b[cc.column_b] = true;
    res.columns.push_back(cc);
  }
  if (options.columns.empty())  // with a selection, the other columns are ignored on purpose
    for (size_t j = 0; j < b.header.size(); ++j)
      if (!used_b[j]) res.only_in_b.push_back(b.header[j]);

  // Rows of A inside B's range.
  std::vector<Eigen::Index> rows;
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const double t = a.data(r, ta);
    if (t >= b0 - eps && t <= b1 + eps) rows.push_back(r);
  }
  if (rows.empty()) throw InputError("incompatible files: no time of " + a.path + " lies in the range of " + b.path);
  res.rows_compared = static_cast<Eigen::Index>(rows.size());
  res.t_begin = a.data(rows.front(), ta);
  res.t_end = a.data(rows.back(), ta);

  const Sampler sampler(b, tb, eps);
  for (const Eigen::Index r : rows)
    if (sampler.interpolates(a.data(r, ta))) ++res.rows_interpolated;

  const double delta = options.time_tolerance;
  for (ColumnComparison& cc : res.columns) {
    // Peak magnitude over the compared rows of A and B's rows in the compared interval.
    double peak = 0.0;
    for (const Eigen::Index r : rows) {
      const double x = a.data(r, cc.column_a);
      if (std::isfinite(x)) peak = std::max(peak, std::abs(x));
    }
    for (Eigen::Index r = 0; r < b.rows(); ++r) {
      const double t = b.data(r, tb), x = b.data(r, cc.column_b);
      if (t >= res.t_begin - delta - eps && t <= res.t_end + delta + eps && std::isfinite(x))
        peak = std::max(peak, std::abs(x));
    }
    cc.peak = peak;
    cc.tolerance = options.atol + options.rtol * peak;
    cc.max_deviation = -1.0;
    for (const Eigen::Index r : rows) {
      const double t = a.data(r, ta), x = a.data(r, cc.column_a);
      const Band band = sampler.band(cc.column_b, t, delta);
      double dev = 0.0, y = x;
      if (!std::isfinite(x) || !band.finite) {
        // Non-finite values: equal only when B has the same value (both NaN, or the same infinity).
        const std::vector<double> v = sampler.raw(cc.column_b, t);
        const bool same =
            std::all_of(v.begin(), v.end(), [x](double z) { return (std::isnan(x) && std::isnan(z)) || x == z; });
        dev = same ? 0.0 : std::numeric_limits<double>::infinity();
        y = v.front();
      } else if (x < band.lo) {
        dev = band.lo - x;
        y = band.lo;
      } else if (x > band.hi) {
        dev = x - band.hi;
        y = band.hi;
      } else {
        y = band.lo == band.hi ? band.lo : x;
      }
      if (dev > cc.max_deviation) {
        cc.max_deviation = dev;
        cc.time = t;
        cc.value_a = x;
        cc.value_b = y;
        cc.line_a = a.lines[r];
      }
    }
    cc.pass = cc.max_deviation <= cc.tolerance;
  }
  return res;
}

CompareResult compareCsvFiles(const std::string& path_a, const std::string& path_b, const CompareOptions& options) {
  const CsvTable a = readCsv(path_a, false);
  const CsvTable b = readCsv(path_b, false);
  return compareTables(a, b, options);
}

std::string formatComparison(const CompareResult& r, bool failures_only) {
  std::string out;
  char buf[512];
  std::snprintf(buf, sizeof buf, "A: %s\nB: %s\n", r.path_a.c_str(), r.path_b.c_str());
  out += buf;
  std::snprintf(buf, sizeof buf, "compared %ld rows of A over [%.9g, %.9g] s (%ld with B interpolated)\n",
                static_cast<long>(r.rows_compared), r.t_begin, r.t_end, static_cast<long>(r.rows_interpolated));
  out += buf;
  std::snprintf(buf, sizeof buf, "tolerance per column: |a - b| <= atol + rtol * peak|x|, rtol %.3g, atol %.3g",
                r.options.rtol, r.options.atol);
  out += buf;
  if (r.options.time_tolerance > 0.0) {
    std::snprintf(buf, sizeof buf, ", time tolerance %.3g s", r.options.time_tolerance);
    out += buf;
  }
  out += "\n";
  size_t w = 6;
  for (const auto& c : r.columns) w = std::max(w, displayWidth(c.name));
  std::snprintf(buf, sizeof buf, "  %-11s  %-11s  %-9s  %-16s  %-24s  %-24s  %s\n", "max|a-b|", "tolerance", "dev/tol",
                "at time[s]", "a", "b", "result");
  out += padded("column", w) + buf;
  for (const auto& c : r.columns) {
    if (failures_only && c.pass) continue;
    const double ratio = c.tolerance > 0.0 ? c.max_deviation / c.tolerance
                                           : (c.max_deviation > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
    std::snprintf(buf, sizeof buf, "  %-11.4g  %-11.4g  %-9.3g  %-16.10g  %-24.17g  %-24.17g  %s\n", c.max_deviation,
                  c.tolerance, ratio, c.time, c.value_a, c.value_b, c.pass ? "ok" : "FAIL");
    out += padded(c.name, w) + buf;
  }
  if (!r.only_in_b.empty()) {
    std::string list;
    for (const auto& n : r.only_in_b) list += (list.empty() ? "" : ", ") + n;
    out += "not compared (only in B): " + list + "\n";
  }
  const int failed = r.failed();
  if (failed == 0) {
    std::snprintf(buf, sizeof buf, "all %zu columns within tolerance\n", r.columns.size());
    out += buf;
  } else {
    std::string list;
    for (const auto& c : r.columns)
      if (!c.pass) list += (list.empty() ? "" : ", ") + c.name;
    std::snprintf(buf, sizeof buf, "%d of %zu columns differ beyond tolerance: ", failed, r.columns.size());
    out += buf + list + "\n";
  }
  return out;
}

}  // namespace jointsim::report
