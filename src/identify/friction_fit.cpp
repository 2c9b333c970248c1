#include "jointsim/identify/friction_fit.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <tuple>
#include <utility>

#include <Eigen/SVD>
#include <ceres/ceres.h>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "quiet_ceres.hpp"

namespace jointsim::identify {
namespace {

constexpr int kNumParams = 4;       // α0, α1, α2, v_S
constexpr double kDeltaMin = 0.25;  // bounds of a free δ [-]
constexpr double kDeltaMax = 8.0;
constexpr double kSignificance = 3.0;  // α1 must exceed this many standard errors
constexpr double kDipFactor = 2.0;     // points slower than kDipFactor·v_S sample the Stribeck dip
constexpr int kMinDipPoints = 3;

/// Residual of one point of one direction: α0 + α1·exp(−(w/v_S)^δ) + α2·w − y [N·m], w = |v| > 0.
struct MapResidual {
  MapResidual(double w, double y) : w_(w), y_(y) {}
  template <typename T>
  bool operator()(const T* p, const T* delta, T* r) const {
    using std::exp;
    using std::pow;
    const T x = T(w_) / p[3];
    r[0] = p[0] + p[1] * exp(-pow(x, delta[0])) + p[2] * T(w_) - T(y_);
    return true;
  }

 private:
  double w_, y_;
};

/// The points of one direction as magnitudes, sorted by speed.
struct Branch {
  std::string name;       // "positive" / "negative"
  std::string label;      // "positive direction (v > 0)"
  std::vector<double> w;  // |v| [rad/s], ascending
  std::vector<double> y;  // friction magnitude [N·m]
};

[[noreturn]] void unidentifiable(const Branch& b, const std::string& reason) {
  throw UnidentifiableError(b.label + ": " + reason);
}

/// Straight line y = a + b·w through the points [first, last) by least squares.
std::pair<double, double> lineFit(const Branch& br, size_t first, size_t last) {
  const double n = static_cast<double>(last - first);
  double sw = 0, sy = 0, sww = 0, swy = 0;
  for (size_t i = first; i < last; ++i) {
    sw += br.w[i];
    sy += br.y[i];
    sww += br.w[i] * br.w[i];
    swy += br.w[i] * br.y[i];
  }
  const double den = n * sww - sw * sw;
  if (!(std::abs(den) > 1e-300)) return {sy / n, 0.0};
  const double slope = (n * swy - sw * sy) / den;
  return {(sy - slope * sw) / n, slope};
}

/// Initial guess [α0, α1, α2, v_S] from the data (see the header, step 2).
std::array<double, kNumParams> initialGuess(const Branch& br) {
  const size_t n = br.w.size();
  const size_t n_hi = std::max<size_t>(3, n / 3);
  auto [a0, a2] = lineFit(br, n - n_hi, n);
  if (a2 < 0) {  // no visible viscous rise: flat line at the mean of the fast points
    a2 = 0;
    a0 = 0;
    for (size_t i = n - n_hi; i < n; ++i) a0 += br.y[i] / static_cast<double>(n_hi);
  }
  double y_max = 0;
  for (double y : br.y) y_max = std::max(y_max, std::abs(y));
  a0 = std::max(a0, 1e-3 * y_max + 1e-12);

  std::vector<double> excess(n);
  for (size_t i = 0; i < n; ++i) excess[i] = br.y[i] - (a0 + a2 * br.w[i]);
  const size_t n_lo = std::min<size_t>(3, n);
  double a1 = 0;
  for (size_t i = 0; i < n_lo; ++i) a1 += excess[i] / static_cast<double>(n_lo);
  a1 = std::max(a1, 0.05 * a0);

  // v_S: first speed at which the (3-point averaged) excess has decayed below α1/e.
  double vs = std::sqrt(br.w.front() * br.w.back());
  for (size_t i = 1; i + 2 < n; ++i) {
    const double e = (excess[i] + excess[i + 1] + excess[i + 2]) / 3.0;
    if (e < a1 / std::exp(1.0)) {
      vs = std::sqrt(br.w[i - 1] * br.w[i]);
      break;
    }
  }
  return {a0, a1, a2, vs};
}

/// Lower and upper bound of v_S [rad/s].
std::pair<double, double> vsBounds(const Branch& br) { return {br.w.front() / 100.0, br.w.back() * 100.0}; }

ceres::LossFunction* makeLoss(const FrictionFitOptions& o) {
  switch (o.loss) {
    case FitLoss::Huber: return new ceres::HuberLoss(o.loss_scale);
    case FitLoss::Cauchy: return new ceres::CauchyLoss(o.loss_scale);
    case FitLoss::None: break;
  }
  return nullptr;
}

/// Adds the residuals of one direction, its bounds and the shared δ block to `problem`.
void addBranch(ceres::Problem& problem, const Branch& br, double* p, double* delta, const FrictionFitOptions& o) {
  for (size_t i = 0; i < br.w.size(); ++i)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<MapResidual, 1, kNumParams, 1>(
                                 new MapResidual(br.w[i], br.y[i])),
                             makeLoss(o), p, delta);
  for (int k = 0; k < 3; ++k) problem.SetParameterLowerBound(p, k, 0.0);
  const auto [lo, hi] = vsBounds(br);
  problem.SetParameterLowerBound(p, 3, lo);
  problem.SetParameterUpperBound(p, 3, hi);
}

ceres::Solver::Options solverOptions(const FrictionFitOptions& o) {
  ceres::Solver::Options s;
  s.linear_solver_type = ceres::DENSE_QR;
  s.max_num_iterations = o.max_iterations;
  s.function_tolerance = 1e-14;
  s.gradient_tolerance = 1e-16;
  s.parameter_tolerance = 1e-14;
  s.logging_type = ceres::SILENT;
  s.minimizer_progress_to_stdout = false;
  s.num_threads = 1;
  return s;
}

/// Sum of squared (plain) residuals of a direction [N·m²].
double ssr(const Branch& br, const double* p, double delta) {
  double s = 0;
  for (size_t i = 0; i < br.w.size(); ++i) {
    const double r = p[0] + p[1] * std::exp(-std::pow(br.w[i] / p[3], delta)) + p[2] * br.w[i] - br.y[i];
    s += r * r;
  }
  return s;
}

/// Fits one direction with δ fixed, from several starts of v_S; returns the best parameters.
std::array<double, kNumParams> fitBranch(const Branch& br, double delta, const FrictionFitOptions& o,
                                         const std::array<double, kNumParams>& guess, int& iterations) {
  std::array<double, kNumParams> best = guess;
  double best_cost = INFINITY;
  const auto [lo, hi] = vsBounds(br);
  for (double factor : {1.0, 0.3, 3.0}) {
    std::array<double, kNumParams> p = guess;
    p[3] = std::clamp(guess[3] * factor, lo, hi);
    double d = delta;
    ceres::Problem problem;
    addBranch(problem, br, p.data(), &d, o);
    problem.SetParameterBlockConstant(&d);
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(o), &problem, &summary);
    iterations += static_cast<int>(summary.iterations.size());
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best = p;
    }
  }
  return best;
}

