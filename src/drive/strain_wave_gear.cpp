#include "jointsim/drive/strain_wave_gear.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "common/constants.hpp"
#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::drive {
namespace {

const char* const kComponent = "strain_wave_gear";
void swgPositive(const char* field, double v, const char* unit) { check::positive(kComponent, field, v, unit); }
void swgNonNegative(const char* field, double v, const char* unit) { check::nonNegative(kComponent, field, v, unit); }

}  // namespace

// ------------------------------------------------------------------------------------------ parameters

void StrainWaveGearParams::validate() const {
  swgPositive("r_g", r_g, "m");
  if (!std::isfinite(alpha_t) || !(alpha_t > 0.0) || !(alpha_t < 0.5 * kPi))
    check::fail(kComponent, "alpha_t", "a pressure angle in (0, pi/2) rad", alpha_t);
  if (!std::isfinite(tau) || !(tau > 1.0)) check::fail(kComponent, "tau", "a finite reduction ratio > 1", tau);
  swgPositive("K_WG", K_WG, "N·m/rad");
  swgPositive("K_b", K_b, "N/m");
  swgPositive("K_FS", K_FS, "N·m/rad");
  swgPositive("K_m", K_m, "N/m");
  swgPositive("K_CS", K_CS, "N·m/rad");
  swgPositive("J_WG", J_WG, "kg·m²");
  swgPositive("J_FS", J_FS, "kg·m²");
  swgPositive("J_CS", J_CS, "kg·m²");
  const bool ratio = damping_mode == DampingMode::DampingRatio;
  swgNonNegative("c_WG", c_WG, ratio ? "(damping ratio)" : "N·m·s/rad");
  swgNonNegative("c_b", c_b, ratio ? "(damping ratio)" : "N·s/m");
  swgNonNegative("c_m", c_m, ratio ? "(damping ratio)" : "N·s/m");
  swgNonNegative("c_FS", c_FS, ratio ? "(damping ratio)" : "N·m·s/rad");
  swgNonNegative("c_CS", c_CS, ratio ? "(damping ratio)" : "N·m·s/rad");
}

double StrainWaveGearParams::alphaN() const { return std::atan(1.0 / (tau * std::tan(alpha_t))); }

StrainWaveGearParams StrainWaveGearParams::ur5SizeA() { return StrainWaveGearParams{}; }

StrainWaveGearParams StrainWaveGearParams::ur5SizeB() {
  StrainWaveGearParams p;
  p.r_g = 16.90e-3;
  p.K_WG = 1.77e4;
  p.K_b = 1.2e8;
  p.K_FS = 7.26e4;
  p.K_m = 3.20e8;
  p.K_CS = 6.23e6;
  p.J_WG = 2.21e-6;
  p.J_FS = 3.75e-5;
  p.J_CS = 1.85e-5;
  return p;
}

// ------------------------------------------------------------------------------------------ model

StrainWaveGear::StrainWaveGear(const StrainWaveGearParams& params) : p_(params) {
  p_.validate();
  tn_ = 1.0 / (p_.tau * std::tan(p_.alpha_t));  // eq. 3: tan α_n tan α_t = 1/τ exactly
  rho_ = p_.reaction_form == ReactionForm::EnergyConsistent ? tn_ : tn_ / (1.0 + tn_ * tn_);  // sin·cos
  st_ = std::sin(p_.alpha_t);
  ct_ = std::cos(p_.alpha_t);
  rtn_ = p_.r_g * tn_;
  const double r2 = p_.r_g * p_.r_g;
  m_FS_ = p_.J_FS / r2;
  kFSt_ = p_.K_FS / r2;
  if (p_.damping_mode == DampingMode::Coefficient) {
    c_ = {p_.c_WG, p_.c_b, p_.c_m, p_.c_FS, p_.c_CS};
  } else {
    // c = 2ζ√(k m_eq), m_eq = effective inertia of the element deflection with both shafts held.
    const double m_b = 1.0 / (rtn_ * rtn_ / p_.J_WG + r2 / p_.J_FS);
    const double m_m = 1.0 / (r2 / p_.J_FS + r2 * ct_ * ct_ / p_.J_CS);
    c_.c_WG = 2.0 * p_.c_WG * std::sqrt(p_.K_WG * p_.J_WG);
    c_.c_b = 2.0 * p_.c_b * std::sqrt(p_.K_b * m_b);
    c_.c_m = 2.0 * p_.c_m * std::sqrt(p_.K_m * m_m);
    c_.c_FS = 2.0 * p_.c_FS * std::sqrt(p_.K_FS * p_.J_FS);
    c_.c_CS = 2.0 * p_.c_CS * std::sqrt(p_.K_CS * p_.J_CS);
  }
  cFSt_ = c_.c_FS / r2;
}

