#include "jointsim/drive/friction_models.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/drive/msl_friction.hpp"

namespace jointsim::drive {
namespace {

// Parameter errors (common/check.hpp) carry the field spelled like the YAML key as their key path, so that
// frictionFromYaml can point at the key's line.
[[noreturn]] void badParameter(const char* model, const std::string& field, const std::string& rule, double value) {
  check::fail(model, field, rule, value);
}
void frictionPositive(const char* model, const std::string& field, double v, const char* unit) {
  check::positive(model, field, v, unit);
}
void frictionNonNegative(const char* model, const std::string& field, double v, const char* unit) {
  check::nonNegative(model, field, v, unit);
}

inline double sgn(double v) { return static_cast<double>((v > 0.0) - (v < 0.0)); }

// Checks one per-direction set; `lugre` additionally requires α0 > 0 so that g(v) >= α0 > 0.
void validateBranch(const char* model, const std::string& side, const StribeckBranch& b, bool lugre) {
  if (lugre)
    frictionPositive(model, side + ".alpha0", b.alpha0, "N·m (g(v) >= alpha0 must stay > 0)");
  else
    frictionNonNegative(model, side + ".alpha0", b.alpha0, "N·m");
  frictionNonNegative(model, side + ".alpha1", b.alpha1, "N·m (Stribeck: g decreases from alpha0 + alpha1)");
  frictionNonNegative(model, side + ".alpha2", b.alpha2, "N·m·s/rad");
  frictionPositive(model, side + ".v_s", b.v_s, "rad/s");
}

}  // namespace

// ------------------------------------------------------------------------------ Coulomb + viscous

void CoulombViscousParams::validate() const {
  frictionNonNegative("coulomb_viscous", "f_c", f_c, "N·m");
  frictionNonNegative("coulomb_viscous", "f_v", f_v, "N·m·s/rad");
  frictionPositive("coulomb_viscous", "v_reg", v_reg, "rad/s");
}

CoulombViscousFriction::CoulombViscousFriction(const CoulombViscousParams& params) : p_(params) { p_.validate(); }

double CoulombViscousFriction::evaluate(const FrictionInput& in, const double*, double*) const {
  return steadyState(in.v);
}

double CoulombViscousFriction::steadyState(double v) const {
  // [Hauschild2003, eq. 4.2], F = F_v v + F_C sgn(v), with sgn(v) ≈ tanh(v / v_reg) (our choice).
  return p_.f_c * std::tanh(v / p_.v_reg) + p_.f_v * v;
}

// ------------------------------------------------------------------------------ table friction

void TableFrictionParams::validate() const {
  const char* m = "table";
  if (tau_pos.empty()) badParameter(m, "tau_pos", "at least one row [w, tau]", 0.0);
  for (size_t i = 0; i < tau_pos.size(); ++i) {
    const std::string row = "tau_pos[" + std::to_string(i) + "]";
    frictionNonNegative(m, row, tau_pos[i][0], "rad/s as the velocity w (column 1)");
    frictionNonNegative(m, row, tau_pos[i][1], "N·m as the friction torque (column 2)");
    if (i > 0 && !(tau_pos[i][0] > tau_pos[i - 1][0]))
      badParameter(m, row, "velocities strictly increasing, w > " + formatNumber(tau_pos[i - 1][0]) + " rad/s",
                   tau_pos[i][0]);
  }
  if (tau_pos.size() >= 2) {
    const auto& a = tau_pos[0];
    const auto& b = tau_pos[1];
    const double tau0 = a[1] - a[0] * (b[1] - a[1]) / (b[0] - a[0]);  // extrapolation to w = 0
    if (!(tau0 >= 0.0)) badParameter(m, "tau_pos", "a table whose value extrapolated to w = 0 is >= 0 N·m", tau0);
    const auto& y = tau_pos[tau_pos.size() - 2];
    const auto& z = tau_pos.back();
    const double slope = (z[1] - y[1]) / (z[0] - y[0]);
    if (!(slope >= 0.0))
      badParameter(m, "tau_pos", "a last slope >= 0 N·m·s/rad (extrapolated friction must stay >= 0)", slope);
  }
  if (!(peak >= 1.0) || !std::isfinite(peak)) badParameter(m, "peak", "a finite value >= 1 (-)", peak);
  frictionPositive(m, "v_stick", v_stick, "rad/s");
  frictionNonNegative(m, "d_stick", d_stick, "N·m·s/rad (0 = automatic)");
}

TableFriction::TableFriction(const TableFrictionParams& params) : p_(params) {
  p_.validate();
  tau0_ = tableTorque(0.0);
  d_stick_ = p_.d_stick > 0.0 ? p_.d_stick : p_.peak * tau0_ / p_.v_stick;
}

double TableFriction::tableTorque(double w) const {
  return frictionTableValue(p_.tau_pos, w);  // [MSL, Rotational.Components.BearingFriction]: extrapolated table
}

double TableFriction::evaluate(const FrictionInput& in, const double*, double*) const {
  const double v = in.v;
  const double stiction = p_.peak * tau0_;
  if (std::abs(v) < p_.v_stick) {
    // Karnopp band ([Hauschild2003, §4.3.1], [Karnopp1985]): stuck while |τ_d| <= peak·τ0
    // ([Olsson2017, eq. 3.1]); the sticking damping makes J v̇ = −d_stick v so the shaft comes to rest.
    if (std::abs(in.driving_torque) <= stiction)
      return std::clamp(in.driving_torque + d_stick_ * v, -stiction, stiction);
    // Break-away (MSL startForward/startBackward): the friction drops to the table value.
    return sgn(in.driving_torque) * tableTorque(std::abs(v));
  }
  return sgn(v) * tableTorque(std::abs(v));  // sliding, [Olsson2017, eq. 3.1]: τ = k ω ± m
}

double TableFriction::steadyState(double v) const { return sgn(v) * tableTorque(std::abs(v)); }

// ------------------------------------------------------------------------------ Stribeck

void StribeckParams::validate() const {
  validateBranch("stribeck", "positive", positive, false);
  validateBranch("stribeck", "negative", negative, false);
  frictionPositive("stribeck", "delta", delta, "(-)");
  frictionPositive("stribeck", "k_s", k_s, "s/rad");
}

StribeckFriction::StribeckFriction(const StribeckParams& params) : p_(params) { p_.validate(); }

double StribeckFriction::evaluate(const FrictionInput& in, const double*, double*) const { return steadyState(in.v); }

double StribeckFriction::steadyState(double v) const {
  const StribeckBranch& b = v >= 0.0 ? p_.positive : p_.negative;
  const double a = std::abs(v);
  // [Hauschild2003, eq. 4.6] with |v| in the exponent (our correction), times the slope limiter
  // 1 − e^{−k_S|v|} of [Hauschild2003, eq. 4.24].
  const double branch = (b.alpha0 + b.alpha1 * std::exp(-std::pow(a / b.v_s, p_.delta))) * sgn(v) + b.alpha2 * v;
  return branch * -std::expm1(-p_.k_s * a);
}

// ------------------------------------------------------------------------------ Dahl

void DahlParams::validate() const {
  frictionPositive("dahl", "sigma", sigma, "N·m/rad");
  frictionPositive("dahl", "f_c", f_c, "N·m");
  if (!(alpha >= 1.0) || !std::isfinite(alpha))
    badParameter("dahl", "alpha", "a finite value >= 1 (-) (alpha < 1 is not Lipschitz at |F| = f_c)", alpha);
}

DahlFriction::DahlFriction(const DahlParams& params) : p_(params) { p_.validate(); }

double DahlFriction::evaluate(const FrictionInput& in, const double* z, double* zdot) const {
  const double v = in.v;
  // [Hauschild2003, eq. 4.7] in the bristle state: dF/dx = σ (1 − F sgn(v)/F_C)^α, F = σ z, ż = v · dF/dx / σ.
  const double u = 1.0 - p_.sigma * z[0] * sgn(v) / p_.f_c;
  const double phi = p_.alpha == 1.0 ? u : sgn(u) * std::pow(std::abs(u), p_.alpha);
  zdot[0] = v * phi;  // α = 1: ż = v − σ|v| z / F_C (eq. 4.9)
  return p_.sigma * z[0];
}

double DahlFriction::steadyState(double v) const { return p_.f_c * sgn(v); }

// ------------------------------------------------------------------------------ LuGre

void LuGreParams::validate() const {
  frictionPositive("lugre", "sigma0", sigma0, "N·m/rad");
  frictionPositive("lugre", "sigma1", sigma1, "N·m·s/rad");
  validateBranch("lugre", "positive", positive, true);
  validateBranch("lugre", "negative", negative, true);
}

LuGreFriction::LuGreFriction(const LuGreParams& params) : p_(params) { p_.validate(); }

double LuGreFriction::g(double v) const {
  const StribeckBranch& b = v >= 0.0 ? p_.positive : p_.negative;
  const double r = v / b.v_s;
  return b.alpha0 + b.alpha1 * std::exp(-r * r);  // [Hauschild2003, eq. 4.17]
}

double LuGreFriction::evaluate(const FrictionInput& in, const double* z, double* zdot) const {
  const double v = in.v;
  const double alpha2 = v >= 0.0 ? p_.positive.alpha2 : p_.negative.alpha2;
  const double zd = v - p_.sigma0 * std::abs(v) * z[0] / g(v);  // [Hauschild2003, eq. 4.15]
  zdot[0] = zd;
  return p_.sigma0 * z[0] + p_.sigma1 * zd + alpha2 * v;  // [Hauschild2003, eq. 4.16]
}

double LuGreFriction::steadyState(double v) const {
  const double alpha2 = v >= 0.0 ? p_.positive.alpha2 : p_.negative.alpha2;
  return g(v) * sgn(v) + alpha2 * v;  // [Hauschild2003, eq. 4.21]
}

// ------------------------------------------------------------------------------ UR5 LuGre

void LuGreUr5Params::validate() const {
  const char* m = "lugre_ur5";
  frictionPositive(m, "sigma0", sigma0, "N·m/rad");
  frictionPositive(m, "sigma1", sigma1, "N·m·s/rad");
  frictionPositive(m, "qd_s", qd_s, "rad/s");
  frictionNonNegative(m, "k_static", k_static, "(-)");
  frictionPositive(m, "viscous_exponent", viscous_exponent, "(-)");
  // Not given by [Raviola2023]: must be supplied (NaN = unset fails these checks).
  frictionPositive(m, "f_c", f_c, "N·m (required: not given by [Raviola2023])");
  frictionNonNegative(m, "f_v", f_v, "N·m·(s/rad)^exponent (required: not given by [Raviola2023])");
  frictionNonNegative(m, "k_q", k_q, "(-) (required: not given by [Raviola2023])");
}

LuGreUr5Friction::LuGreUr5Friction(const LuGreUr5Params& params) : p_(params) { p_.validate(); }

double LuGreUr5Friction::g(double v) const {
  const double a = std::abs(v);
  // [Raviola2023, §2.4, eq. 7] with |q̇|^{2/3} (our correction: |q̇|^(2/3) so g stays real for q̇ < 0).
  return p_.f_c * (1.0 + p_.k_static * std::exp(-p_.k_q * a / p_.qd_s)) + p_.f_v * std::pow(a, p_.viscous_exponent);
}

double LuGreUr5Friction::evaluate(const FrictionInput& in, const double* z, double* zdot) const {
  const double v = in.v;
  const double zd = v - std::abs(v) * z[0] / g(v) * p_.sigma0;  // [Raviola2023, eq. 7]
  zdot[0] = zd;
  return p_.sigma0 * z[0] + p_.sigma1 * zd;  // T_f = σ0 z + σ1 ż, no separate viscous term
}

double LuGreUr5Friction::steadyState(double v) const { return sgn(v) * g(v); }

}  // namespace jointsim::drive

