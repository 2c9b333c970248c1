// MSL Modelica.Blocks.Sources.KinematicPTP2, transcribed expression by expression (same operation order
// as the Modelica source, so results match Dymola's to rounding). See kinematic_ptp.hpp.
#include "jointsim/control/kinematic_ptp.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "jointsim/common/error.hpp"

namespace jointsim::control {
namespace {

Eigen::VectorXd broadcast(const Eigen::VectorXd& v, Eigen::Index n, const char* name) {
  if (v.size() == n) return v;
  if (v.size() == 1) return Eigen::VectorXd::Constant(n, v[0]);
  throw InputError(std::string("kinematic_ptp: ") + name + " has " + std::to_string(v.size()) + " entries, expected " +
                   std::to_string(n) + " (or 1)");
}

}  // namespace

KinematicPtpTrajectory::KinematicPtpTrajectory(const Eigen::VectorXd& q_begin, const Eigen::VectorXd& q_end,
                                               const Eigen::VectorXd& qd_max, const Eigen::VectorXd& qdd_max,
                                               double start_time)
    : t0_(start_time) {
  const Eigen::Index n = std::max({q_begin.size(), q_end.size(), qd_max.size(), qdd_max.size()});
  if (q_begin.size() < 1 || q_end.size() < 1 || qd_max.size() < 1 || qdd_max.size() < 1)
    throw InputError("kinematic_ptp: q_begin, q_end, qd_max and qdd_max need at least one entry each");
  qb_ = broadcast(q_begin, n, "q_begin");
  qe_ = broadcast(q_end, n, "q_end");
  qd_max_ = broadcast(qd_max, n, "qd_max");
  qdd_max_ = broadcast(qdd_max, n, "qdd_max");
  if (!qb_.allFinite() || !qe_.allFinite()) throw InputError("kinematic_ptp: q_begin and q_end must be finite");
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(qd_max_[i] > 0.0 && std::isfinite(qd_max_[i])))
      throw InputError("kinematic_ptp: qd_max of axis " + std::to_string(i + 1) + " must be > 0 rad/s");
    if (!(qdd_max_[i] > 0.0 && std::isfinite(qdd_max_[i])))
      throw InputError("kinematic_ptp: qdd_max of axis " + std::to_string(i + 1) + " must be > 0 rad/s^2");
  }
  if (!(start_time >= 0.0 && std::isfinite(start_time))) throw InputError("kinematic_ptp: start_time must be >= 0 s");

  dq_ = qe_ - qb_;  // p_deltaq = p_q_end - p_q_begin
  // aux1[i] = p_deltaq[i]/p_qd_max[i]; aux2[i] = p_deltaq[i]/p_qdd_max[i]; max(abs(.))
  for (Eigen::Index i = 0; i < n; ++i) {
    const double a1 = std::abs(dq_[i] / qd_max_[i]);
    const double a2 = std::abs(dq_[i] / qdd_max_[i]);
    if (a1 > sd_max_inv_) {
      sd_max_inv_ = a1;
      speed_axis_ = static_cast<int>(i);
    }
    if (a2 > sdd_max_inv_) {
      sdd_max_inv_ = a2;
      accel_axis_ = static_cast<int>(i);
    }
  }

  degenerate_ = sd_max_inv_ <= kEps || sdd_max_inv_ <= kEps;
  if (degenerate_) return;  // everything 0, endTime = Tes = 0

  sd_max_ = 1 / sd_max_inv_;
  sdd_max_ = 1 / sdd_max_inv_;
  Ta1_ = std::sqrt(1 / sdd_max_);
  Ta2_ = sd_max_ / sdd_max_;
  no_w_phase_ = Ta2_ >= Ta1_;
  Tv_ = no_w_phase_ ? Ta1_ : 1 / sd_max_;
  Te_ = no_w_phase_ ? Ta1_ + Ta1_ : Tv_ + Ta2_;
  Ta1s_ = Ta1_ + t0_;
  Ta2s_ = Ta2_ + t0_;
  Tvs_ = Tv_ + t0_;
  Tes_ = Te_ + t0_;
  sd_max2_ = sdd_max_ * Ta1_;
  s1_ = sdd_max_ * (no_w_phase_ ? Ta1_ * Ta1_ : Ta2_ * Ta2_) / 2;
  s2_ = s1_ + (no_w_phase_ ? sd_max2_ * (Te_ - Ta1_) - (sdd_max_ / 2) * ((Te_ - Ta1_) * (Te_ - Ta1_))
                           : sd_max_ * (Tv_ - Ta2_));
  s3_ = s2_ + sd_max_ * (Te_ - Tv_) - (sdd_max_ / 2) * (Te_ - Tv_) * (Te_ - Tv_);
  end_time_ = Tes_;
}