double StrainWaveGear::alphaN() const { return std::atan(tn_); }

double StrainWaveGear::staticTorqueRatio() const { return p_.tau * tn_ / rho_; }

double StrainWaveGear::staticOutputStiffness() const {
  const double r2 = p_.r_g * p_.r_g;
  const double tt = std::tan(p_.alpha_t);
  const double compliance = (rho_ / tn_) / (p_.tau * p_.tau * p_.K_WG) + tt * tt / (r2 * p_.K_b) +
                            1.0 / (r2 * p_.K_m * ct_ * ct_) + 1.0 / p_.K_FS + 1.0 / p_.K_CS;
  return 1.0 / compliance;
}

inline double StrainWaveGear::meshDeflection(const ShaftPorts& ports, const double* x) const {
  // δ_m = x_FS sα_t − (y_CS + y_FS) cα_t with x_FS = r_g tanα_n (q_in − φ_WG) − Δ_b, y_CS = r_g (q_out + φ_CS)
  // and sα_t r_g tanα_n = cα_t r_g / τ.
  const double net = ports.q_in / p_.tau - ports.q_out;
  return p_.r_g * ct_ * net - st_ * (rtn_ * x[kTwistWG] + x[kBearing]) - ct_ * (p_.r_g * x[kTwistCS] + x[kFSy]);
}

inline double StrainWaveGear::meshRate(const double* x) const {
  return st_ * x[kVelFSx] - ct_ * (p_.r_g * x[kVelCS] + x[kVelFSy]);
}

StrainWaveGearForces StrainWaveGear::forces(const ShaftPorts& ports, const double* x) const {
  StrainWaveGearForces f;
  f.T_in = p_.K_WG * x[kTwistWG] + c_.c_WG * (ports.qd_in - x[kVelWG]);
  f.F_b = p_.K_b * x[kBearing] + c_.c_b * (rtn_ * x[kVelWG] - x[kVelFSx]);
  f.F_m = p_.K_m * meshDeflection(ports, x) + c_.c_m * meshRate(x);
  f.F_t = kFSt_ * x[kFSy] + cFSt_ * x[kVelFSy];
  f.T_CS = p_.K_CS * x[kTwistCS] + c_.c_CS * (x[kVelCS] - ports.qd_out);
  return f;
}

PortTorques StrainWaveGear::evaluate(const ShaftPorts& ports, const double* x, double* xdot) const {
  const StrainWaveGearForces f = forces(ports, x);
  xdot[kTwistWG] = ports.qd_in - x[kVelWG];
  xdot[kVelWG] = (f.T_in - f.F_b * p_.r_g * rho_) / p_.J_WG;
  xdot[kBearing] = rtn_ * x[kVelWG] - x[kVelFSx];
  xdot[kVelFSx] = (f.F_b - f.F_m * st_) / m_FS_;
  xdot[kFSy] = x[kVelFSy];
  xdot[kVelFSy] = (f.F_m * ct_ - f.F_t) / m_FS_;
  xdot[kTwistCS] = x[kVelCS] - ports.qd_out;
  xdot[kVelCS] = (f.F_m * p_.r_g * ct_ - f.T_CS) / p_.J_CS;
  return {f.T_in, f.T_CS};
}

