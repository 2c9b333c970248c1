#include "jointsim/drive/transmissions.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/LU>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::drive {
namespace {
void transmissionPositive(double v, const std::string& name, const char* unit) {
  check::positive("transmission", name, v, unit);
}
void transmissionNonNegative(double v, const std::string& name, const char* unit) {
  check::nonNegative("transmission", name, v, unit);
}

// Deflection and its rate on the compliance side, and the map from the side torque to the ports.
struct SideKinematics {
  double delta, delta_dot;
};
inline SideKinematics deflection(const ShaftPorts& p, double N, ComplianceSide side) {
  if (side == ComplianceSide::Motor) return {p.q_in - N * p.q_out, p.qd_in - N * p.qd_out};
  return {p.q_in / N - p.q_out, p.qd_in / N - p.qd_out};
}
inline PortTorques portTorques(double tau_side, double N, ComplianceSide side) {
  if (side == ComplianceSide::Motor) return {tau_side, N * tau_side};
  return {tau_side / N, tau_side};
}
}  // namespace

RigidGear::RigidGear(double ratio) : N_(ratio) { transmissionPositive(ratio, "ratio", "(-)"); }

void ElasticGearParams::validate() const {
  transmissionPositive(ratio, "ratio", "(-)");
  transmissionPositive(stiffness, "stiffness", "N·m/rad");
  transmissionNonNegative(damping, "damping", "N·m·s/rad");
}

ElasticGear::ElasticGear(const ElasticGearParams& params) : p_(params) { p_.validate(); }

PortTorques ElasticGear::evaluate(const ShaftPorts& ports, const double*, double*) const {
  const SideKinematics k = deflection(ports, p_.ratio, p_.side);
  return portTorques(p_.stiffness * k.delta + p_.damping * k.delta_dot, p_.ratio, p_.side);
}

double ElasticGear::storedEnergy(const ShaftPorts& ports, const double*) const {
  const double d = deflection(ports, p_.ratio, p_.side).delta;
  return 0.5 * p_.stiffness * d * d;
}

void ElastoBacklashParams::validate() const {
  transmissionPositive(ratio, "ratio", "(-)");
  transmissionPositive(stiffness, "stiffness", "N·m/rad");
  transmissionNonNegative(damping, "damping", "N·m·s/rad");
  transmissionNonNegative(backlash, "backlash", "rad");
}

ElastoBacklash::ElastoBacklash(const ElastoBacklashParams& params) : p_(params) { p_.validate(); }

double ElastoBacklash::contactTorque(double delta, double delta_dot) const {
  const double c = p_.stiffness, b = p_.backlash;
  const double tau_d = p_.damping * delta_dot;
  if (b <= 1e-10) return c * delta + tau_d;
  const double half = 0.5 * b;
  if (delta > half) {
    const double tau_c = c * (delta - half);
    return tau_c + tau_d <= 0.0 ? 0.0 : tau_c + std::min(tau_c, tau_d);
  }
  if (delta < -half) {
    const double tau_c = c * (delta + half);
    return tau_c + tau_d >= 0.0 ? 0.0 : tau_c + std::max(tau_c, tau_d);
  }
  return 0.0;  // inside the gap
}

PortTorques ElastoBacklash::evaluate(const ShaftPorts& ports, const double*, double*) const {
  const SideKinematics k = deflection(ports, p_.ratio, p_.side);
  return portTorques(contactTorque(k.delta, k.delta_dot), p_.ratio, p_.side);
}

double ElastoBacklash::storedEnergy(const ShaftPorts& ports, const double*) const {
  const double d = deflection(ports, p_.ratio, p_.side).delta;
  const double s = std::max(0.0, std::abs(d) - 0.5 * p_.backlash);
  return 0.5 * p_.stiffness * s * s;
}

CouplingMatrix::CouplingMatrix(const Eigen::MatrixXd& G) : G_(G) {
  if (G.rows() != G.cols() || G.rows() == 0)
    throw InputError("coupling matrix: expected a non-empty square matrix, got " + std::to_string(G.rows()) + "x" +
                     std::to_string(G.cols()));
  if (!G.allFinite()) throw InputError("coupling matrix: entries must be finite");
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(G);
  if (!lu.isInvertible())
    throw InputError("coupling matrix: must be invertible (each motor drives the joints independently)");
  Ginv_ = lu.inverse();
}

Eigen::VectorXd CouplingMatrix::jointTorques(const Eigen::VectorXd& tau_motor) const {
  return Ginv_.transpose() * tau_motor;
}