/// Covariance blocks (unscaled (J^T J)^{-1}) of the given parameter blocks; false if singular.
bool covariance(ceres::Problem& problem, const std::vector<std::pair<const double*, int>>& blocks,
                std::vector<std::vector<double>>& out) {
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = 0;
  co.min_reciprocal_condition_number = 1e-14;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (const auto& b : blocks) pairs.emplace_back(b.first, b.first);
  if (!cov.Compute(pairs, &problem)) return false;
  out.clear();
  for (const auto& b : blocks) {
    std::vector<double> c(static_cast<size_t>(b.second * b.second));
    if (!cov.GetCovarianceBlock(b.first, b.first, c.data())) return false;
    for (double x : c)
      if (!std::isfinite(x)) return false;
    out.push_back(std::move(c));
  }
  return true;
}

/// Sum of squared residuals for the variance estimate [N·m²]: plain, or with a robust loss the IRLS-weighted
/// Σ ρ'(r²)·r², so that rejected outliers do not inflate σ².
double varianceSsr(const Branch& br, const double* p, double delta, const FrictionFitOptions& o) {
  const std::unique_ptr<ceres::LossFunction> loss(makeLoss(o));
  if (!loss) return ssr(br, p, delta);
  double s = 0;
  for (size_t i = 0; i < br.w.size(); ++i) {
    const double r = p[0] + p[1] * std::exp(-std::pow(br.w[i] / p[3], delta)) + p[2] * br.w[i] - br.y[i];
    double rho[3];
    loss->Evaluate(r * r, rho);
    s += rho[1] * r * r;
  }
  return s;
}

