// Ceres fit of the 1-D transmission model of [KR300Thesis] to a clamping curve (quasi-static response), standard
// errors, optional validation simulation with the joint rig. See clamping_fit.hpp.
#include "jointsim/identify/clamping_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include <ceres/ceres.h>

#include "jointsim/common/error.hpp"
#include "jointsim/common/interpolate.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "quiet_ceres.hpp"

namespace jointsim::identify {

namespace {

std::string fitNum(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// Torque residual of one cleaned point: τ_meas − [EB(φ − φ0, φ̇) + s F + k_v φ̇].
struct PointResidual {
  double x, tau, s, v;
  template <typename T>
  bool operator()(const T* c, const T* b, const T* F, const T* phi0, const T* kv, const T* d, T* residual) const {
    const T delta = T(x) - phi0[0];
    const T half = 0.5 * b[0];
    const T td = d[0] * v;
    T eb = T(0.0);
    if (delta > half) {  // positive contact: the damper never pulls and is limited to the spring torque
      const T tc = c[0] * (delta - half);
      eb = (tc + td <= T(0.0)) ? T(0.0) : tc + (tc < td ? tc : td);
    } else if (delta < -half) {
      const T tc = c[0] * (delta + half);
      eb = (tc + td >= T(0.0)) ? T(0.0) : tc + (tc > td ? tc : td);
    }
    residual[0] = T(tau) - (eb + s * F[0] + kv[0] * v);
    return true;
  }
};

/// RMS angle error of the dynamic 1-D model (joint rig, clamped, measured torque as input) [rad].
double validationAngleRms(const ClampingData& data, const ClampingFitResult& r, const ClampingFitOptions& o) {
  systems::JointRigSetup s;
  s.name = "clamping_validation";
  s.rotor_inertia = o.rotor_inertia;
  drive::ElastoBacklashParams eb;
  eb.stiffness = r.stiffness.value;
  eb.backlash = r.backlash.value;
  eb.damping = r.damping ? std::max(0.0, r.damping->value) : o.validation_damping;
  s.transmission = std::make_shared<drive::ElastoBacklash>(eb);
  drive::TableFrictionParams fp;
  const double kv = r.viscous ? std::max(0.0, r.viscous->value) : 0.0;
  fp.tau_pos = {{{0.0, std::max(0.0, r.friction.value)}}, {{1.0, std::max(0.0, r.friction.value) + kv}}};
  s.friction = std::make_shared<drive::TableFriction>(fp);
  s.clamped = true;
  s.input = systems::RigInput::MotorTorque;
  const Eigen::Index n = data.time.size();
  const double t0 = data.time[0];
  std::vector<double> times(static_cast<size_t>(n)), values(static_cast<size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) {
    times[static_cast<size_t>(k)] = data.time[k] - t0;
    values[static_cast<size_t>(k)] = data.torque[k];
  }
  s.profile = control::Profile::piecewise(times, values);
  s.q_m0 = data.angle[0] - r.center.value;
  s.duration = data.time[n - 1] - t0;
  s.log_rate = static_cast<double>(n - 1) / s.duration;
  systems::JointRig rig(s);
  const sim::SignalTable log = sim::simulateTable(rig, rig.simulateOptions());
  const Eigen::VectorXd ts = log["time"], qs = log["motor_angle"];
  double ss = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double q = interpolateLinear(
        static_cast<size_t>(ts.size()), [&](size_t i) { return ts[static_cast<Eigen::Index>(i)]; },
        [&](size_t i) { return qs[static_cast<Eigen::Index>(i)]; }, data.time[k] - t0, Ends::Hold);
    ss += std::pow(q + r.center.value - data.angle[k], 2);
  }
  return std::sqrt(ss / static_cast<double>(n));
}

}  // namespace

double elastoBacklashStatic(double x, double stiffness, double backlash) {
  const double half = 0.5 * backlash;
  if (x > half) return stiffness * (x - half);
  if (x < -half) return stiffness * (x + half);
  return 0.0;
}

void ClampingFitOptions::validate() const {
  curve.validate();
  auto bad = [](const std::string& field, double v, const std::string& rule) {
    throw InputError("clamping fit options: " + field + ": expected " + rule + ", got " + fitNum(v));
  };
  if (fixed_backlash && !(*fixed_backlash >= 0 && std::isfinite(*fixed_backlash)))
    bad("fixed_backlash", *fixed_backlash, "a finite backlash >= 0 rad");
  if (velocity_half_window < 1) bad("velocity_half_window", velocity_half_window, "an integer >= 1");
  if (max_iterations < 1) bad("max_iterations", max_iterations, "an integer >= 1");
  if (!(max_relative_std_error > 0)) bad("max_relative_std_error", max_relative_std_error, "a value > 0");
  if (!(rotor_inertia > 0 && std::isfinite(rotor_inertia))) bad("rotor_inertia", rotor_inertia, "a value > 0 kg*m^2");
  if (!(validation_damping >= 0)) bad("validation_damping", validation_damping, "a value >= 0 N*m*s/rad");
}

ClampingFitResult identifyClamping(const ClampingData& data, const ClampingFitOptions& o) {
  const QuietCeres quiet;
  o.validate();
  ClampingFitResult r;
  r.curves = preprocessClampingCurve(data, o.curve);
  const ClampingCurves& cv = r.curves;

  if (!cv.crosses_zero && !o.fixed_backlash)
    throw UnidentifiableError(
        "backlash: the clamping curve never crosses zero torque (the mid-line between the upper and lower curves "
        "keeps one sign), so the gap is never traversed and the backlash is unobservable (as for joint 2 of "
        "[KR300Thesis]); give the backlash (--fix-backlash B [rad]) to identify the stiffness and friction");

  // start values: Algorithm II estimates
  double c = cv.stiffness, b = cv.backlash, F = std::max(0.0, cv.friction), phi0 = cv.center, kv = 0.0, d = 0.0;
  if (o.fixed_backlash) {
    b = *o.fixed_backlash;
    if (!cv.crosses_zero) phi0 = cv.center - (data.torque.mean() >= 0 ? 0.5 : -0.5) * b;  // one-sided contact
  }
  r.stiffness.initial = cv.stiffness;
  r.backlash.initial = cv.backlash;
  r.friction.initial = cv.friction;
  r.center.initial = cv.center;

  // residuals on the cleaned points of the kept half-cycles
  ceres::Problem problem;
  const Eigen::Index n = data.time.size();
  const int hw = o.velocity_half_window;
  double v_ss = 0.0;
  for (const HalfCycle& h : cv.half_cycles) {
    if (h.rejected) continue;
    for (int k : h.kept) {
      const Eigen::Index a = std::max<Eigen::Index>(0, k - hw), e = std::min<Eigen::Index>(n - 1, k + hw);
      const double v = (data.angle[e] - data.angle[a]) / (data.time[e] - data.time[a]);
      v_ss += v * v;
      auto* cost = new ceres::AutoDiffCostFunction<PointResidual, 1, 1, 1, 1, 1, 1, 1>(
          new PointResidual{data.angle[k], data.torque[k], static_cast<double>(h.direction), v});
      problem.AddResidualBlock(cost, nullptr, &c, &b, &F, &phi0, &kv, &d);
      ++r.points;
    }
  }
  const double v_rms = std::sqrt(v_ss / std::max(1, r.points));
  problem.SetParameterLowerBound(&c, 0, 1e-12 * std::max(1.0, std::abs(c)));
  problem.SetParameterLowerBound(&b, 0, 0.0);
  problem.SetParameterLowerBound(&F, 0, 0.0);
  if (o.fixed_backlash) problem.SetParameterBlockConstant(&b);
  if (!o.fit_viscous) problem.SetParameterBlockConstant(&kv);
  if (!o.fit_damping) problem.SetParameterBlockConstant(&d);
  if (o.fit_damping) problem.SetParameterLowerBound(&d, 0, 0.0);

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable())
    throw UnidentifiableError("clamping fit: Ceres found no usable solution: " + summary.message);
  r.iterations = static_cast<int>(summary.iterations.size());
  r.solver_summary = summary.BriefReport();
  r.rms_residual = std::sqrt(2.0 * summary.final_cost / std::max(1, r.points));