// ------------------------------------------------------------------------------ parameter tables

namespace jointsim::drive {
namespace {
using R = ParameterRange;
constexpr ParameterRole kNone = ParameterRole::None;

// The static set of one direction (`side` "positive" or "negative"); α0 > 0 for LuGre (g ≥ α0 > 0).
void branchRefs(std::vector<ParameterRef>& out, const std::string& side, StribeckBranch& b, bool lugre) {
  const std::string dir = side == "positive" ? " (v > 0)" : " (v < 0)";
  out.push_back({{side + ".alpha0", "N·m", 0.0, lugre ? R::positive() : R::nonNegative(), ParameterRole::Coulomb,
                  "Coulomb friction α0 = F_C" + dir},
                 &b.alpha0});
  out.push_back(
      {{side + ".alpha1", "N·m", 0.0, R::nonNegative(), kNone, "stiction excess α1 = F_S − F_C" + dir}, &b.alpha1});
  out.push_back(
      {{side + ".alpha2", "N·m·s/rad", 0.0, R::nonNegative(), kNone, "viscous coefficient α2" + dir}, &b.alpha2});
  out.push_back({{side + ".v_s", "rad/s", 0.0, R::positive(), kNone, "Stribeck velocity v_S" + dir}, &b.v_s});
}

std::vector<ParameterRef> refs(CoulombViscousParams& p) {
  return {{{"f_c", "N·m", 0.0, R::nonNegative(), ParameterRole::Coulomb, "Coulomb friction F_C"}, &p.f_c},
          {{"f_v", "N·m·s/rad", 0.0, R::nonNegative(), kNone, "viscous coefficient F_v"}, &p.f_v},
          {{"v_reg", "rad/s", 0.0, R::positive(), kNone, "regularisation velocity of sgn(v)"}, &p.v_reg}};
}

std::vector<ParameterRef> refs(TableFrictionParams& p) {
  std::vector<ParameterRef> out;
  for (size_t i = 0; i < p.tau_pos.size(); ++i) {
    const std::string row = "tau_pos[" + std::to_string(i) + "]";
    out.push_back({{row + "[0]", "rad/s", 0.0, R::nonNegative(), kNone, "speed of table row " + std::to_string(i)},
                   &p.tau_pos[i][0]});
    out.push_back({{row + "[1]", "N·m", 0.0, R::nonNegative(), ParameterRole::Coulomb,
                    "sliding friction torque of table row " + std::to_string(i)},
                   &p.tau_pos[i][1]});
  }
  out.push_back(
      {{"peak", "1", 0.0, R::atLeast(1.0), kNone, "stiction factor (stiction torque peak·τ_pos(0))"}, &p.peak});
  out.push_back({{"v_stick", "rad/s", 0.0, R::positive(), kNone, "half-width of the sticking band"}, &p.v_stick});
  out.push_back({{"d_stick", "N·m·s/rad", 0.0, R::nonNegative(), kNone,
                  "damping inside the sticking band (0: peak·τ_pos(0)/v_stick)"},
                 &p.d_stick});
  return out;
}

std::vector<ParameterRef> refs(StribeckParams& p) {
  std::vector<ParameterRef> out;
  branchRefs(out, "positive", p.positive, false);
  branchRefs(out, "negative", p.negative, false);
  out.push_back({{"delta", "1", 0.0, R::positive(), kNone, "form factor δ of the Stribeck exponential"}, &p.delta});
  out.push_back({{"k_s", "s/rad", 0.0, R::positive(), kNone, "slope-limiter factor k_S"}, &p.k_s});
  return out;
}

std::vector<ParameterRef> refs(DahlParams& p) {
  return {{{"sigma", "N·m/rad", 0.0, R::positive(), ParameterRole::BristleStiffness, "rest stiffness σ"}, &p.sigma},
          {{"f_c", "N·m", 0.0, R::positive(), ParameterRole::Coulomb, "Coulomb friction F_C"}, &p.f_c},
          {{"alpha", "1", 0.0, R::atLeast(1.0), kNone, "shape exponent α"}, &p.alpha}};
}

std::vector<ParameterRef> refs(LuGreParams& p) {
  std::vector<ParameterRef> out{
      {{"sigma0", "N·m/rad", 0.0, R::positive(), ParameterRole::BristleStiffness, "bristle stiffness σ0"}, &p.sigma0},
      {{"sigma1", "N·m·s/rad", 0.0, R::positive(), kNone, "bristle damping σ1"}, &p.sigma1}};
  branchRefs(out, "positive", p.positive, true);
  branchRefs(out, "negative", p.negative, true);
  return out;
}

std::vector<ParameterRef> refs(LuGreUr5Params& p) {
  return {{{"f_c", "N·m", 0.0, R::positive(), ParameterRole::Coulomb, "Coulomb coefficient f_c"}, &p.f_c},
          {{"f_v", "N·m·(s/rad)^" + formatNumber(p.viscous_exponent, 6), 0.0, R::nonNegative(), kNone,
            "viscous coefficient f_v (on |q̇| to the viscous exponent)"},
           &p.f_v},
          {{"k_q", "1", 0.0, R::nonNegative(), kNone, "Stribeck shape factor k_q"}, &p.k_q},
          {{"sigma0", "N·m/rad", 0.0, R::positive(), ParameterRole::BristleStiffness, "bristle stiffness σ0"},
           &p.sigma0},
          {{"sigma1", "N·m·s/rad", 0.0, R::positive(), kNone, "bristle damping σ1"}, &p.sigma1},
          {{"qd_s", "rad/s", 0.0, R::positive(), kNone, "Stribeck speed q̇_s"}, &p.qd_s},
          {{"k_static", "1", 0.0, R::nonNegative(), kNone, "static increment K_static over Coulomb"}, &p.k_static},
          {{"viscous_exponent", "1", 0.0, R::positive(), kNone, "exponent on |q̇| of the viscous term"},
           &p.viscous_exponent}};
}

template <class Model>
std::vector<ParameterInfo> tableOf(const Model& m) {
  auto p = m.params();
  return describeParameters(refs(p));
}

template <class Model>
std::shared_ptr<const Friction> changed(const Model& m, const ParameterChanges& changes) {
  auto p = m.params();
  assignParameters(refs(p), changes, m.type());
  return std::make_shared<Model>(p);
}
}  // namespace

std::vector<ParameterInfo> CoulombViscousFriction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> CoulombViscousFriction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}
std::vector<ParameterInfo> TableFriction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> TableFriction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}
std::vector<ParameterInfo> StribeckFriction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> StribeckFriction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}
std::vector<ParameterInfo> DahlFriction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> DahlFriction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}
std::vector<ParameterInfo> LuGreFriction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> LuGreFriction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}
std::vector<ParameterInfo> LuGreUr5Friction::parameters() const { return tableOf(*this); }
std::shared_ptr<const Friction> LuGreUr5Friction::withParameters(const ParameterChanges& c) const {
  return changed(*this, c);
}

}  // namespace jointsim::drive