void fillDirection(DirectionFit& d, const Branch& br, const std::array<double, kNumParams>& p,
                   const std::array<double, kNumParams>& guess, const std::vector<double>& cov, double delta,
                   int n_params, const FrictionFitOptions& o) {
  const double m = static_cast<double>(br.w.size());
  const double s = ssr(br, p.data(), delta);
  d.direction = br.name;
  d.points = static_cast<int>(br.w.size());
  d.min_speed = br.w.front();
  d.max_speed = br.w.back();
  d.rms_residual = std::sqrt(s / m);
  d.sigma = std::sqrt(varianceSsr(br, p.data(), delta, o) / (m - n_params));
  ParameterEstimate* est[kNumParams] = {&d.alpha0, &d.alpha1, &d.alpha2, &d.v_s};
  for (int k = 0; k < kNumParams; ++k) {
    est[k]->value = p[static_cast<size_t>(k)];
    est[k]->initial = guess[static_cast<size_t>(k)];
    est[k]->std_error = d.sigma * std::sqrt(std::max(0.0, cov[static_cast<size_t>(k * kNumParams + k)]));
  }
}

/// Whether the Jacobian of `problem` with respect to `blocks` has full column rank: smallest over largest
/// singular value above 1e-6 (ceres::Covariance with DENSE_SVD fails below sqrt(1e-14) = 1e-7 and logs).
bool wellConditioned(ceres::Problem& problem, const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = blocks;
  eo.num_threads = 1;
  ceres::CRSMatrix jac;
  if (!problem.Evaluate(eo, nullptr, nullptr, nullptr, &jac)) return false;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(jac.num_rows, jac.num_cols);
  for (int r = 0; r < jac.num_rows; ++r)
    for (int k = jac.rows[static_cast<size_t>(r)]; k < jac.rows[static_cast<size_t>(r) + 1]; ++k)
      J(r, jac.cols[static_cast<size_t>(k)]) = jac.values[static_cast<size_t>(k)];
  if (!J.allFinite()) return false;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
  const Eigen::VectorXd& sv = svd.singularValues();
  return sv.size() > 0 && sv(0) > 0 && sv(sv.size() - 1) > 1e-6 * sv(0);
}

/// Reason for a singular problem: no visible Stribeck term, or a generic one.
std::string singularReason(const Branch& br, const std::array<double, kNumParams>& p, double delta) {
  const double effect = p[1] * std::exp(-std::pow(br.w.front() / p[3], delta));  // Stribeck term at min |v|
  if (effect <= 1e-6 * (p[0] + p[1]))
    return "no Stribeck dip: the best fit puts v_s = " + formatShortest(p[3]) + " rad/s far below the slowest point (" +
           formatShortest(br.w.front()) +
           " rad/s), so alpha1 and v_s have no effect on the data (fit a Coulomb–viscous model "
           "instead, or measure slower speeds)";
  return "the parameters are not determined by the data (singular covariance at alpha0 = " + formatShortest(p[0]) +
         ", alpha1 = " + formatShortest(p[1]) + ", alpha2 = " + formatShortest(p[2]) +
         ", v_s = " + formatShortest(p[3]) + ")";
}

