// Algorithm II preprocessing of clamping curves ([KR300Thesis, §4.3, Table 6.1]). See clamping_curve.hpp.
#include "jointsim/identify/clamping_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/common/interpolate.hpp"
#include "jointsim/io/csv_reader.hpp"

namespace jointsim::identify {

namespace {

std::string curveNum(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

std::string where(const std::string& source) { return source.empty() ? std::string("clamping data") : source; }

/// Least-squares line τ = a + s (x − x̄) through the points; returns {slope, value at `at`}.
struct Line {
  double slope = 0.0, intercept = 0.0, x_mean = 0.0;  // τ = intercept + slope (x − x_mean)
  double operator()(double x) const { return intercept + slope * (x - x_mean); }
};

template <class GetX, class GetY>
Line fitLine(size_t n, GetX gx, GetY gy) {
  Line l;
  if (n == 0) return l;
  double sx = 0, sy = 0;
  for (size_t i = 0; i < n; ++i) {
    sx += gx(i);
    sy += gy(i);
  }
  l.x_mean = sx / static_cast<double>(n);
  const double y_mean = sy / static_cast<double>(n);
  double sxx = 0, sxy = 0;
  for (size_t i = 0; i < n; ++i) {
    const double dx = gx(i) - l.x_mean;
    sxx += dx * dx;
    sxy += dx * (gy(i) - y_mean);
  }
  l.slope = sxx > 0 ? sxy / sxx : 0.0;
  l.intercept = y_mean;
  return l;
}

Line fitLine(const Eigen::VectorXd& x, const Eigen::VectorXd& y, Eigen::Index from = 0, Eigen::Index to = -1) {
  if (to < 0) to = x.size() - 1;
  const size_t n = to >= from ? static_cast<size_t>(to - from + 1) : 0;
  return fitLine(
      n, [&](size_t i) { return x[from + static_cast<Eigen::Index>(i)]; },
      [&](size_t i) { return y[from + static_cast<Eigen::Index>(i)]; });
}

/// Linear interpolation in sorted x (held at the ends).
double interp(const Eigen::VectorXd& x, const Eigen::VectorXd& y, double at) {
  return interpolateLinear(
      static_cast<size_t>(x.size()), [&x](size_t i) { return x[static_cast<Eigen::Index>(i)]; },
      [&y](size_t i) { return y[static_cast<Eigen::Index>(i)]; }, at, Ends::Hold);
}

GridCurve sampleCurve(const GridCurve& c, double lo, double hi, int n) {
  GridCurve out;
  out.x = Eigen::VectorXd::LinSpaced(n, lo, hi);
  out.tau.resize(n);
  for (int i = 0; i < n; ++i) out.tau[i] = c.at(out.x[i]);
  return out;
}

double meanAndStd(const std::vector<double>& v, double& sd) {
  const double n = static_cast<double>(v.size());
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0;
  for (double x : v) ss += (x - mean) * (x - mean);
  sd = v.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0;
  return mean;
}

/// Steps 3/5: rejects half-cycles (of `group`) whose slope or representative torque stands out.
void rejectOutlierHalfCycles(std::vector<HalfCycle>& hcs, const std::vector<int>& group, const ClampingCurveOptions& o,
                             double torque_half_span, const std::string& step) {
  if (group.size() < 3) return;  // two values are always within one standard deviation of their mean
  std::vector<double> slopes, reps;
  for (int i : group) {
    slopes.push_back(hcs[i].slope);
    reps.push_back(hcs[i].rep_torque);
  }
  double sd_s = 0, sd_r = 0;
  const double m_s = meanAndStd(slopes, sd_s), m_r = meanAndStd(reps, sd_r);
  const double tol_s = std::max(o.half_cycle_kappa * sd_s, o.min_slope_deviation * std::abs(m_s));
  const double tol_r = std::max(o.half_cycle_kappa * sd_r, o.min_torque_deviation * torque_half_span);
  for (int i : group) {
    HalfCycle& h = hcs[i];
    if (std::abs(h.slope - m_s) > tol_s) {
      h.rejected = true;
      h.reason = step + ": slope " + curveNum(h.slope) + " N*m/rad differs from the mean " + curveNum(m_s) +
                 " by more than " + curveNum(tol_s);
    } else if (std::abs(h.rep_torque - m_r) > tol_r) {
      h.rejected = true;
      h.reason = step + ": representative torque " + curveNum(h.rep_torque) + " N*m differs from the mean " +
                 curveNum(m_r) + " by more than " + curveNum(tol_r);
    }
  }
}

std::vector<int> active(const std::vector<HalfCycle>& hcs, int upper /* -1 any, 0 lower, 1 upper */) {
  std::vector<int> out;
  for (size_t i = 0; i < hcs.size(); ++i)
    if (!hcs[i].rejected && (upper < 0 || static_cast<int>(hcs[i].upper) == upper)) out.push_back(static_cast<int>(i));
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------- data

void ClampingData::validate(int min_rows) const {
  const std::string src = where(source);
  const Eigen::Index n = time.size();
  if (angle.size() != n || torque.size() != n)
    throw InputError(src + ": time, angle and torque must have the same length (" + std::to_string(n) + ", " +
                     std::to_string(angle.size()) + ", " + std::to_string(torque.size()) + ")");
  auto lineOf = [&](Eigen::Index k) {
    return static_cast<size_t>(k) < lines.size() ? src + ":" + std::to_string(lines[static_cast<size_t>(k)])
                                                 : src + ": sample " + std::to_string(k);
  };
  for (Eigen::Index k = 0; k < n; ++k)
    if (!std::isfinite(time[k]) || !std::isfinite(angle[k]) || !std::isfinite(torque[k]))
      throw InputError(lineOf(k) + ": non-finite time, angle or torque");
  for (Eigen::Index k = 1; k < n; ++k)
    if (!(time[k] > time[k - 1]))
      throw InputError(lineOf(k) + ": time[s] must be strictly increasing, got " + curveNum(time[k]) + " after " +
                       curveNum(time[k - 1]));
  if (n < min_rows)
    throw InputError(src + ": " + std::to_string(n) + " data rows, a clamping curve needs at least " +
                     std::to_string(min_rows));
}

ClampingData readClampingCsv(const std::string& path, double gear_ratio) {
  if (!(gear_ratio > 0.0) || !std::isfinite(gear_ratio))
    throw InputError("gear ratio: expected a finite value > 0, got " + curveNum(gear_ratio));
  const io::CsvTable t = io::readCsv(path);
  const int ti = t.require("time", "the sample time in s");
  const int ai = t.require("motor_angle", "the motor angle in rad");
  const int qi = t.require("motor_torque", "the motor torque in N*m");
  ClampingData d;
  d.source = path;
  d.time = t.data.col(ti);
  d.angle = t.data.col(ai);
  // The KUKA logs of [KR300Thesis] give degrees: honour a [deg] unit.
  const std::string& ah = t.header[static_cast<size_t>(ai)];
  if (ah.find("[deg]") != std::string::npos) d.angle *= 3.14159265358979323846 / 180.0;
  d.torque = t.data.col(qi) / gear_ratio;
  d.lines = t.lines;
  d.validate();
  return d;
}

void ClampingCurveOptions::validate() const {
  auto bad = [](const std::string& field, double v, const std::string& rule) {
    throw InputError("clamping curve options: " + field + ": expected " + rule + ", got " + curveNum(v));
  };
  if (!(step_threshold_factor >= 0)) bad("step_threshold_factor", step_threshold_factor, "a value >= 0");
  if (step_filter_window < 1 || step_filter_window % 2 == 0)
    bad("step_filter_window", step_filter_window, "an odd number >= 1");
  if (min_run_samples < 2) bad("min_run_samples", min_run_samples, "an integer >= 2");
  if (!(extreme_fraction >= 0 && extreme_fraction < 0.5))
    bad("extreme_fraction", extreme_fraction, "a value in [0, 0.5)");
  if (!(end_trim_fraction >= 0 && end_trim_fraction < 0.5))
    bad("end_trim_fraction", end_trim_fraction, "a value in [0, 0.5)");
  if (!(point_kappa > 0)) bad("point_kappa", point_kappa, "a value > 0");
  if (min_points < 3) bad("min_points", min_points, "an integer >= 3");
  if (!(half_cycle_kappa > 0)) bad("half_cycle_kappa", half_cycle_kappa, "a value > 0");
  if (!(min_slope_deviation >= 0)) bad("min_slope_deviation", min_slope_deviation, "a value >= 0");
  if (!(min_torque_deviation >= 0)) bad("min_torque_deviation", min_torque_deviation, "a value >= 0");
  if (!(max_rejected_fraction >= 0 && max_rejected_fraction <= 1))
    bad("max_rejected_fraction", max_rejected_fraction, "a value in [0, 1]");
  if (!(coverage_fraction > 0 && coverage_fraction <= 1))
    bad("coverage_fraction", coverage_fraction, "a value in (0, 1]");
  if (!(min_span_fraction >= 0 && min_span_fraction <= 1))
    bad("min_span_fraction", min_span_fraction, "a value in [0, 1]");
  if (grid_points < 20) bad("grid_points", grid_points, "an integer >= 20");
  if (!(slope_threshold > 0 && slope_threshold < 1)) bad("slope_threshold", slope_threshold, "a value in (0, 1)");
  if (!(slope_window_fraction > 0 && slope_window_fraction < 0.5))
    bad("slope_window_fraction", slope_window_fraction, "a value in (0, 0.5)");
  if (!(zero_margin >= 0 && zero_margin < 1)) bad("zero_margin", zero_margin, "a value in [0, 1)");
  if (!(min_side_fraction >= 0 && min_side_fraction < 0.5))
    bad("min_side_fraction", min_side_fraction, "a value in [0, 0.5)");
  if (min_linear_points < 3) bad("min_linear_points", min_linear_points, "an integer >= 3");
}

double GridCurve::at(double position) const { return interp(x, tau, position); }

// ---------------------------------------------------------------------------------------------------- step 1

std::vector<HalfCycle> segmentHalfCycles(const Eigen::VectorXd& angle, const ClampingCurveOptions& o) {
  const Eigen::Index n = angle.size();
  std::vector<HalfCycle> out;
  if (n < 3) return out;
  const Eigen::Index m = n - 1;
  Eigen::VectorXd d = angle.tail(m) - angle.head(m);
  const double mean_step = d.cwiseAbs().mean();
  for (Eigen::Index k = 0; k < m; ++k)
    if (std::abs(d[k]) < o.step_threshold_factor * mean_step || mean_step == 0.0) d[k] = 0.0;
  // zero-phase moving average (centred window, shortened at the ends)
  const Eigen::Index hw = o.step_filter_window / 2;
  std::vector<int> sign(static_cast<size_t>(m), 0);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Index a = std::max<Eigen::Index>(0, k - hw), b = std::min<Eigen::Index>(m - 1, k + hw);
    const double f = d.segment(a, b - a + 1).mean();
    sign[static_cast<size_t>(k)] = f > 0 ? 1 : (f < 0 ? -1 : 0);
  }
  struct Run {
    Eigen::Index first, last;
    int sign;
  };
  // runs of one sign; zeros between entries of the same sign belong to the run
  std::vector<Run> runs;
  for (Eigen::Index k = 0; k < m; ++k) {
    const int s = sign[static_cast<size_t>(k)];
    if (s == 0) continue;
    if (!runs.empty() && runs.back().sign == s)
      runs.back().last = k;
    else
      runs.push_back({k, k, s});
  }
  // drop turning-region flicker, then merge neighbours of equal sign
  std::vector<Run> merged;
  for (const Run& r : runs) {
    if (r.last - r.first + 1 < o.min_run_samples) continue;
    if (!merged.empty() && merged.back().sign == r.sign)
      merged.back().last = r.last;
    else
      merged.push_back(r);
  }
  for (const Run& r : merged) {
    HalfCycle h;
    h.first = static_cast<int>(r.first);
    h.last = static_cast<int>(r.last + 1);  // step k joins samples k and k+1
    h.direction = r.sign;
    out.push_back(h);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------- step 6

GridCurve mergeCurves(const std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>& curves, int min_cover, int n) {
  GridCurve out;
  std::vector<double> ends;
  for (const auto& c : curves)
    if (c.first.size() >= 2) {
      ends.push_back(c.first[0]);
      ends.push_back(c.first[c.first.size() - 1]);
    }
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  auto cover = [&](double a, double b) {
    int k = 0;
    for (const auto& c : curves)
      if (c.first.size() >= 2 && c.first[0] <= a && c.first[c.first.size() - 1] >= b) ++k;
    return k;
  };
  // longest contiguous union of elementary intervals covered by >= min_cover curves
  double best_lo = 0, best_hi = 0, cur_lo = 0;
  bool in_run = false;
  for (size_t i = 0; i + 1 < ends.size(); ++i) {
    const bool ok = cover(ends[i], ends[i + 1]) >= min_cover;
    if (ok && !in_run) {
      cur_lo = ends[i];
      in_run = true;
    }
    if (ok && ends[i + 1] - cur_lo > best_hi - best_lo) {
      best_lo = cur_lo;
      best_hi = ends[i + 1];
    }
    if (!ok) in_run = false;
  }
  if (!(best_hi > best_lo)) return out;
  out.x = Eigen::VectorXd::LinSpaced(n, best_lo, best_hi);
  out.tau.resize(n);
  for (int i = 0; i < n; ++i) {
    double sum = 0;
    int k = 0;
    for (const auto& c : curves) {
      if (c.first.size() < 2) continue;
      const double eps = 1e-12 * (best_hi - best_lo);
      if (out.x[i] < c.first[0] - eps || out.x[i] > c.first[c.first.size() - 1] + eps) continue;
      sum += interp(c.first, c.second, out.x[i]);
      ++k;
    }
    out.tau[i] = k > 0 ? sum / k : 0.0;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------- steps 8-11

Eigen::VectorXd localSlope(const GridCurve& c, int window) {
  const Eigen::Index n = c.x.size();
  const Eigen::Index hw = std::max(1, window / 2);
  Eigen::VectorXd s(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index a = std::max<Eigen::Index>(0, i - hw), b = std::min<Eigen::Index>(n - 1, i + hw);
    s[i] = fitLine(c.x, c.tau, a, b).slope;
  }
  return s;
}

std::pair<int, int> longestFlatRun(const Eigen::VectorXd& slope, double threshold) {
  const int n = static_cast<int>(slope.size());
  std::pair<int, int> best{-1, -1};
  int i = 0;
  while (i < n) {
    if (slope[i] >= threshold) {
      ++i;
      continue;
    }
    int j = i;
    while (j + 1 < n && slope[j + 1] < threshold) ++j;
    const bool interior = i > 0 && j < n - 1;
    if (interior && (best.first < 0 || j - i > best.second - best.first)) best = {i, j};
    i = j + 1;
  }
  return best;
}

namespace {
int slopeWindow(const GridCurve& c, const ClampingCurveOptions& o) {
  const double span = c.x[c.x.size() - 1] - c.x[0];
  const double h = span / static_cast<double>(c.x.size() - 1);
  return std::max(3, static_cast<int>(std::lround(o.slope_window_fraction * span / h)));
}
}  // namespace

GridCurve foldCurve(const GridCurve& merged, double middle, const ClampingCurveOptions& o, double& flat,
                    double& stiffness) {
  const Eigen::Index n = merged.x.size();
  const double h = (merged.x[n - 1] - merged.x[0]) / static_cast<double>(n - 1);
  const double reach = std::min(middle - merged.x[0], merged.x[n - 1] - middle);
  const int nj = static_cast<int>(std::floor(reach / h + 1e-9)) + 1;
  GridCurve f;
  if (nj < o.min_linear_points + 2)
    throw UnidentifiableError("stiffness: the merged clamping curve is too uneven around its middle (" +
                              std::to_string(nj) + " fold points), no linear region to fit");
  f.x.resize(nj);
  f.tau.resize(nj);
  for (int j = 0; j < nj; ++j) {
    f.x[j] = j * h;
    f.tau[j] = 0.5 * (merged.at(middle + j * h) - merged.at(middle - j * h));
  }
  // step 11: initial flat interval (dF/dj < φ × LS slope of F), then the LS slope beyond it
  const int window = std::max(3, static_cast<int>(std::lround(o.slope_window_fraction * 2.0 * (nj - 1))));
  const Eigen::VectorXd slope = localSlope(f, window);
  const double thr = o.slope_threshold * fitLine(f.x, f.tau).slope;
  int k = 0;
  while (k < nj && slope[k] < thr) ++k;
  flat = k > 0 ? f.x[std::min(k, nj - 1)] : 0.0;
  const int start = std::min(nj, k + window / 2);  // beyond the window's reach into the flat part
  if (nj - start < o.min_linear_points)
    throw UnidentifiableError("stiffness: no linear region beyond the backlash interval of the folded clamping "
                              "curve (" +
                              std::to_string(std::max(0, nj - start)) + " points, need " +
                              std::to_string(o.min_linear_points) + ")");
  const Line lin = fitLine(f.x, f.tau, start, nj - 1);
  stiffness = lin.slope;
  if (!(stiffness > 0))
    throw UnidentifiableError("stiffness: the linear region of the folded clamping curve has slope " +
                              curveNum(stiffness) + " N*m/rad (not positive)");
  return f;
}

// ---------------------------------------------------------------------------------------------------- steps
namespace {

/// Samples where the angle step on both sides is below the step-1 threshold (the motor does not move).
std::vector<char> stuckSamples(const ClampingData& data, const ClampingCurveOptions& o) {
  std::vector<char> stuck(static_cast<size_t>(data.angle.size()), 0);
  if (!o.drop_stuck_points) return stuck;
  const Eigen::Index n = data.angle.size();
  const Eigen::VectorXd d = data.angle.tail(n - 1) - data.angle.head(n - 1);
  const double thr = o.step_threshold_factor * d.cwiseAbs().mean();
  auto still = [&](Eigen::Index k) { return k < 0 || k >= n - 1 || std::abs(d[k]) < thr; };
  for (Eigen::Index k = 0; k < n; ++k) stuck[static_cast<size_t>(k)] = still(k - 1) && still(k);
  return stuck;
}

/// Step 2: cleans one half-cycle (drops stuck samples, the extreme angles, the turning ends, points off its LS
/// line) and sets its line; rejects it when too few points are left.
void cleanHalfCycle(HalfCycle& h, const ClampingData& data, const std::vector<char>& stuck, double mean_position,
                    const ClampingCurveOptions& o) {
  std::vector<int> idx;
  for (int k = h.first; k <= h.last; ++k)
    if (!stuck[static_cast<size_t>(k)]) idx.push_back(k);
  std::sort(idx.begin(), idx.end(), [&](int a, int b) { return data.angle[a] < data.angle[b]; });
  const size_t cut = static_cast<size_t>(std::floor(o.extreme_fraction * static_cast<double>(idx.size())));
  if (2 * cut < idx.size())
    idx = std::vector<int>(idx.begin() + static_cast<long>(cut), idx.end() - static_cast<long>(cut));
  if (!idx.empty()) {
    const double lo = data.angle[idx.front()], hi = data.angle[idx.back()];
    const double a = lo + o.end_trim_fraction * (hi - lo), b = hi - o.end_trim_fraction * (hi - lo);
    std::vector<int> kept;
    for (int k : idx)
      if (data.angle[k] >= a && data.angle[k] <= b) kept.push_back(k);
    idx.swap(kept);
  }
  auto line = [&](const std::vector<int>& v) {
    return fitLine(
        v.size(), [&](size_t i) { return data.angle[v[i]]; }, [&](size_t i) { return data.torque[v[i]]; });
  };
  if (idx.size() >= 3) {
    const Line l = line(idx);
    double ss = 0;
    for (int k : idx) ss += std::pow(data.torque[k] - l(data.angle[k]), 2);
    const double sigma = std::sqrt(ss / static_cast<double>(idx.size()));
    std::vector<int> kept;
    for (int k : idx)
      if (std::abs(data.torque[k] - l(data.angle[k])) <= o.point_kappa * sigma) kept.push_back(k);
    idx.swap(kept);
  }
  if (static_cast<int>(idx.size()) < o.min_points) {
    h.rejected = true;
    h.reason = "cleaning: " + std::to_string(idx.size()) + " points left, need " + std::to_string(o.min_points);
    return;
  }
  std::sort(idx.begin(), idx.end());  // sample order
  h.kept = idx;
  const Line l = line(idx);
  h.slope = l.slope;
  h.rep_torque = l(mean_position);
}

/// Steps 3–5: half-cycle outliers among all, classification into upper and lower curve (the direction must
/// match the side friction pushes it to), outliers per curve.
void classifyHalfCycles(std::vector<HalfCycle>& hcs, const ClampingCurveOptions& o, double torque_half_span) {
  rejectOutlierHalfCycles(hcs, active(hcs, -1), o, torque_half_span, "step 3 (all half-cycles)");
  const std::vector<int> act = active(hcs, -1);
  double mean_rep = 0;
  for (int i : act) mean_rep += hcs[i].rep_torque;
  if (!act.empty()) mean_rep /= static_cast<double>(act.size());
  for (int i : act) {
    HalfCycle& h = hcs[i];
    h.upper = h.rep_torque > mean_rep;
    if ((h.direction > 0) != h.upper) {
      h.rejected = true;
      h.reason = std::string("step 4: classified ") + (h.upper ? "upper" : "lower") + " but the angle " +
                 (h.direction > 0 ? "increases" : "decreases") + " (friction would act the other way)";
    }
  }
  rejectOutlierHalfCycles(hcs, active(hcs, 1), o, torque_half_span, "step 5 (upper curve)");
  rejectOutlierHalfCycles(hcs, active(hcs, 0), o, torque_half_span, "step 5 (lower curve)");
}

/// After step 5: counts the half-cycles per curve and refuses data that cannot identify (too many rejected, a
/// curve without half-cycles, a falling torque).
void requireUsableHalfCycles(ClampingCurves& r, const ClampingCurveOptions& o) {
  const std::vector<HalfCycle>& hcs = r.half_cycles;
  const std::vector<int> up = active(hcs, 1), lo = active(hcs, 0);
  r.used_upper = static_cast<int>(up.size());
  r.used_lower = static_cast<int>(lo.size());
  r.rejected = static_cast<int>(hcs.size()) - r.used_upper - r.used_lower;
  auto reasons = [&] {
    std::string s;
    for (size_t i = 0; i < hcs.size(); ++i)
      if (hcs[i].rejected) s += "; half-cycle " + std::to_string(i + 1) + ": " + hcs[i].reason;
    return s;
  };
  const double frac = static_cast<double>(r.rejected) / static_cast<double>(hcs.size());
  if (frac > o.max_rejected_fraction)
    throw UnidentifiableError("clamping curve: " + std::to_string(r.rejected) + " of " + std::to_string(hcs.size()) +
                              " half-cycles rejected (more than " + curveNum(100 * o.max_rejected_fraction) +
                              " %), too few points between the turning regions" + reasons());
  if (up.empty() || lo.empty())
    throw UnidentifiableError(std::string("friction: no ") + (up.empty() ? "upper (loading)" : "lower (unloading)") +
                              " half-cycle left, the branch distance is unobservable" + reasons());
  double ms = 0;
  for (int i : up) ms += hcs[i].slope;
  for (int i : lo) ms += hcs[i].slope;
  if (!(ms > 0))
    throw UnidentifiableError("stiffness: the torque decreases with the angle (mean half-cycle slope " +
                              curveNum(ms / static_cast<double>(up.size() + lo.size())) +
                              " N*m/rad); check the sign conventions of the angle and torque columns");
}

/// Step 6: merges the kept points of one curve's half-cycles onto a grid (partial half-cycles left out: they
/// would lower the coverage of the central interval).
GridCurve mergeGroup(const std::vector<HalfCycle>& hcs, const std::vector<int>& g_all, const ClampingData& data,
                     const ClampingCurveOptions& o) {
  double longest = 0;
  auto span = [&](int i) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k : hcs[i].kept) lo = std::min(lo, data.angle[k]), hi = std::max(hi, data.angle[k]);
    return hcs[i].kept.empty() ? 0.0 : hi - lo;
  };
  for (int i : g_all) longest = std::max(longest, span(i));
  std::vector<int> g;
  for (int i : g_all)
    if (span(i) >= o.min_span_fraction * longest) g.push_back(i);
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> curves;
  for (int i : g) {
    std::vector<int> v = hcs[i].kept;
    std::sort(v.begin(), v.end(), [&](int a, int b) { return data.angle[a] < data.angle[b]; });
    Eigen::VectorXd x(static_cast<Eigen::Index>(v.size())), t(static_cast<Eigen::Index>(v.size()));
    for (size_t k = 0; k < v.size(); ++k) {
      x[static_cast<Eigen::Index>(k)] = data.angle[v[k]];
      t[static_cast<Eigen::Index>(k)] = data.torque[v[k]];
    }
    curves.emplace_back(x, t);
  }
  const double need = o.coverage_fraction * static_cast<double>(g.size());
  const int cover = std::max(1, static_cast<int>(std::ceil(need - 1e-9)));
  return mergeCurves(curves, cover, o.grid_points);
}

/// Step 7: the friction is half the mean distance of the upper and lower curves over their common interval;
/// returns both sampled there.
std::pair<GridCurve, GridCurve> estimateFriction(ClampingCurves& r, const ClampingCurveOptions& o) {
  const double c_lo = std::max(r.upper.x[0], r.lower.x[0]);
  const double c_hi = std::min(r.upper.x[r.upper.x.size() - 1], r.lower.x[r.lower.x.size() - 1]);
  if (!(c_hi > c_lo)) throw UnidentifiableError("friction: the upper and lower curves do not overlap in position");
  GridCurve u = sampleCurve(r.upper, c_lo, c_hi, o.grid_points);
  GridCurve l = sampleCurve(r.lower, c_lo, c_hi, o.grid_points);
  r.friction = 0.5 * (u.tau - l.tau).mean();
  return {u, l};
}

/// Observability of the backlash: the mid-line (upper + lower)/2 = EB(x) must take both signs. When it does
/// not (no traversal of the gap), sets the stiffness from the mid-line and the centre where it crosses zero
/// (extrapolated), backlash 0, and returns false.
bool backlashObservable(ClampingCurves& r, const GridCurve& u, const GridCurve& l, const ClampingCurveOptions& o) {
  const Eigen::VectorXd mid = 0.5 * (u.tau + l.tau);
  const double big = mid.cwiseAbs().maxCoeff();
  int neg = 0, pos = 0;
  for (Eigen::Index i = 0; i < mid.size(); ++i) {
    if (mid[i] < -o.zero_margin * big) ++neg;
    if (mid[i] > o.zero_margin * big) ++pos;
  }
  const double need = o.min_side_fraction * static_cast<double>(mid.size());
  r.crosses_zero = neg >= need && pos >= need && big > 0;
  if (r.crosses_zero) return true;
  const GridCurve m{u.x, mid};
  const Line lin = fitLine(m.x, m.tau);
  r.stiffness = lin.slope;
  if (!(r.stiffness > 0))
    throw UnidentifiableError("stiffness: the clamping curve's mid-line has slope " + curveNum(r.stiffness) +
                              " N*m/rad (not positive)");
  r.center = lin.x_mean - lin.intercept / lin.slope;
  r.backlash = 0.0;
  return false;
}

/// Step 8: the middle of a curve's backlash (low-slope) interval and its length; without one, the position
/// where the curve is closest to `level`.
double flatMiddle(const GridCurve& c, double level, double& length, const ClampingCurveOptions& o) {
  const Eigen::VectorXd s = localSlope(c, slopeWindow(c, o));
  const double thr = o.slope_threshold * fitLine(c.x, c.tau).slope;
  const auto run = longestFlatRun(s, thr);
  if (run.first >= 0) {
    length = c.x[run.second] - c.x[run.first];
    return 0.5 * (c.x[run.first] + c.x[run.second]);
  }
  length = 0.0;
  Eigen::Index best = 0;
  (c.tau.array() - level).abs().minCoeff(&best);
  return c.x[best];
}

/// Step 9: shifts the lower curve horizontally (backlash middles coincide) and up (mean distance) and merges it
/// with the upper curve.
GridCurve alignAndMerge(const ClampingCurves& r, double mid_u, double mid_l, const ClampingCurveOptions& o) {
  GridCurve lower_shifted = r.lower;
  lower_shifted.x.array() += mid_u - mid_l;
  const double a = std::max(r.upper.x[0], lower_shifted.x[0]);
  const double b = std::min(r.upper.x[r.upper.x.size() - 1], lower_shifted.x[lower_shifted.x.size() - 1]);
  if (!(b > a)) throw UnidentifiableError("friction: the aligned upper and lower curves do not overlap");
  const GridCurve us = sampleCurve(r.upper, a, b, o.grid_points);
  const GridCurve ls = sampleCurve(lower_shifted, a, b, o.grid_points);
  lower_shifted.tau.array() += (us.tau - ls.tau).mean();
  return mergeCurves({{r.upper.x, r.upper.tau}, {lower_shifted.x, lower_shifted.tau}}, 1, o.grid_points);
}

/// Steps 10–11: fold the merged curve about its middle; the backlash is twice the x-intercept of the fold's
/// linear part (the flat length of the fold is half the total backlash, our reading of [KR300Thesis, §4.3,
/// Algorithm II step 11]; the derivative window biases the threshold crossing, the intercept is the kink itself).
void foldAndMeasure(ClampingCurves& r, const ClampingCurveOptions& o) {
  double unused = 0;
  r.center = flatMiddle(r.merged, r.friction, unused, o);
  r.folded = foldCurve(r.merged, r.center, o, r.fold_flat, r.stiffness);
  const Eigen::Index nj = r.folded.x.size();
  const int window = std::max(3, static_cast<int>(std::lround(o.slope_window_fraction * 2.0 * (nj - 1))));
  const Eigen::Index k = static_cast<Eigen::Index>(std::lround(r.fold_flat / (r.folded.x[1] - r.folded.x[0])));
  const Eigen::Index start = std::min<Eigen::Index>(nj - 2, k + window / 2);
  const Line lin = fitLine(r.folded.x, r.folded.tau, start, nj - 1);
  const double x0 = lin.x_mean - lin.intercept / lin.slope;
  r.backlash = std::max(0.0, 2.0 * x0);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------- driver

ClampingCurves preprocessClampingCurve(const ClampingData& data, const ClampingCurveOptions& o) {
  o.validate();
  data.validate();
  ClampingCurves r;
  r.mean_position = data.angle.mean();
  r.torque_half_span = 0.5 * (data.torque.maxCoeff() - data.torque.minCoeff());
  r.half_cycles = segmentHalfCycles(data.angle, o);  // step 1
  if (r.half_cycles.size() < 2)
    throw InputError(where(data.source) + ": found " + std::to_string(r.half_cycles.size()) +
                     " half-cycle(s) (runs of one direction of motion), need at least 2: the motor angle must move "
                     "back and forth as in a clamping experiment");
  const std::vector<char> stuck = stuckSamples(data, o);
  for (HalfCycle& h : r.half_cycles) cleanHalfCycle(h, data, stuck, r.mean_position, o);  // step 2
  classifyHalfCycles(r.half_cycles, o, r.torque_half_span);                               // steps 3–5
  requireUsableHalfCycles(r, o);
  r.upper = mergeGroup(r.half_cycles, active(r.half_cycles, 1), data, o);  // step 6
  r.lower = mergeGroup(r.half_cycles, active(r.half_cycles, 0), data, o);
  if (r.upper.empty() || r.lower.empty())
    throw UnidentifiableError("clamping curve: the half-cycles of the " +
                              std::string(r.upper.empty() ? "upper" : "lower") +
                              " curve do not cover a common position interval");
  const auto [u, l] = estimateFriction(r, o);  // step 7
  if (!backlashObservable(r, u, l, o)) return r;
  const double mid_u = flatMiddle(r.upper, r.friction, r.backlash_upper, o);  // step 8
  const double mid_l = flatMiddle(r.lower, -r.friction, r.backlash_lower, o);
  r.merged = alignAndMerge(r, mid_u, mid_l, o);  // step 9
  foldAndMeasure(r, o);                          // steps 10–11
  return r;
}

}  // namespace jointsim::identify