Eigen::MatrixXd CouplingMatrix::reflectedInertia(const Eigen::VectorXd& motor_inertias) const {
  return Ginv_.transpose() * motor_inertias.asDiagonal() * Ginv_;
}

Eigen::Matrix3d CouplingMatrix::irb140Wrist() {
  // [Olsson2017, §2.2, eqs. 2.1–2.2, §3.12, A.13, Listing 4.1]; exact rational G derived from Listing 4.1
  // (spaces inside numbers of the extraction removed).
  const double a = 6649.0 / 110.0, b = 207675.0 / 3190.0, c = 486720.0 / 7975.0;
  Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
  G(0, 0) = 110.0 / 6649.0;
  G(1, 0) = 71.0 / (22.0 * a * b);
  G(1, 1) = 3190.0 / 207675.0;
  G(2, 0) = (71.0 * 243360.0 * 22.0 + b * 64.0 * 22.0 * 4147.0) / (22.0 * 4147.0 * 22.0 * a * b * c);
  G(2, 1) = 243360.0 / (4147.0 * b * c);
  G(2, 2) = 7975.0 / 486720.0;
  return G;
}

}  // namespace jointsim::drive

// ------------------------------------------------------------------------------------------ parameter tables

namespace jointsim::drive {
namespace {
const char* sideText(ComplianceSide side) { return side == ComplianceSide::Motor ? "motor side" : "output side"; }
ParameterRef ratioRef(double* ratio) {
  return {{"ratio", "1", 0.0, ParameterRange::positive(), ParameterRole::None, "reduction ratio N = q_in/q_out"},
          ratio};
}
// The spring–damper (and backlash) rows shared by the elastic and the elasto-backlash gear.
std::vector<ParameterRef> complianceRefs(double* ratio, double* stiffness, double* damping, double* backlash,
                                         ComplianceSide side) {
  const std::string s = sideText(side);
  return {ratioRef(ratio),
          {{"stiffness", "N·m/rad", 0.0, ParameterRange::positive(), ParameterRole::Stiffness,
            "gear stiffness c (" + s + ")"},
           stiffness},
          {{"damping", "N·m·s/rad", 0.0, ParameterRange::nonNegative(), ParameterRole::None,
            "gear damping d (" + s + ")"},
           damping},
          {{"backlash", "rad", 0.0, ParameterRange::nonNegative(), ParameterRole::Backlash,
            "total backlash b (" + s + "), gap ±b/2"},
           backlash}};
}
}  // namespace

std::vector<ParameterInfo> RigidGear::parameters() const {
  double n = N_;
  return describeParameters({ratioRef(&n)});
}

std::shared_ptr<const Transmission> RigidGear::withParameters(const ParameterChanges& changes) const {
  double n = N_;
  assignParameters({ratioRef(&n)}, changes, "transmission");
  return std::make_shared<RigidGear>(n);
}

std::vector<ParameterInfo> ElasticGear::parameters() const {
  ElasticGearParams p = p_;
  double backlash = 0.0;  // none: a change to > 0 makes an elasto-backlash gear (withParameters)
  return describeParameters(complianceRefs(&p.ratio, &p.stiffness, &p.damping, &backlash, p.side));
}

std::shared_ptr<const Transmission> ElasticGear::withParameters(const ParameterChanges& changes) const {
  ElasticGearParams p = p_;
  double backlash = 0.0;
  assignParameters(complianceRefs(&p.ratio, &p.stiffness, &p.damping, &backlash, p.side), changes, "transmission");
  if (backlash == 0.0) return std::make_shared<ElasticGear>(p);
  // ElastoBacklash with b > 0 and the same spring–damper: no states either, the same ratio; continuous at b → 0.
  ElastoBacklashParams q;
  q.ratio = p.ratio;
  q.stiffness = p.stiffness;
  q.damping = p.damping;
  q.side = p.side;
  q.backlash = backlash;
  return std::make_shared<ElastoBacklash>(q);
}

std::vector<ParameterInfo> ElastoBacklash::parameters() const {
  ElastoBacklashParams p = p_;
  return describeParameters(complianceRefs(&p.ratio, &p.stiffness, &p.damping, &p.backlash, p.side));
}

std::shared_ptr<const Transmission> ElastoBacklash::withParameters(const ParameterChanges& changes) const {
  ElastoBacklashParams p = p_;
  assignParameters(complianceRefs(&p.ratio, &p.stiffness, &p.damping, &p.backlash, p.side), changes, "transmission");
  return std::make_shared<ElastoBacklash>(p);
}

}  // namespace jointsim::drive