  // standard errors: (JᵀJ)⁻¹ scaled by the residual variance SSR/(n − p)
  std::vector<std::pair<double*, std::string>> free{{&c, "stiffness"}, {&F, "friction"}, {&phi0, "center"}};
  if (!o.fixed_backlash) free.emplace_back(&b, "backlash");
  if (o.fit_viscous) free.emplace_back(&kv, "viscous friction");
  if (o.fit_damping) free.emplace_back(&d, "damping");
  const int p = static_cast<int>(free.size());
  if (r.points <= p)
    throw UnidentifiableError("clamping fit: " + std::to_string(r.points) + " points for " + std::to_string(p) +
                              " parameters");
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (const auto& f : free) blocks.emplace_back(f.first, f.first);
  if (!cov.Compute(blocks, &problem)) {
    std::string names;
    for (const auto& f : free) names += (names.empty() ? "" : ", ") + f.second;
    throw UnidentifiableError("clamping fit: the parameters (" + names +
                              ") are not jointly identifiable from these data (rank-deficient Jacobian)" +
                              (o.fit_viscous || o.fit_damping
                                   ? std::string("; viscous friction and damping need a varying velocity")
                                   : std::string()));
  }
  const double s2 = 2.0 * summary.final_cost / static_cast<double>(r.points - p);
  auto se = [&](const double* x) {
    double var = 0;
    cov.GetCovarianceBlock(x, x, &var);
    return std::sqrt(std::max(0.0, var * s2));
  };
  r.stiffness.value = c;
  r.stiffness.fitted = true;
  r.stiffness.std_error = se(&c);
  r.backlash.value = b;
  r.backlash.fitted = !o.fixed_backlash;
  r.backlash.std_error = o.fixed_backlash ? 0.0 : se(&b);
  r.friction.value = F;
  r.friction.fitted = true;
  r.friction.std_error = se(&F);
  r.center.value = phi0;
  r.center.fitted = true;
  r.center.std_error = se(&phi0);
  // optional velocity terms: unidentifiable when their torque uncertainty at the typical speed exceeds a
  // fraction of the friction (the velocity is nearly constant between the turning regions by design)
  auto optional = [&](double value, const double* x, const std::string& name) {
    FittedParameter fpar;
    fpar.value = value;
    fpar.fitted = true;
    fpar.std_error = se(x);
    const double effect = fpar.std_error * v_rms, limit = o.max_relative_std_error * std::max(F, 1e-12);
    if (!(effect <= limit))
      throw UnidentifiableError(name + ": standard error " + fitNum(fpar.std_error) + " N*m*s/rad, i.e. " +
                                fitNum(effect) + " N*m at the RMS speed " + fitNum(v_rms) + " rad/s, more than " +
                                fitNum(o.max_relative_std_error) + " x the friction " + fitNum(F) +
                                " N*m: the speed hardly varies along the branches, so it is confounded with the "
                                "Coulomb friction");
    return fpar;
  };
  if (o.fit_viscous) r.viscous = optional(kv, &kv, "viscous friction");
  if (o.fit_damping) r.damping = optional(d, &d, "damping");

