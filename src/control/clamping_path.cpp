#include "jointsim/control/clamping_path.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/error.hpp"

namespace jointsim::control {

void ClampingPathParams::validate() const {
  if (!std::isfinite(q_pos)) throw InputError("clamping path: q_pos must be a finite angle in rad");
  if (!(qd_max > 0.0) || !std::isfinite(qd_max)) throw InputError("clamping path: qd_max must be > 0 rad/s");
  if (!(qdd_max > 0.0) || !std::isfinite(qdd_max)) throw InputError("clamping path: qdd_max must be > 0 rad/s²");
  if (!(segment_time > 0.0) || !std::isfinite(segment_time))
    throw InputError("clamping path: segment_time must be > 0 s");
  if (segments < 1) throw InputError("clamping path: segments must be >= 1");
}

ClampingPath::ClampingPath(const ClampingPathParams& params) : p_(params) {
  p_.validate();
  const Eigen::VectorXd vmax = Eigen::VectorXd::Constant(1, p_.qd_max), amax = Eigen::VectorXd::Constant(1, p_.qdd_max);
  for (int k = 0; k < p_.segments; ++k) {
    // 0 → +q, then alternately +q → −q and −q → +q.
    const double begin = k == 0 ? 0.0 : (k % 2 == 1 ? p_.q_pos : -p_.q_pos);
    const double end = k % 2 == 0 ? p_.q_pos : -p_.q_pos;
    segs_.emplace_back(Eigen::VectorXd::Constant(1, begin), Eigen::VectorXd::Constant(1, end), vmax, amax,
                       k * p_.segment_time);
    final_ = end;
  }
}

void ClampingPath::evaluate(double t, double& q, double& qd, double& qdd) const {
  if (t < 0.0) {
    q = qd = qdd = 0.0;
    return;
  }
  const auto k = static_cast<long>(std::floor(t / p_.segment_time));
  if (k >= p_.segments) {
    q = final_;
    qd = qdd = 0.0;
    return;
  }
  Eigen::Matrix<double, 1, 1> a, b, c;
  segs_[static_cast<size_t>(k)].evaluate(t, a, b, c);
  q = a[0];
  qd = b[0];
  qdd = c[0];
}

std::vector<double> ClampingPath::breakpoints() const {
  std::vector<double> t;
  for (int k = 0; k < p_.segments; ++k) {
    const double lo = k * p_.segment_time, hi = (k + 1) * p_.segment_time;
    if (k > 0) t.push_back(lo);
    for (double b : segs_[static_cast<size_t>(k)].breakpoints())
      if (b > lo && b < hi) t.push_back(b);
  }
  t.push_back(endTime());
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

}  // namespace jointsim::control