double StrainWaveGear::storedEnergy(const ShaftPorts& ports, const double* x) const {
  const double dm = meshDeflection(ports, x);
  const double kinetic = p_.J_WG * x[kVelWG] * x[kVelWG] + m_FS_ * (x[kVelFSx] * x[kVelFSx] + x[kVelFSy] * x[kVelFSy]) +
                         p_.J_CS * x[kVelCS] * x[kVelCS];
  const double potential = p_.K_WG * x[kTwistWG] * x[kTwistWG] + p_.K_b * x[kBearing] * x[kBearing] + p_.K_m * dm * dm +
                           kFSt_ * x[kFSy] * x[kFSy] + p_.K_CS * x[kTwistCS] * x[kTwistCS];
  return 0.5 * (kinetic + potential);
}

double StrainWaveGear::dissipatedPower(const ShaftPorts& ports, const double* x) const {
  const double v_wg = ports.qd_in - x[kVelWG];
  const double v_b = rtn_ * x[kVelWG] - x[kVelFSx];
  const double v_m = meshRate(x);
  const double v_cs = x[kVelCS] - ports.qd_out;
  return c_.c_WG * v_wg * v_wg + c_.c_b * v_b * v_b + c_.c_m * v_m * v_m + cFSt_ * x[kVelFSy] * x[kVelFSy] +
         c_.c_CS * v_cs * v_cs;
}

double StrainWaveGear::spuriousPower(const ShaftPorts& ports, const double* x) const {
  return forces(ports, x).F_b * p_.r_g * x[kVelWG] * (tn_ - rho_);
}

std::vector<std::string> StrainWaveGear::stateNames() const {
  return {"phi_WG[rad]", "qd_WG[rad/s]", "delta_b[m]",  "xd_FS[m/s]",
          "y_FS[m]",     "yd_FS[m/s]",   "phi_CS[rad]", "qd_CS[rad/s]"};
}

Eigen::Matrix<double, 6, 1> StrainWaveGear::staticEquilibrium(double q_M, double q_0) const {
  // eq. 6, unknowns (q_WG, x_WG, x_FS, y_FS, y_CS, q_CS); row 1 with ρ instead of sα_n cα_n.
  const double r = p_.r_g, Kb = p_.K_b, Km = p_.K_m;
  const double sc = st_ * ct_, c2 = ct_ * ct_, s2 = st_ * st_;
  Eigen::Matrix<double, 6, 6> A;
  A << p_.K_WG, Kb * r * rho_, -Kb * r * rho_, 0, 0, 0,       //
      0, Kb, -(Kb + Km * s2), Km * sc, Km * sc, 0,            //
      0, 0, -Km * sc, Km * c2 + kFSt_, Km * c2, 0,            //
      0, 0, -Km * r * sc, Km * r * c2, Km * r * c2, p_.K_CS,  //
      rtn_, -1, 0, 0, 0, 0,                                   //
      0, 0, 0, 0, -1, r;
  Eigen::Matrix<double, 6, 1> b;
  b << p_.K_WG * q_M, 0, 0, p_.K_CS * q_0, 0, 0;
  return A.colPivHouseholderQr().solve(b);
}