void KinematicPtpTrajectory::evaluatePath(double t, double& s, double& sd, double& sdd) const {
  // sd = der(s), sdd = der(sd): the symbolic derivatives of each branch.
  if (degenerate_ || t < t0_) {
    s = sd = sdd = 0.0;
  } else if (no_w_phase_) {
    if (t < Ta1s_) {
      s = (sdd_max_ / 2) * (t - t0_) * (t - t0_);
      sd = sdd_max_ * (t - t0_);
      sdd = sdd_max_;
    } else if (t < Tes_) {
      s = s1_ + sd_max2_ * (t - Ta1s_) - (sdd_max_ / 2) * (t - Ta1s_) * (t - Ta1s_);
      sd = sd_max2_ - sdd_max_ * (t - Ta1s_);
      sdd = -sdd_max_;
    } else {
      s = s2_;
      sd = sdd = 0.0;
    }
  } else if (t < Ta2s_) {
    s = (sdd_max_ / 2) * (t - t0_) * (t - t0_);
    sd = sdd_max_ * (t - t0_);
    sdd = sdd_max_;
  } else if (t < Tvs_) {
    s = s1_ + sd_max_ * (t - Ta2s_);
    sd = sd_max_;
    sdd = 0.0;
  } else if (t < Tes_) {
    s = s2_ + sd_max_ * (t - Tvs_) - (sdd_max_ / 2) * (t - Tvs_) * (t - Tvs_);
    sd = sd_max_ - sdd_max_ * (t - Tvs_);
    sdd = -sdd_max_;
  } else {
    s = s3_;
    sd = sdd = 0.0;
  }
}

void KinematicPtpTrajectory::evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                      Eigen::Ref<Eigen::VectorXd> qdd) const {
  double s = 0, sd = 0, sdd = 0;
  evaluatePath(t, s, sd, sdd);
  for (Eigen::Index i = 0; i < qb_.size(); ++i) {
    qdd[i] = dq_[i] * sdd;
    qd[i] = dq_[i] * sd;
    q[i] = qb_[i] + dq_[i] * s;
  }
}

bool KinematicPtpTrajectory::moving(int i, double t) const {
  const auto k = static_cast<Eigen::Index>(i);
  if (k < 0 || k >= qb_.size())
    throw InputError("kinematic_ptp: moving(): axis " + std::to_string(i) + " out of range");
  return std::abs(qb_[k] - qe_[k]) > kEps && t < end_time_;
}

std::vector<double> KinematicPtpTrajectory::breakpoints() const {
  std::vector<double> out;
  if (degenerate_) return out;
  const double candidates[] = {t0_, no_w_phase_ ? Ta1s_ : Ta2s_, Tvs_, Tes_};
  for (double b : candidates)
    if (b > 0.0 && b <= end_time_ && (out.empty() || b > out.back())) out.push_back(b);
  return out;
}

std::string KinematicPtpTrajectory::describe() const {
  std::ostringstream os;
  os << "kinematic_ptp(" << dof() << " joints, "
     << (degenerate_ ? "no motion" : (no_w_phase_ ? "triangular" : "trapezoidal")) << ", start " << t0_ << " s, end "
     << end_time_ << " s)";
  return os.str();
}

}  // namespace jointsim::control