/// The checks of the header's step 5 that need the fitted values.
void checkIdentifiable(const Branch& br, const DirectionFit& d, const FrictionFitOptions& o) {
  if (d.alpha1.value <= kSignificance * d.alpha1.std_error)
    unidentifiable(br, "no significant Stribeck dip: alpha1 = " + formatShortest(d.alpha1.value) +
                           " N·m with standard error " + formatShortest(d.alpha1.std_error) +
                           " N·m, so v_s cannot be determined (fit a Coulomb–viscous "
                           "model instead, or measure slower speeds)");
  int dip = 0;
  for (double w : br.w) dip += w < kDipFactor * d.v_s.value ? 1 : 0;
  if (dip < kMinDipPoints)
    unidentifiable(br, "only " + std::to_string(dip) +
                           " points slower than 2·v_s = " + formatShortest(kDipFactor * d.v_s.value) +
                           " rad/s (at least " + std::to_string(kMinDipPoints) +
                           " needed): the Stribeck dip is not sampled; measure slower speeds");
  const std::pair<const char*, const ParameterEstimate*> checked[] = {{"alpha0", &d.alpha0},
                                                                      {"alpha1", &d.alpha1},
                                                                      {"v_s", &d.v_s}};
  for (const auto& [name, e] : checked)
    if (!(e->std_error <= o.max_relative_std_error * std::abs(e->value)))
      unidentifiable(br, std::string(name) + " = " + formatShortest(e->value) + " has a standard error of " +
                             formatShortest(e->std_error) + " (more than " +
                             formatShortest(100 * o.max_relative_std_error) +
                             " % of the value): the data do not determine it");
}

}  // namespace

void FrictionFitOptions::validate() const {
  auto bad = [](const std::string& field, double value, const std::string& rule) {
    throw InputError("friction fit option '" + field + "': " + rule + ", got " + formatShortest(value));
  };
  if (!(delta > 0) || !std::isfinite(delta)) bad("delta", delta, "expected a finite form factor > 0");
  if (fit_delta && !(delta >= kDeltaMin && delta <= kDeltaMax))
    bad("delta", delta,
        "expected a start value in [" + formatShortest(kDeltaMin) + ", " + formatShortest(kDeltaMax) + "]");
  if (min_points < 6) bad("min_points", min_points, "expected at least 6 points per direction");
  if (!(loss_scale > 0) || !std::isfinite(loss_scale)) bad("loss_scale", loss_scale, "expected a finite scale > 0 N·m");
  if (!(max_relative_std_error > 0)) bad("max_relative_std_error", max_relative_std_error, "expected a value > 0");
  if (max_iterations < 1) bad("max_iterations", max_iterations, "expected at least 1");
}

drive::StribeckBranch DirectionFit::branch() const {
  return drive::StribeckBranch{alpha0.value, alpha1.value, alpha2.value, v_s.value};
}

double DirectionFit::magnitude(double w, double delta) const {
  return alpha0.value + alpha1.value * std::exp(-std::pow(w / v_s.value, delta)) + alpha2.value * w;
}

double FrictionFit::map(double v) const {
  if (v > 0) return positive.magnitude(v, delta.value);
  if (v < 0) return -negative.magnitude(-v, delta.value);
  return 0.0;
}

drive::ParameterChanges frictionChanges(const FrictionFit& fit, const drive::Friction& model) {
  const std::vector<drive::ParameterInfo> table = model.parameters();
  auto has = [&](const std::string& key) {
    for (const auto& p : table)
      if (p.key == key) return true;
    return false;
  };
  drive::ParameterChanges out;
  for (const DirectionFit* d : {&fit.positive, &fit.negative})
    for (const auto& [name, estimate] : {std::pair<const char*, const ParameterEstimate*>{"alpha0", &d->alpha0},
                                         {"alpha1", &d->alpha1},
                                         {"alpha2", &d->alpha2},
                                         {"v_s", &d->v_s}}) {
      const std::string key = d->direction + "." + name;
      if (!has(key))
        throw InputError("identified friction map: the " + model.type() + " friction model has no parameter '" + key +
                         "' (the map applies to models with the Stribeck static set: stribeck, lugre)");
      out.push_back({key, estimate->value});
    }
  if (has("delta")) {
    out.push_back({"delta", fit.delta.value});
  } else if (fit.delta.value != 2.0) {
    throw InputError("identified friction map: delta = " + formatShortest(fit.delta.value) + ", but the " +
                     model.type() + " friction model has its Stribeck curve with delta = 2 and no parameter for it");
  }
  return out;
}