void StrainWaveGear::initialState(double q_in, double q_out, double* x) const {
  // eq. 6 after the exact change of variables q_WG = q_M − φ_WG, x_WG = r_g tanα_n q_M + e_x,
  // x_FS = x_WG − Δ_b, y_CS = r_g q_M/τ + e_y, q_CS = q_0 + φ_CS. Unknowns u = (φ_WG, e_x, Δ_b, y_FS, e_y,
  // φ_CS); the only source is the net twist ν = q_0 − q_M/τ, so no large angles enter the solve.
  // δ_m = sα_t (e_x − Δ_b) − cα_t (e_y + y_FS).
  const double r = p_.r_g, Kb = p_.K_b, Km = p_.K_m;
  const double s = st_, c = ct_;
  Eigen::Matrix<double, 6, 6> A;
  A << p_.K_WG, 0, -Kb * r * rho_, 0, 0, 0,                               // WG
      0, -Km * s * s, Kb + Km * s * s, Km * s * c, Km * s * c, 0,         // FS radial: F_b − F_m s = 0
      0, Km * c * s, -Km * c * s, -(Km * c * c + kFSt_), -Km * c * c, 0,  // FS tangential: F_m c − F_t = 0
      0, Km * r * c * s, -Km * r * c * s, -Km * r * c * c, -Km * r * c * c, -p_.K_CS,  // CS: F_m r c − T_CS = 0
      rtn_, 1, 0, 0, 0, 0,                                                             // e_x = −r_g tanα_n φ_WG
      0, 0, 0, 0, 1, -r;                                                               // e_y = r_g (ν + φ_CS)
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  b[5] = r * (q_out - q_in / p_.tau);
  const Eigen::Matrix<double, 6, 1> u = A.colPivHouseholderQr().solve(b);
  x[kTwistWG] = u[0];
  x[kVelWG] = 0.0;
  x[kBearing] = u[2];
  x[kVelFSx] = 0.0;
  x[kFSy] = u[3];
  x[kVelFSy] = 0.0;
  x[kTwistCS] = u[5];
  x[kVelCS] = 0.0;
}

Eigen::Matrix<double, 6, 1> StrainWaveGear::absoluteCoordinates(const ShaftPorts& ports, const double* x) const {
  Eigen::Matrix<double, 6, 1> z;
  const double q_WG = ports.q_in - x[kTwistWG];
  const double x_WG = rtn_ * q_WG;
  const double q_CS = ports.q_out + x[kTwistCS];
  z << q_WG, x_WG, x_WG - x[kBearing], x[kFSy], p_.r_g * q_CS, q_CS;
  return z;
}

Eigen::VectorXd StrainWaveGear::linearisedModes(double J_in, double J_out) const {
  if (!(J_in > 0.0)) throw InputError("linearisedModes: J_in must be > 0 kg·m² (or +inf for a held shaft)");
  if (!(J_out > 0.0)) throw InputError("linearisedModes: J_out must be > 0 kg·m² (or +inf for a held shaft)");
  // DoFs z = (q_in, q_WG, x_FS, y_FS, q_CS, q_out). Each element i has stiffness k_i and deflection g_i·z;
  // its generalized force is −k_i h_i (g_i·z), with h_i = g_i except the WG entry of the bearing (ρ r_g).
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  Eigen::Matrix<double, 6, 6> K = Eigen::Matrix<double, 6, 6>::Zero();
  auto add = [&K](double k, const Vec6& h, const Vec6& g) { K += k * h * g.transpose(); };
  Vec6 g;
  g << 1, -1, 0, 0, 0, 0;
  add(p_.K_WG, g, g);
  g << 0, rtn_, -1, 0, 0, 0;
  Vec6 h = g;
  h[1] = p_.r_g * rho_;
  add(p_.K_b, h, g);
  g << 0, 0, st_, -ct_, -ct_ * p_.r_g, 0;
  add(p_.K_m, g, g);
  g << 0, 0, 0, 1, 0, 0;
  add(kFSt_, g, g);
  g << 0, 0, 0, 0, 1, -1;
  add(p_.K_CS, g, g);
  Vec6 m;
  m << J_in, p_.J_WG, m_FS_, m_FS_, p_.J_CS, J_out;

  // Keep the free DoFs (a held shaft has infinite inertia: remove its row and column).
  int idx[6];
  int n = 0;
  for (int i = 0; i < 6; ++i)
    if (std::isfinite(m[i])) idx[n++] = i;
  Eigen::MatrixXd Kr(n, n), Mr = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    Mr(i, i) = m[idx[i]];
    for (int j = 0; j < n; ++j) Kr(i, j) = K(idx[i], idx[j]);
  }
  Eigen::VectorXd lambda(n);
  if (p_.reaction_form == ReactionForm::EnergyConsistent) {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kr, Mr, Eigen::EigenvaluesOnly);
    lambda = es.eigenvalues();
  } else {
    const Eigen::MatrixXd A = Mr.diagonal().cwiseInverse().asDiagonal() * Kr;
    Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
    lambda = es.eigenvalues().real();
  }
  Eigen::VectorXd f(n);
  for (int i = 0; i < n; ++i) f[i] = std::sqrt(std::max(lambda[i], 0.0)) / (2.0 * kPi);
  std::sort(f.data(), f.data() + n);
  return f;
}

}  // namespace jointsim::drive