  if (o.simulate_validation) r.validation_angle_rms = validationAngleRms(data, r, o);
  return r;
}

std::string clampingReportYaml(const ClampingFitResult& r, const std::string& data_path, double gear_ratio) {
  std::ostringstream y;
  const ClampingCurves& cv = r.curves;
  auto par = [&](const char* name, const FittedParameter& p, const char* unit) {
    y << "  " << name << ": {value: " << fitNum(p.value) << ", unit: \"" << unit
      << "\", std_error: " << fitNum(p.std_error) << ", fitted: " << (p.fitted ? "true" : "false") << "}\n";
  };
  auto quoted = [](const std::string& s) {
    std::string out = "\"";
    for (char ch : s) {
      if (ch == '"' || ch == '\\') out += '\\';
      out += ch;
    }
    return out + "\"";
  };
  y << "# jointsim identify clamping: [KR300Thesis, Algorithm II] preprocessing + Ceres fit of the 1-D transmission\n"
    << "# model (quasi-static branch response tau = EB_static(phi - center; c, b) + sgn(phi_dot) F). Motor side.\n";
  y << "data: " << quoted(data_path) << "\n";
  y << "side: motor\n";
  y << "gear_ratio: " << fitNum(gear_ratio) << "   # torque column divided by this\n";
  y << "parameters:\n";
  par("stiffness", r.stiffness, "N*m/rad");
  par("backlash", r.backlash, "rad");
  par("friction", r.friction, "N*m");
  if (r.viscous) par("viscous_friction", *r.viscous, "N*m*s/rad");
  if (r.damping) par("damping", *r.damping, "N*m*s/rad");
  par("center", r.center, "rad");
  y << "algorithm_ii:\n";
  y << "  stiffness: {value: " << fitNum(cv.stiffness) << ", unit: \"N*m/rad\"}\n";
  y << "  backlash: {value: " << fitNum(cv.backlash) << ", unit: \"rad\"}   # 2 x fold kink position\n";
  y << "  fold_flat_length: {value: " << fitNum(cv.fold_flat)
    << ", unit: \"rad\"}   # half the backlash ([KR300Thesis, Algorithm II step 11])\n";
  y << "  backlash_interval_upper: {value: " << fitNum(cv.backlash_upper) << ", unit: \"rad\"}\n";
  y << "  backlash_interval_lower: {value: " << fitNum(cv.backlash_lower) << ", unit: \"rad\"}\n";
  y << "  friction: {value: " << fitNum(cv.friction) << ", unit: \"N*m\"}\n";
  y << "  center: {value: " << fitNum(cv.center) << ", unit: \"rad\"}\n";
  y << "  crosses_zero_torque: " << (cv.crosses_zero ? "true" : "false") << "\n";
  y << "fit:\n";
  y << "  rms_residual: {value: " << fitNum(r.rms_residual) << ", unit: \"N*m\"}\n";
  y << "  points: " << r.points << "\n";
  y << "  iterations: " << r.iterations << "\n";
  if (r.validation_angle_rms)
    y << "  validation_angle_rms: {value: " << fitNum(*r.validation_angle_rms) << ", unit: \"rad\"}\n";
  y << "half_cycles:\n";
  y << "  found: " << cv.half_cycles.size() << "\n";
  y << "  used_upper: " << cv.used_upper << "\n";
  y << "  used_lower: " << cv.used_lower << "\n";
  y << "  rejected: " << cv.rejected << "\n";
  y << "  rejected_reasons:";
  bool any = false;
  for (size_t i = 0; i < cv.half_cycles.size(); ++i)
    if (cv.half_cycles[i].rejected) {
      y << "\n    - " << quoted("half-cycle " + std::to_string(i + 1) + ": " + cv.half_cycles[i].reason);
      any = true;
    }
  y << (any ? "\n" : " []\n");
  return y.str();
}