FrictionFit fitFrictionMap(const std::vector<double>& velocity, const std::vector<double>& torque,
                           const FrictionFitOptions& options) {
  const QuietCeres quiet;
  const auto t0 = std::chrono::steady_clock::now();
  options.validate();
  if (velocity.size() != torque.size())
    throw InputError("friction map: " + std::to_string(velocity.size()) + " velocities but " +
                     std::to_string(torque.size()) + " torques");
  FrictionFit fit;
  Branch pos{"positive", "positive direction (v > 0)", {}, {}};
  Branch neg{"negative", "negative direction (v < 0)", {}, {}};
  std::vector<std::pair<double, double>> pts_pos, pts_neg;
  for (size_t i = 0; i < velocity.size(); ++i) {
    const double v = velocity[i], f = torque[i];
    if (!std::isfinite(v) || !std::isfinite(f))
      throw InputError("friction map point " + std::to_string(i) + ": expected finite velocity and torque, got " +
                       formatShortest(v) + " rad/s, " + formatShortest(f) + " N·m");
    if (v > 0)
      pts_pos.emplace_back(v, f);
    else if (v < 0)
      pts_neg.emplace_back(-v, -f);
    else
      ++fit.dropped_zero;
  }
  for (auto* pr : {&pts_pos, &pts_neg}) std::sort(pr->begin(), pr->end());
  for (const auto& [w, y] : pts_pos) pos.w.push_back(w), pos.y.push_back(y);
  for (const auto& [w, y] : pts_neg) neg.w.push_back(w), neg.y.push_back(y);

  for (const Branch* br : {&pos, &neg}) {
    if (br->w.empty())
      unidentifiable(*br, "no points (the map has only " + std::string(br == &pos ? "v <= 0" : "v >= 0") +
                              "); measure both directions");
    if (static_cast<int>(br->w.size()) < options.min_points)
      unidentifiable(*br, "only " + std::to_string(br->w.size()) + " points, at least " +
                              std::to_string(options.min_points) + " needed");
    if (br->w.front() == br->w.back())
      unidentifiable(*br, "all points have the same speed " + formatShortest(br->w.front()) + " rad/s");
  }

  // Stage 1: each direction alone with δ fixed (multi-start in v_S).
  std::array<double, kNumParams> p[2], guess[2];
  Branch* branches[2] = {&pos, &neg};
  DirectionFit* dirs[2] = {&fit.positive, &fit.negative};
  for (int k = 0; k < 2; ++k) {
    guess[k] = initialGuess(*branches[k]);
    p[k] = fitBranch(*branches[k], options.delta, options, guess[k], fit.iterations);
    // α1 at its bound makes the v_S column of the Jacobian vanish: say so before the covariance fails.
    double y_max = 0;
    for (double y : branches[k]->y) y_max = std::max(y_max, std::abs(y));
    if (p[k][1] <= 1e-9 * y_max)
      unidentifiable(*branches[k], "no Stribeck dip: the fitted alpha1 is 0 (friction does not rise towards v = 0), "
                                   "so v_s cannot be determined (fit a Coulomb–viscous model instead)");
  }
  double delta = options.delta;

  // Stage 2 (free δ only): both directions together, δ shared.
  ceres::Problem joint;
  if (options.fit_delta) {
    addBranch(joint, pos, p[0].data(), &delta, options);
    addBranch(joint, neg, p[1].data(), &delta, options);
    joint.SetParameterLowerBound(&delta, 0, kDeltaMin);
    joint.SetParameterUpperBound(&delta, 0, kDeltaMax);
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(options), &joint, &summary);
    fit.iterations += static_cast<int>(summary.iterations.size());
    if (!summary.IsSolutionUsable())
      throw UnidentifiableError("friction map: the fit with a free delta failed: " + summary.message);
  }

  // Covariance. The rank is checked first (same measure as ceres::Covariance's DENSE_SVD, stricter threshold),
  // so that a singular problem becomes an UnidentifiableError with a reason instead of a Ceres log line.
  const int n_params = kNumParams + (options.fit_delta ? 1 : 0);  // per direction (δ counted for both)
  for (int k = 0; k < 2; ++k) {
    ceres::Problem single;
    double d = delta;
    addBranch(single, *branches[k], p[k].data(), &d, options);
    single.SetParameterBlockConstant(&d);
    if (!wellConditioned(single, {p[k].data()}))
      unidentifiable(*branches[k], singularReason(*branches[k], p[k], delta));
    std::vector<std::vector<double>> cov;
    if (!options.fit_delta) {
      if (!covariance(single, {{p[k].data(), kNumParams}}, cov))
        unidentifiable(*branches[k], singularReason(*branches[k], p[k], delta));
      fillDirection(*dirs[k], *branches[k], p[k], guess[k], cov[0], delta, n_params, options);
    }
  }
  fit.delta.value = delta;
  fit.delta.initial = options.delta;
  fit.delta_fitted = options.fit_delta;
  if (options.fit_delta) {
    std::vector<std::vector<double>> cov;
    if (!wellConditioned(joint, {p[0].data(), p[1].data(), &delta}) ||
        !covariance(joint, {{p[0].data(), kNumParams}, {p[1].data(), kNumParams}, {&delta, 1}}, cov))
      throw UnidentifiableError("friction map: the form factor delta is not determined by the data (fit it with "
                                "delta fixed instead)");
    for (int k = 0; k < 2; ++k)
      fillDirection(*dirs[k], *branches[k], p[k], guess[k], cov[static_cast<size_t>(k)], delta, n_params, options);
    const double m = static_cast<double>(pos.w.size() + neg.w.size());
    const double s2 = (varianceSsr(pos, p[0].data(), delta, options) + varianceSsr(neg, p[1].data(), delta, options)) /
                      (m - (2 * kNumParams + 1));
    fit.delta.std_error = std::sqrt(s2 * std::max(0.0, cov[2][0]));
  }
  for (int k = 0; k < 2; ++k) checkIdentifiable(*branches[k], *dirs[k], options);
  fit.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fit;
}