// ------------------------------------------------------------------------------------------ parameter table

namespace jointsim::drive {
namespace {
std::vector<ParameterRef> swgRefs(StrainWaveGearParams& p) {
  using R = ParameterRange;
  const auto none = ParameterRole::None;
  const auto stiff = ParameterRole::Stiffness;
  const bool zeta = p.damping_mode == DampingMode::DampingRatio;
  auto damping = [&](const char* key, const char* unit, const std::string& what, double* target) {
    return ParameterRef{{key, zeta ? "1" : unit, 0.0, R::nonNegative(), none,
                         what + (zeta ? " as a damping ratio ζ" : " (coefficient)")},
                        target};
  };
  return {
      {{"r_g", "m", 0.0, R::positive(), none, "primitive radius r_g of the flexspline"}, &p.r_g},
      {{"alpha_t", "rad", 0.0, {0.0, 0.5 * kPi, true, true}, none, "tooth pressure angle α_t"}, &p.alpha_t},
      {{"tau", "1", 0.0, R::above(1.0), none, "reduction ratio τ = Z_CS/(Z_CS − Z_FS) [Raviola2023, eq. 2]"}, &p.tau},
      {{"K_WG", "N·m/rad", 0.0, R::positive(), stiff, "motor shaft – wave generator torsional stiffness"}, &p.K_WG},
      {{"K_b", "N/m", 0.0, R::positive(), stiff, "wave generator bearing – flexspline radial stiffness"}, &p.K_b},
      {{"K_FS", "N·m/rad", 0.0, R::positive(), stiff, "flexspline torsional stiffness to the case"}, &p.K_FS},
      {{"K_m", "N/m", 0.0, R::positive(), stiff, "flexspline – circular spline mesh stiffness"}, &p.K_m},
      {{"K_CS", "N·m/rad", 0.0, R::positive(), stiff, "circular spline – output flange torsional stiffness"}, &p.K_CS},
      {{"J_WG", "kg·m²", 0.0, R::positive(), none, "wave generator inertia"}, &p.J_WG},
      {{"J_FS", "kg·m²", 0.0, R::positive(), none, "flexspline inertia"}, &p.J_FS},
      {{"J_CS", "kg·m²", 0.0, R::positive(), none, "circular spline inertia"}, &p.J_CS},
      damping("c_WG", "N·m·s/rad", "motor shaft – wave generator damping", &p.c_WG),
      damping("c_b", "N·s/m", "bearing – flexspline radial damping", &p.c_b),
      damping("c_m", "N·s/m", "mesh contact damping", &p.c_m),
      damping("c_FS", "N·m·s/rad", "flexspline – case damping", &p.c_FS),
      damping("c_CS", "N·m·s/rad", "circular spline – output flange damping", &p.c_CS)};
}
}  // namespace

std::vector<ParameterInfo> StrainWaveGear::parameters() const {
  StrainWaveGearParams p = p_;
  return describeParameters(swgRefs(p));
}

std::shared_ptr<const Transmission> StrainWaveGear::withParameters(const ParameterChanges& changes) const {
  StrainWaveGearParams p = p_;
  assignParameters(swgRefs(p), changes, kComponent);
  return std::make_shared<StrainWaveGear>(p);
}

}  // namespace jointsim::drive
