// Drive parameters from measured motor currents along a motion (identify/current_fit.hpp).
#include "jointsim/identify/current_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <ceres/ceres.h>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "quiet_ceres.hpp"

namespace jointsim::identify {
namespace {

std::string currentFitNum(double v) { return formatNumber(v, 6); }

/// i = (τ + τ_f(v)) / (N k_t s) + i₀ − i_measured, parameters x = (s, F_c⁺, F_c⁻, F_v⁺, F_v⁻, i₀).
/// With `symmetric`, F_c⁻ = F_c⁺ (x[2] unused): the fit with an offset; with `tied`, also F_v⁻ = F_v⁺ (x[4] unused):
/// a motion in one direction only.
struct CurrentResidual {
  double tau, v, i, Nkt;
  bool symmetric, tied;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    const T tf = v > 0.0 ? x[1] + x[3] * v : -((symmetric || tied ? x[1] : x[2]) + (tied ? x[3] : x[4]) * (-v));
    r[0] = (T(tau) + tf) / (T(Nkt) * x[0]) + x[5] - T(i);
    return true;
  }
};

/// The joint torques τ = RNEA + J_M N² q̈ of every sample (K × n) [N·m].
Eigen::MatrixXd jointTorques(const multibody::Model& model, const std::vector<DriveNominal>& drives,
                             const CurrentLog& log) {
  const Eigen::Index K = log.q.rows(), n = model.nq;
  multibody::Data data(model);
  Eigen::MatrixXd tau(K, n);
  for (Eigen::Index k = 0; k < K; ++k) {
    const Eigen::VectorXd q = log.q.row(k).transpose(), qd = log.qd.row(k).transpose(),
                          qdd = log.qdd.row(k).transpose();
    tau.row(k) = multibody::rnea(model, data, q, qd, qdd).transpose();
    for (Eigen::Index j = 0; j < n; ++j) {
      const DriveNominal& d = drives[static_cast<size_t>(j)];
      tau(k, j) += d.rotor_inertia * d.ratio * d.ratio * qdd[j];
    }
  }
  return tau;
}

void checkInputs(const multibody::Model& model, const std::vector<DriveNominal>& drives, const CurrentLog& log) {
  const Eigen::Index n = model.nq;
  if (static_cast<Eigen::Index>(drives.size()) != n)
    throw InputError(log.source + ": " + std::to_string(drives.size()) + " drives for a robot of " + std::to_string(n) +
                     " joints");
  for (const Eigen::MatrixXd* m : {&log.q, &log.qd, &log.qdd, &log.current}) {
    if (m->cols() != n || m->rows() != log.q.rows())
      throw InputError(log.source + ": q, qd, qdd and current must all be K x " + std::to_string(n) + " (got " +
                       std::to_string(m->rows()) + " x " + std::to_string(m->cols()) + ")");
    if (!m->allFinite()) throw InputError(log.source + ": every value must be finite");
  }
  for (size_t j = 0; j < drives.size(); ++j)
    if (!(drives[j].ratio != 0.0 && std::isfinite(drives[j].ratio) && drives[j].kt > 0.0 &&
          drives[j].rotor_inertia >= 0.0))
      throw InputError(log.source + ": drive " + std::to_string(j) +
                       ": expected a non-zero ratio, kt > 0 N*m/A and a rotor inertia >= 0 kg*m^2");
}

}  // namespace

void CurrentFitOptions::validate() const {
  auto bad = [](const std::string& field, double v, const std::string& rule) {
    throw InputError("current fit options: " + field + ": expected " + rule + ", got " + currentFitNum(v));
  };
  if (!(min_speed >= 0.0 && std::isfinite(min_speed))) bad("min_speed", min_speed, "a speed >= 0 rad/s");
  if (!(scale_bound > 0.0 && scale_bound < 1.0)) bad("scale_bound", scale_bound, "a value in (0, 1)");
  if (!(max_offset >= 0.0 && std::isfinite(max_offset))) bad("max_offset", max_offset, "a current >= 0 A");
  if (max_iterations < 1) bad("max_iterations", max_iterations, "an integer >= 1");
}