FrictionMapData readFrictionMap(const std::string& path) {
  const io::CsvTable t = io::readCsv(path);
  const int cv = t.require("velocity[rad/s]", "the shaft velocity in rad/s");
  const int ct = t.require("friction_torque[N*m]", "the steady-state friction torque in N·m");
  // A unit written in the header must be the SI one.
  auto checkUnit = [&](int col, const std::vector<std::string>& accepted) {
    const std::string& h = t.header[static_cast<size_t>(col)];
    const size_t a = h.find('['), b = h.rfind(']');
    if (a == std::string::npos || b == std::string::npos || b < a) return;
    const std::string unit = h.substr(a + 1, b - a - 1);
    if (std::find(accepted.begin(), accepted.end(), unit) == accepted.end())
      throw InputError(path + ":1: column '" + h + "': expected the unit " + accepted.front() + ", got '" + unit + "'");
  };
  checkUnit(cv, {"rad/s"});
  checkUnit(ct, {"N*m", "N·m", "Nm", "N m", "N.m"});
  if (t.rows() == 0) throw InputError(path + ": no data rows after the header line");
  FrictionMapData d;
  for (Eigen::Index r = 0; r < t.rows(); ++r) {
    d.velocity.push_back(t.data(r, cv));
    d.torque.push_back(t.data(r, ct));
    d.lines.push_back(t.lines[static_cast<size_t>(r)]);
  }
  return d;
}