drive::ParameterChanges clampingChanges(const ClampingFitResult& fit, const drive::Transmission& gear) {
  const std::vector<drive::ParameterInfo> table = gear.parameters();
  const drive::ParameterInfo* stiffness = nullptr;
  const drive::ParameterInfo* backlash = nullptr;
  const drive::ParameterInfo* damping = nullptr;
  int stiffnesses = 0;
  for (const auto& p : table) {
    if (p.role == drive::ParameterRole::Stiffness) {
      stiffness = &p;
      ++stiffnesses;
    }
    if (p.role == drive::ParameterRole::Backlash) backlash = &p;
    if (p.key == "damping") damping = &p;
  }
  const std::string side = gear.complianceSide();
  if (stiffnesses != 1 || backlash == nullptr || side.empty())
    throw InputError("identified clamping curve: a " + gear.type() +
                     " transmission does not take it (it identifies one spring with backlash on the motor side: an "
                     "elastic or elasto_backlash gear)");
  const double N = gear.ratio();
  const bool output = side == "output";
  drive::ParameterChanges out{{stiffness->key, output ? N * N * fit.stiffness.value : fit.stiffness.value},
                              {backlash->key, output ? fit.backlash.value / N : fit.backlash.value}};
  if (fit.damping && damping != nullptr)
    out.push_back({damping->key, output ? N * N * fit.damping->value : fit.damping->value});
  return out;
}

}  // namespace jointsim::identify