CurrentFit fitDriveCurrents(const multibody::Model& model, const std::vector<DriveNominal>& drives,
                            const CurrentLog& log, const CurrentFitOptions& o) {
  const QuietCeres quiet;
  o.validate();
  checkInputs(model, drives, log);
  const Eigen::MatrixXd tau = jointTorques(model, drives, log);
  const Eigen::Index K = log.q.rows();
  CurrentFit fit;
  for (Eigen::Index j = 0; j < model.nq; ++j) {
    const std::string joint = model.joint_names[static_cast<size_t>(j)];
    const DriveNominal& d = drives[static_cast<size_t>(j)];
    const double Nkt = d.ratio * d.kt;
    double x[6] = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    int pos = 0, neg = 0;
    for (Eigen::Index k = 0; k < K; ++k) {
      const double v = log.qd(k, j);
      if (std::abs(v) >= o.min_speed && v != 0.0) (v > 0.0 ? pos : neg) += 1;
    }
    if (pos + neg < 40)
      throw UnidentifiableError(log.source + ": joint " + joint + ": " + std::to_string(pos) +
                                " samples moving forward and " + std::to_string(neg) + " backward faster than " +
                                currentFitNum(o.min_speed) + " rad/s: at least 40 moving samples are needed");
    const bool tied = pos < 20 || neg < 20;  // one direction only: one friction law for both
    ceres::Problem problem;
    for (Eigen::Index k = 0; k < K; ++k) {
      const double v = log.qd(k, j);
      if (std::abs(v) < o.min_speed || v == 0.0) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CurrentResidual, 1, 6>(
                                   new CurrentResidual{tau(k, j), v, log.current(k, j), Nkt, o.fit_offset, tied}),
                               nullptr, x);
    }
    const double lower[6] = {1.0 - o.scale_bound, 0.0, 0.0, 0.0, 0.0, -o.max_offset};
    const double upper[6] = {1.0 + o.scale_bound, 1e6, 1e6, 1e6, 1e6, o.max_offset};
    for (int p = 0; p < 6; ++p) {
      problem.SetParameterLowerBound(x, p, lower[p]);
      problem.SetParameterUpperBound(x, p, upper[p]);
    }
    // An offset and a direction-dependent Coulomb friction are one degree of freedom (without stiction, moving
    // samples see i₀ + F_c⁺/(N k_t s) and i₀ − F_c⁻/(N k_t s)): fit either.
    std::vector<int> fixed{o.fit_offset ? 2 : 5};
    if (tied) {
      fixed = {2, 4};
      if (!o.fit_offset) fixed.push_back(5);
    }
    problem.SetManifold(x, new ceres::SubsetManifold(6, fixed));
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = o.max_iterations;
    so.logging_type = ceres::SILENT;
    so.function_tolerance = 1e-12;
    so.parameter_tolerance = 1e-12;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (!summary.IsSolutionUsable())
      throw UnidentifiableError(log.source + ": joint " + joint +
                                ": Ceres found no usable solution: " + summary.message);
    JointCurrentFit f;
    f.points = pos + neg;
    f.tied = tied;
    f.rms = std::sqrt(2.0 * summary.final_cost / f.points);
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = 1;
    ceres::Covariance cov(co);
    const std::vector<std::pair<const double*, const double*>> blocks{{x, x}};
    if (!cov.Compute(blocks, &problem))
      throw UnidentifiableError(log.source + ": joint " + joint +
                                ": the torque-constant scale, friction and offset are not jointly identifiable from "
                                "this motion (rank-deficient Jacobian)");
    double C[36];
    cov.GetCovarianceBlock(x, x, C);
    const double s2 = 2.0 * summary.final_cost / static_cast<double>(f.points - (6 - static_cast<int>(fixed.size())));
    if (o.fit_offset || tied) x[2] = x[1];
    if (tied) x[4] = x[3];
    ParameterEstimate* out[6] = {&f.kt_scale,    &f.coulomb_pos, &f.coulomb_neg,
                                 &f.viscous_pos, &f.viscous_neg, &f.offset};
    const char* names[6] = {"kt_scale", "coulomb_pos", "coulomb_neg", "viscous_pos", "viscous_neg", "offset"};
    const double initial[6] = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (int p = 0; p < 6; ++p) {
      out[p]->value = x[p];
      out[p]->initial = initial[p];
      const int q = p == 2 && (o.fit_offset || tied) ? 1 : (p == 4 && tied ? 3 : p);  // a tied one: its twin's error
      out[p]->std_error = std::sqrt(std::max(0.0, C[7 * q] * s2));
      auto near = [&](double b) { return std::abs(x[p] - b) <= 1e-8 * std::max(1.0, std::abs(b)); };
      const bool is_fixed = std::find(fixed.begin(), fixed.end(), p) != fixed.end();
      if (!is_fixed && (near(lower[p]) || near(upper[p]))) f.at_bound.emplace_back(names[p]);
    }
    fit.joints.push_back(f);
  }
  return fit;
}

Eigen::MatrixXd predictCurrents(const multibody::Model& model, const std::vector<DriveNominal>& drives,
                                const CurrentLog& log, const CurrentFit& fit) {
  checkInputs(model, drives, log);
  if (static_cast<Eigen::Index>(fit.joints.size()) != model.nq)
    throw InputError(log.source + ": a fit of " + std::to_string(fit.joints.size()) + " joints for a robot of " +
                     std::to_string(model.nq));
  const Eigen::MatrixXd tau = jointTorques(model, drives, log);
  Eigen::MatrixXd i(tau.rows(), tau.cols());
  for (Eigen::Index j = 0; j < model.nq; ++j) {
    const JointCurrentFit& f = fit.joints[static_cast<size_t>(j)];
    const DriveNominal& d = drives[static_cast<size_t>(j)];
    const double x[6] = {f.kt_scale.value,    f.coulomb_pos.value, f.coulomb_neg.value,
                         f.viscous_pos.value, f.viscous_neg.value, f.offset.value};
    for (Eigen::Index k = 0; k < tau.rows(); ++k) {
      const double v = log.qd(k, j);
      const double tf = v > 0.0 ? x[1] + x[3] * v : (v < 0.0 ? -(x[2] + x[4] * (-v)) : 0.0);
      i(k, j) = (tau(k, j) + tf) / (d.ratio * d.kt * x[0]) + x[5];
    }
  }
  return i;
}

}  // namespace jointsim::identify