std::string frictionFitYaml(const FrictionFit& fit, const FrictionYamlOptions& o) {
  if (o.lugre) {
    if (fit.delta.value != 2.0)
      throw InputError("the LuGre model has delta = 2 ([Hauschild2003, eq. 4.17]); the fit used delta = " +
                       formatShortest(fit.delta.value) + ", write a stribeck block instead");
    if (!(o.sigma0 > 0) || !std::isfinite(o.sigma0))
      throw InputError("LuGre sigma0: expected a finite bristle stiffness > 0 N·m/rad, got " +
                       formatShortest(o.sigma0));
    if (!(o.sigma1 > 0) || !std::isfinite(o.sigma1))
      throw InputError("LuGre sigma1: expected a finite bristle damping > 0 N·m·s/rad, got " +
                       formatShortest(o.sigma1));
  } else if (!(o.k_s > 0) || !std::isfinite(o.k_s)) {
    throw InputError("stribeck k_s: expected a finite slope-limiter factor > 0 s/rad, got " + formatShortest(o.k_s));
  }
  std::ostringstream y;
  y << "# jointsim identify friction" << (o.source.empty() ? "" : ": " + o.source) << "\n"
    << "# Static friction map ([Hauschild2003, eq. 4.6] / LuGre steady state eq. 4.21), one parameter set per "
       "direction:\n"
    << "#   F(v) = (alpha0 + alpha1*exp(-(|v|/v_s)^delta))*sgn(v) + alpha2*v\n"
    << "# Units: alpha0, alpha1 [N*m], alpha2 [N*m*s/rad], v_s [rad/s], delta [-].\n"
    << "# `friction` is a friction-model block (e.g. the `model:` of a joint-rig `friction:` entry).\n"
    << "friction:\n";
  if (o.lugre) {
    y << "  type: lugre\n"
      << "  # sigma0/sigma1 are dynamic parameters: a static map cannot determine them. These values were given\n"
      << "  # on the command line (default: [Hauschild2003, §4.5.4], Watflex shoulder), not identified.\n"
      << "  sigma0: " << formatShortest(o.sigma0) << "   # bristle stiffness [N*m/rad]\n"
      << "  sigma1: " << formatShortest(o.sigma1) << "   # bristle damping [N*m*s/rad]\n";
  } else {
    y << "  type: stribeck\n"
      << "  delta: " << formatShortest(fit.delta.value) << "   # form factor [-]"
      << (fit.delta_fitted ? " (fitted)" : " (fixed)") << "\n"
      << "  k_s: " << formatShortest(o.k_s)
      << "   # slope limiter 1 - exp(-k_s|v|) of [Hauschild2003, eq. 4.24] [s/rad], not fitted: "
      << "it lowers the map by 1 % at |v| = 4.6/k_s and more below\n";
  }
  for (const DirectionFit* d : {&fit.positive, &fit.negative})
    y << "  " << d->direction << ": {alpha0: " << formatShortest(d->alpha0.value)
      << ", alpha1: " << formatShortest(d->alpha1.value) << ", alpha2: " << formatShortest(d->alpha2.value)
      << ", v_s: " << formatShortest(d->v_s.value) << "}   # v "
      << (d->direction == "positive" ? "> 0" : "< 0 (magnitudes)") << "\n";
  y << "fit:\n";
  if (!o.source.empty()) y << "  source: \"" << o.source << "\"\n";
  y << "  method: Ceres Levenberg-Marquardt, per-direction least squares on |v|; std_error = sqrt(diag((J^T J)^-1) "
       "* SSR/(m - p))\n"
    << "  delta: {value: " << formatShortest(fit.delta.value)
    << ", unit: \"-\", std_error: " << formatShortest(fit.delta.std_error)
    << ", fitted: " << (fit.delta_fitted ? "true" : "false") << "}\n"
    << "  dropped_zero_velocity_points: " << fit.dropped_zero << "   # v = 0 belongs to neither direction\n";
  if (o.wall_time_s >= 0) y << "  wall_time_s: " << formatShortest(o.wall_time_s) << "\n";
  for (const DirectionFit* d : {&fit.positive, &fit.negative}) {
    y << "  " << d->direction << ":\n"
      << "    points: " << d->points << "\n"
      << "    speed_range: [" << formatShortest(d->min_speed) << ", " << formatShortest(d->max_speed)
      << "]   # |v| [rad/s]\n"
      << "    rms_residual: " << formatShortest(d->rms_residual) << "   # [N*m]\n";
    const std::tuple<const char*, const char*, const ParameterEstimate*> rows[] = {{"alpha0", "N*m", &d->alpha0},
                                                                                   {"alpha1", "N*m", &d->alpha1},
                                                                                   {"alpha2", "N*m*s/rad", &d->alpha2},
                                                                                   {"v_s", "rad/s", &d->v_s}};
    for (const auto& [name, unit, e] : rows)
      y << "    " << name << ": {value: " << formatShortest(e->value) << ", unit: \"" << unit
        << "\", std_error: " << formatShortest(e->std_error) << ", initial: " << formatShortest(e->initial) << "}\n";
  }
  return y.str();
}

}  // namespace jointsim::identify
