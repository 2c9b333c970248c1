#include "jointsim/control/clamping_path.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::control {

void ClampingPathParams::validate() const {
  check::finite("clamping path", "q_pos", q_pos, "rad");
  check::positive("clamping path", "qd_max", qd_max, "rad/s");
  check::positive("clamping path", "qdd_max", qdd_max, "rad/s²");
  check::positive("clamping path", "segment_time", segment_time, "s");
  check::atLeast("clamping path", "segments", segments, 1, "");
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
