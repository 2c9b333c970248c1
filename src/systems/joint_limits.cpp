#include "jointsim/systems/joint_limits.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::systems {

const char* jointLimitModeName(JointLimitMode mode) {
  switch (mode) {
    case JointLimitMode::Ignore: return "ignore";
    case JointLimitMode::Warn: return "warn";
    case JointLimitMode::Stop: return "stop";
  }
  return "?";
}

void JointLimitSettings::validate() const {
  check::positive("joint_limits", "stiffness", stiffness, "N·m/rad");
  check::nonNegative("joint_limits", "damping", damping, "N·m·s/rad");
}

// ------------------------------------------------------------------------------------------------ end stops

EndStops::EndStops(const multibody::Model& model, const JointLimitSettings& settings) {
  settings.validate();
  if (settings.mode != JointLimitMode::Stop) return;
  k_ = settings.stiffness;
  d_ = settings.damping;
  for (int i = 0; i < model.nq; ++i) {
    const auto& L = model.limits[static_cast<size_t>(i)];
    if (!std::isfinite(L.lower) && !std::isfinite(L.upper)) continue;
    joints_.push_back(i);
    lower_.push_back(L.lower);
    upper_.push_back(L.upper);
  }
}

void EndStops::roots(const Eigen::Ref<const Eigen::VectorXd>& q, double* g) const {
  for (size_t s = 0; s < joints_.size(); ++s) {
    const double qi = q[joints_[s]];
    g[2 * s] = std::isfinite(upper_[s]) ? qi - upper_[s] : -1.0;
    g[2 * s + 1] = std::isfinite(lower_[s]) ? lower_[s] - qi : -1.0;
  }
}

void EndStops::torques(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                       Eigen::Ref<Eigen::VectorXd> tau) const {
  tau.setZero();
  for (size_t s = 0; s < joints_.size(); ++s) {
    const int i = joints_[s];
    // Penetration δ and its rate at the upper (δ = q − q_u) and lower (δ = q_l − q) stop.
    if (const double delta = q[i] - upper_[s]; delta > 0.0)
      tau[i] = -std::max(0.0, k_ * delta + d_ * qd[i]);
    else if (const double delta_l = lower_[s] - q[i]; delta_l > 0.0)
      tau[i] = std::max(0.0, k_ * delta_l - d_ * qd[i]);
  }
}

double EndStops::energy(const Eigen::Ref<const Eigen::VectorXd>& q) const {
  double E = 0.0;
  for (size_t s = 0; s < joints_.size(); ++s) {
    const double qi = q[joints_[s]];
    const double delta = std::max({0.0, qi - upper_[s], lower_[s] - qi});
    E += 0.5 * k_ * delta * delta;
  }
  return E;
}

// ------------------------------------------------------------------------------------------------ monitor

JointLimitMonitor::JointLimitMonitor(const multibody::Model& model, std::vector<int> columns,
                                     JointLimitSettings settings)
    : settings_(settings) {
  settings_.validate();
  if (columns.size() != static_cast<size_t>(model.nq))
    throw InputError("JointLimitMonitor: " + std::to_string(columns.size()) + " columns for " +
                     std::to_string(model.nq) + " joints");
  for (int i = 0; i < model.nq; ++i) {
    const auto& L = model.limits[static_cast<size_t>(i)];
    if (columns[static_cast<size_t>(i)] < 0 || (!std::isfinite(L.lower) && !std::isfinite(L.upper))) continue;
    columns_.push_back(columns[static_cast<size_t>(i)]);
    names_.push_back(model.joint_names[static_cast<size_t>(i)]);
    units_.push_back(model.joint_types[static_cast<size_t>(i)] == multibody::JointType::Revolute ? "rad" : "m");
    limits_.push_back(L);
  }
  state_.resize(columns_.size());
  seen_.assign(columns_.size(), 0);
}

void JointLimitMonitor::observe(const Eigen::VectorXd& row) {
  if (!enabled()) return;
  const double t = row[0];
  for (size_t j = 0; j < columns_.size(); ++j) {
    const double q = row[columns_[j]];
    const double excursion = std::max(q - limits_[j].upper, limits_[j].lower - q);
    if (!(excursion > 0.0)) continue;
    JointLimitViolation& v = state_[j];
    if (!seen_[j]) {
      seen_[j] = 1;
      v.joint = names_[j];
      v.lower = limits_[j].lower;
      v.upper = limits_[j].upper;
      v.first_time = t;
    }
    if (excursion > v.max_excursion) {
      v.max_excursion = excursion;
      v.max_time = t;
      v.max_position = q;
    }
  }
}

void JointLimitMonitor::reset() {
  state_.assign(columns_.size(), JointLimitViolation{});
  seen_.assign(columns_.size(), 0);
}

std::vector<JointLimitViolation> JointLimitMonitor::violations() const {
  std::vector<JointLimitViolation> out;
  for (size_t j = 0; j < state_.size(); ++j)
    if (seen_[j]) out.push_back(state_[j]);
  return out;
}

std::vector<std::string> JointLimitMonitor::describe() const {
  std::vector<std::string> out;
  for (size_t j = 0; j < state_.size(); ++j) {
    if (!seen_[j]) continue;
    const JointLimitViolation& v = state_[j];
    const std::string& u = units_[j];
    out.push_back("joint " + v.joint + " left its range [" + formatNumber(v.lower, 5) + ", " +
                  formatNumber(v.upper, 5) + "] " + u + " at t = " + formatNumber(v.first_time, 6) + " s, by up to " +
                  formatNumber(v.max_excursion, 4) + " " + u + " (q = " + formatNumber(v.max_position, 5) + " " + u +
                  " at t = " + formatNumber(v.max_time, 6) + " s)");
  }
  return out;
}

}  // namespace jointsim::systems
