// Rigid multibody algorithms (Featherstone, RBDA 2008, ch. 5–7), in body-fixed joint frames.
// Notation: X = data.liMi[i] = (R, p) is body i's frame in its parent's; motion vectors are [ω; v],
// force vectors [n; f]. Spatial inertias are (m, h = m c, I_O) about the body-frame origin.
#include "jointsim/multibody/algorithms.hpp"

#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "jointsim/common/error.hpp"

namespace jointsim::multibody {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

void checkSize(const Model& model, const Data& data, const VecRef& x, const char* what) {
  if (x.size() != model.nq)
    throw InputError(std::string(what) + " has " + std::to_string(x.size()) + " values, robot '" + model.name +
                     "' has " + std::to_string(model.nq) + " joints");
  if (data.nq != model.nq) throw InputError("Data was built for a different model");
}

inline bool isRevolute(const Model& model, size_t i) { return model.joint_types[i] == JointType::Revolute; }

// liMi = X_tree · X_joint(q). Rotations about a coordinate axis (model.axis_kind 0, 1, 2) combine the
// columns of X_tree.R directly; other axes use Rodrigues' formula.
inline void jointPlacement(const Model& model, size_t i, double q, Placement& out) {
  const Placement& T = model.joint_placements[i];
  const Vector3d& k = model.axes[i];
  if (!isRevolute(model, i)) {
    out.R = T.R;
    out.p.noalias() = T.p + T.R * (k * q);
    return;
  }
  const double s = std::sin(q), c = std::cos(q);
  out.p = T.p;
  switch (model.axis_kind[i]) {
    case 0:  // R_J = Rx(q): columns e0, (0, c, s), (0, −s, c)
      out.R.col(0) = T.R.col(0);
      out.R.col(1) = c * T.R.col(1) + s * T.R.col(2);
      out.R.col(2) = c * T.R.col(2) - s * T.R.col(1);
      return;
    case 1:  // R_J = Ry(q): columns (c, 0, −s), e1, (s, 0, c)
      out.R.col(0) = c * T.R.col(0) - s * T.R.col(2);
      out.R.col(1) = T.R.col(1);
      out.R.col(2) = s * T.R.col(0) + c * T.R.col(2);
      return;
    case 2:  // R_J = Rz(q): columns (c, s, 0), (−s, c, 0), e2
      out.R.col(0) = c * T.R.col(0) + s * T.R.col(1);
      out.R.col(1) = c * T.R.col(1) - s * T.R.col(0);
      out.R.col(2) = T.R.col(2);
      return;
    default: {
      // Rodrigues: R_J = cos q 1 + sin q [k] + (1 − cos q) k kᵀ.
      const double t = 1.0 - c;
      Matrix3d RJ;
      RJ << c + t * k.x() * k.x(), t * k.x() * k.y() - s * k.z(), t * k.x() * k.z() + s * k.y(),
          t * k.x() * k.y() + s * k.z(), c + t * k.y() * k.y(), t * k.y() * k.z() - s * k.x(),
          t * k.x() * k.z() - s * k.y(), t * k.y() * k.z() + s * k.x(), c + t * k.z() * k.z();
      out.R.noalias() = T.R * RJ;
    }
  }
}

// Motion transform parent → child: ω_c = Rᵀ ω, v_c = Rᵀ (v − p × ω).
inline Vector6d motionToChild(const Placement& X, const Vector6d& m) {
  Vector6d out;
  const Vector3d w = m.head<3>();
  out.head<3>().noalias() = X.R.transpose() * w;
  out.tail<3>().noalias() = X.R.transpose() * (m.tail<3>() - X.p.cross(w));
  return out;
}

// Force transform child → parent: f_p = R f_c, n_p = R n_c + p × f_p.
inline Vector6d forceToParent(const Placement& X, const Vector6d& f) {
  Vector6d out;
  out.tail<3>().noalias() = X.R * f.tail<3>();
  out.head<3>().noalias() = X.R * f.head<3>();
  out.head<3>() += X.p.cross(out.tail<3>());
  return out;
}

// Spatial inertia times motion: n = I_O ω + h × v, f = m v − h × ω.
inline Vector6d inertiaTimes(double m, const Vector3d& h, const Matrix3d& IO, const Vector6d& x) {
  Vector6d out;
  const Vector3d w = x.head<3>(), v = x.tail<3>();
  out.head<3>().noalias() = IO * w;
  out.head<3>() += h.cross(v);
  out.tail<3>() = m * v - h.cross(w);
  return out;
}

// Spatial cross products: motion × motion and motion ×* force.
inline Vector6d crossMotion(const Vector6d& v, const Vector6d& m) {
  Vector6d out;
  out.head<3>() = v.head<3>().cross(m.head<3>());
  out.tail<3>() = v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>());
  return out;
}
inline Vector6d crossForce(const Vector6d& v, const Vector6d& f) {
  Vector6d out;
  out.head<3>() = v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>());
  out.tail<3>() = v.head<3>().cross(f.tail<3>());
  return out;
}

// Joint motion subspace S times a scalar, and Sᵀ f.
inline Vector6d jointMotion(const Model& model, size_t i, double x) {
  Vector6d out = Vector6d::Zero();
  if (isRevolute(model, i))
    out.head<3>() = model.axes[i] * x;
  else
    out.tail<3>() = model.axes[i] * x;
  return out;
}
inline double jointProject(const Model& model, size_t i, const Vector6d& f) {
  if (!isRevolute(model, i)) return model.axes[i].dot(f.tail<3>());
  const int k = model.axis_kind[i];  // a coordinate axis exactly: the dot product is that component, bit for bit
  return k < 3 ? f[k] : model.axes[i].dot(f.head<3>());
}

// Base acceleration −g lets gravity enter as a fictitious upward acceleration of the base ([Featherstone2008, §5.3]).
inline Vector6d baseAcceleration(const Model& model) {
  Vector6d a0;
  a0.head<3>().setZero();
  a0.tail<3>() = -model.gravity;
  return a0;
}

// Shared RNEA core. with_velocity = false skips the velocity-product terms (gravity-only pass).
template <bool with_velocity>
void rneaCore(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd,
              const Matrix6Xd* fext, Eigen::VectorXd& tau) {
  const auto n = static_cast<size_t>(model.nq);
  const Vector6d a0 = baseAcceleration(model);
  // Forward pass: v_i = X v_λ + S q̇_i;  a_i = X a_λ + S q̈_i + v_i × S q̇_i;
  //               f_i = I_i a_i + v_i ×* I_i v_i − fext_i.
  for (size_t i = 0; i < n; ++i) {
    const int parent = model.parents[i];
    Placement& X = data.liMi[i];
    jointPlacement(model, i, q[static_cast<Eigen::Index>(i)], X);
    data.oMi[i] = parent < 0 ? X : data.oMi[static_cast<size_t>(parent)] * X;
    const auto ii = static_cast<Eigen::Index>(i);
    const Vector6d a_parent = parent < 0 ? a0 : data.a[static_cast<size_t>(parent)];
    data.a[i] = motionToChild(X, a_parent) + jointMotion(model, i, qdd[ii]);
    if constexpr (with_velocity) {
      const Vector6d Sqd = jointMotion(model, i, qd[ii]);
      data.v[i] = parent < 0 ? Sqd : Vector6d(motionToChild(X, data.v[static_cast<size_t>(parent)]) + Sqd);
      data.a[i] += crossMotion(data.v[i], Sqd);
      const Vector6d Iv = inertiaTimes(model.mass[i], model.first_moment[i], model.inertia_origin[i], data.v[i]);
      data.f[i] = inertiaTimes(model.mass[i], model.first_moment[i], model.inertia_origin[i], data.a[i]) +
                  crossForce(data.v[i], Iv);
    } else {
      data.v[i].setZero();
      data.f[i] = inertiaTimes(model.mass[i], model.first_moment[i], model.inertia_origin[i], data.a[i]);
    }
    if (fext != nullptr) data.f[i] -= fext->col(ii);
  }
  // Backward pass: τ_i = Sᵀ f_i (+ armature q̈_i);  f_λ += X* f_i.
  for (size_t i = n; i-- > 0;) {
    const auto ii = static_cast<Eigen::Index>(i);
    tau[ii] = jointProject(model, i, data.f[i]) + model.armature[ii] * qdd[ii];
    const int parent = model.parents[i];
    if (parent >= 0) data.f[static_cast<size_t>(parent)] += forceToParent(data.liMi[i], data.f[i]);
  }
}

void checkFext(const Model& model, const Matrix6Xd* fext) {
  if (fext != nullptr && fext->cols() != model.nq)
    throw InputError("external wrench matrix has " + std::to_string(fext->cols()) +
                     " columns, expected one per body (" + std::to_string(model.nq) + ")");
}

}  // namespace

void updateFramePlacements(const Model& model, Data& data) {
  for (size_t k = 0; k < model.frames.size(); ++k) {
    const Frame& fr = model.frames[k];
    data.oMf[k] = fr.joint < 0 ? fr.placement : data.oMi[static_cast<size_t>(fr.joint)] * fr.placement;
  }
}

void forwardKinematics(const Model& model, Data& data, const VecRef& q) {
  checkSize(model, data, q, "q");
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i) {
    jointPlacement(model, i, q[static_cast<Eigen::Index>(i)], data.liMi[i]);
    const int parent = model.parents[i];
    data.oMi[i] = parent < 0 ? data.liMi[i] : data.oMi[static_cast<size_t>(parent)] * data.liMi[i];
  }
  updateFramePlacements(model, data);
}

const Eigen::VectorXd& rnea(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd,
                            const Matrix6Xd* fext) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  checkSize(model, data, qdd, "qdd");
  checkFext(model, fext);
  rneaCore<true>(model, data, q, qd, qdd, fext, data.tau);
  return data.tau;
}

const Eigen::VectorXd& gravityTorques(const Model& model, Data& data, const VecRef& q) {
  checkSize(model, data, q, "q");
  rneaCore<false>(model, data, q, data.zeros, data.zeros, nullptr, data.g);
  return data.g;
}

const Eigen::VectorXd& nonLinearEffects(const Model& model, Data& data, const VecRef& q, const VecRef& qd) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  rneaCore<true>(model, data, q, qd, data.zeros, nullptr, data.nle);
  return data.nle;
}

namespace {

// World spatial inertia (6×6, base axes, about the base origin) of body i from its placement oMi:
// h' = R h + m p, I' = R I_O Rᵀ − [Rh][p] − [p][Rh] − m [p]², as the matrix [[I', [h']], [−[h'], m 1]].
inline void worldInertia(const Model& model, size_t i, const Placement& X, Matrix6d& out) {
  const double m = model.mass[i];
  const Vector3d Rh = X.R * model.first_moment[i];
  const Matrix3d P = skew(X.p), H = skew(Rh);
  const Vector3d hw = Rh + m * X.p;
  out.topLeftCorner<3, 3>().noalias() = X.R * model.inertia_origin[i] * X.R.transpose();
  out.topLeftCorner<3, 3>() -= H * P + P * H + m * P * P;
  const Matrix3d Hw = skew(hw);
  out.topRightCorner<3, 3>() = Hw;
  out.bottomLeftCorner<3, 3>() = -Hw;
  out.bottomRightCorner<3, 3>() = m * Matrix3d::Identity();
}

// Joint motion subspace in base coordinates: revolute [z; o × z], prismatic [0; z].
inline Vector6d worldAxis(const Model& model, size_t i, const Placement& oMi) {
  Vector6d S;
  const Vector3d z = oMi.R * model.axes[i];
  if (isRevolute(model, i)) {
    S.head<3>() = z;
    S.tail<3>() = oMi.p.cross(z);
  } else {
    S.head<3>().setZero();
    S.tail<3>() = z;
  }
  return S;
}

}  // namespace

// Composite rigid bodies in the body frames ([Featherstone2008, §6.2]); only the local placements are needed
// (a base-coordinate variant, with world inertias and no walk, measured slower on the UR5: 465 against 442 ns).
const Eigen::MatrixXd& crba(const Model& model, Data& data, const VecRef& q) {
  checkSize(model, data, q, "q");
  const auto n = static_cast<size_t>(model.nq);
  for (size_t i = 0; i < n; ++i) {
    jointPlacement(model, i, q[static_cast<Eigen::Index>(i)], data.liMi[i]);
    data.Yc_m[i] = model.mass[i];
    data.Yc_h[i] = model.first_moment[i];
    data.Yc_I[i] = model.inertia_origin[i];
  }
  for (size_t i = n; i-- > 0;) {
    const auto ii = static_cast<Eigen::Index>(i);
    // F = Ic_i S_i;  M_ii = S_iᵀ F + armature_i.
    Vector6d F;
    if (isRevolute(model, i)) {
      F.head<3>().noalias() = data.Yc_I[i] * model.axes[i];
      F.tail<3>() = model.axes[i].cross(data.Yc_h[i]);
    } else {
      F.head<3>() = data.Yc_h[i].cross(model.axes[i]);
      F.tail<3>() = data.Yc_m[i] * model.axes[i];
    }
    data.M(ii, ii) = jointProject(model, i, F) + model.armature[ii];
    // Walk to the root: F ← X* F;  M_ij = M_ji = S_jᵀ F.
    size_t j = i;
    while (model.parents[j] >= 0) {
      F = forceToParent(data.liMi[j], F);
      j = static_cast<size_t>(model.parents[j]);
      const auto jj = static_cast<Eigen::Index>(j);
      data.M(jj, ii) = data.M(ii, jj) = jointProject(model, j, F);
    }
    // Ic_λ += X Ic_i Xᵀ:  m' = m, h' = R h + m p, I' = R I Rᵀ − [Rh][p] − [p][Rh] − m [p]².
    const int parent = model.parents[i];
    if (parent >= 0) {
      const auto pp = static_cast<size_t>(parent);
      const Placement& X = data.liMi[i];
      const double m = data.Yc_m[i];
      const Vector3d Rh = X.R * data.Yc_h[i];
      const Vector3d& p = X.p;
      data.Yc_m[pp] += m;
      data.Yc_h[pp] += Rh + m * p;
      // With [a][b] = b aᵀ − (a·b) 1:  −[Rh][p] − [p][Rh] − m[p]² = −(p Rhᵀ + Rh pᵀ + m p pᵀ) + (2 Rh·p + m p·p) 1.
      const Matrix3d T = X.R * data.Yc_I[i];
      const Vector3d w = Rh + 0.5 * m * p;  // p Rhᵀ + Rh pᵀ + m p pᵀ = p wᵀ + w pᵀ
      const double d = 2.0 * Rh.dot(p) + m * p.squaredNorm();
      Matrix3d& Ip = data.Yc_I[pp];
      Ip.noalias() += T * X.R.transpose();
      Ip.noalias() -= p * w.transpose() + w * p.transpose();
      Ip.diagonal().array() += d;
    }
  }
  return data.M;
}

const Eigen::VectorXd& aba(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& tau,
                           const Matrix6Xd* fext) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  checkSize(model, data, tau, "tau");
  checkFext(model, fext);
  const auto n = static_cast<size_t>(model.nq);
  // Pass 1: kinematics, velocity products c_i = v_i × S q̇_i, IA_i = I_i, pA_i = v_i ×* I_i v_i − fext_i.
  for (size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const int parent = model.parents[i];
    Placement& X = data.liMi[i];
    jointPlacement(model, i, q[ii], X);
    data.oMi[i] = parent < 0 ? X : data.oMi[static_cast<size_t>(parent)] * X;
    const Vector6d Sqd = jointMotion(model, i, qd[ii]);
    if (parent < 0) {
      data.v[i] = Sqd;
      data.c[i].setZero();
    } else {
      data.v[i] = motionToChild(X, data.v[static_cast<size_t>(parent)]) + Sqd;
      data.c[i] = crossMotion(data.v[i], Sqd);
    }
    const double m = model.mass[i];
    const Vector3d& h = model.first_moment[i];
    Matrix6d& IA = data.IA[i];
    IA.topLeftCorner<3, 3>() = model.inertia_origin[i];
    IA.topRightCorner<3, 3>() = skew(h);
    IA.bottomLeftCorner<3, 3>() = -IA.topRightCorner<3, 3>();
    IA.bottomRightCorner<3, 3>() = m * Eigen::Matrix3d::Identity();
    data.pA[i] = crossForce(data.v[i], inertiaTimes(m, h, model.inertia_origin[i], data.v[i]));
    if (fext != nullptr) data.pA[i] -= fext->col(ii);
  }
  // Pass 2: U = IA S, D = Sᵀ U + armature, u = τ − Sᵀ pA; propagate Ia = IA − U Uᵀ/D and
  // pa = pA + Ia c + U u/D to the parent.
  for (size_t i = n; i-- > 0;) {
    const auto ii = static_cast<Eigen::Index>(i);
    const Vector3d& k = model.axes[i];
    const Matrix6d& IA = data.IA[i];
    data.U[i].noalias() = isRevolute(model, i) ? Vector6d(IA.leftCols<3>() * k) : Vector6d(IA.rightCols<3>() * k);
    data.D[ii] = jointProject(model, i, data.U[i]) + model.armature[ii];
    data.u[ii] = tau[ii] - jointProject(model, i, data.pA[i]);
    const int parent = model.parents[i];
    if (parent < 0) continue;
    const auto pp = static_cast<size_t>(parent);
    const double Dinv = 1.0 / data.D[ii];
    Matrix6d Ia = IA;
    Ia.noalias() -= (Dinv * data.U[i]) * data.U[i].transpose();
    const Vector6d pa = data.pA[i] + Ia * data.c[i] + data.U[i] * (data.u[ii] * Dinv);
    // Xᵀ Ia X with X = diag(Rᵀ, Rᵀ)·[[1, 0], [−[p], 1]]: rotate the 3×3 blocks, then shift by p:
    // A' = A + [p]Bᵀ − B[p] − [p]C[p],  B' = B + [p]C,  C' = C.
    const Placement& X = data.liMi[i];
    const Matrix3d A = X.R * Ia.topLeftCorner<3, 3>() * X.R.transpose();
    const Matrix3d B = X.R * Ia.topRightCorner<3, 3>() * X.R.transpose();
    const Matrix3d C = X.R * Ia.bottomRightCorner<3, 3>() * X.R.transpose();
    const Matrix3d P = skew(X.p);
    const Matrix3d PC = P * C;
    const Matrix3d Bp = B + PC;
    Matrix6d& IAp = data.IA[pp];
    IAp.topLeftCorner<3, 3>() += A + P * B.transpose() - B * P - PC * P;
    IAp.topRightCorner<3, 3>() += Bp;
    IAp.bottomLeftCorner<3, 3>() += Bp.transpose();
    IAp.bottomRightCorner<3, 3>() += C;
    data.pA[pp] += forceToParent(X, pa);
  }
  // Pass 3: a_i = X a_λ + c_i;  q̈_i = (u_i − U_iᵀ a_i)/D_i;  a_i += S q̈_i.
  const Vector6d a0 = baseAcceleration(model);
  for (size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const int parent = model.parents[i];
    data.a[i] = motionToChild(data.liMi[i], parent < 0 ? a0 : data.a[static_cast<size_t>(parent)]) + data.c[i];
    data.ddq[ii] = (data.u[ii] - data.U[i].dot(data.a[i])) / data.D[ii];
    data.a[i] += jointMotion(model, i, data.ddq[ii]);
  }
  return data.ddq;
}

const Eigen::VectorXd& forwardDynamicsCrba(const Model& model, Data& data, const VecRef& q, const VecRef& qd,
                                           const VecRef& tau, const Matrix6Xd* fext) {
  checkSize(model, data, tau, "tau");
  checkSize(model, data, qd, "qd");
  checkFext(model, fext);
  // b = C q̇ + g − Jᵀ fext via RNEA with q̈ = 0, then M q̈ = τ − b.
  rneaCore<true>(model, data, q, qd, data.zeros, fext, data.nle);
  crba(model, data, q);
  data.llt.compute(data.M);
  if (data.llt.info() != Eigen::Success)
    throw InputError("joint-space inertia matrix of robot '" + model.name + "' is not positive definite");
  data.ddq = tau - data.nle;
  data.llt.solveInPlace(data.ddq);
  return data.ddq;
}

const Matrix6Xd& frameJacobian(const Model& model, Data& data, const VecRef& q, int frame) {
  if (frame < 0 || static_cast<size_t>(frame) >= model.frames.size())
    throw InputError("frame index " + std::to_string(frame) + " out of range");
  forwardKinematics(model, data, q);
  data.J.setZero();
  const Frame& fr = model.frames[static_cast<size_t>(frame)];
  const Vector3d p = data.oMf[static_cast<size_t>(frame)].p;
  for (int j = fr.joint; j >= 0; j = model.parents[static_cast<size_t>(j)]) {
    const auto jj = static_cast<size_t>(j);
    const Vector3d z = data.oMi[jj].R * model.axes[jj];
    if (isRevolute(model, jj)) {
      data.J.col(j).head<3>() = z.cross(p - data.oMi[jj].p);
      data.J.col(j).tail<3>() = z;
    } else {
      data.J.col(j).head<3>() = z;
    }
  }
  return data.J;
}

double kineticEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& qd) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  double T = 0.0;
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const int parent = model.parents[i];
    jointPlacement(model, i, q[ii], data.liMi[i]);
    data.oMi[i] = parent < 0 ? data.liMi[i] : data.oMi[static_cast<size_t>(parent)] * data.liMi[i];
    const Vector6d Sqd = jointMotion(model, i, qd[ii]);
    data.v[i] = parent < 0 ? Sqd : Vector6d(motionToChild(data.liMi[i], data.v[static_cast<size_t>(parent)]) + Sqd);
    T += 0.5 * data.v[i].dot(inertiaTimes(model.mass[i], model.first_moment[i], model.inertia_origin[i], data.v[i]));
    T += 0.5 * model.armature[ii] * qd[ii] * qd[ii];
  }
  return T;
}

double potentialEnergy(const Model& model, Data& data, const VecRef& q) {
  forwardKinematics(model, data, q);
  double V = 0.0;
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i)
    V -= model.mass[i] * model.gravity.dot(data.oMi[i].act(model.inertias[i].com));
  return V;
}

Eigen::Vector3d centerOfMass(const Model& model, Data& data, const VecRef& q) {
  forwardKinematics(model, data, q);
  double m = 0.0;
  Vector3d mc = Vector3d::Zero();
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i) {
    m += model.mass[i];
    mc += model.mass[i] * data.oMi[i].act(model.inertias[i].com);
  }
  return m > 0.0 ? Vector3d(mc / m) : Vector3d::Zero();
}

namespace {

// B = [v×*] I − I [v×] for a world inertia I = [[A, [h]], [−[h], m 1]] and v = [ω; v_l]: with W = [ω], V = [v_l],
// H = [h] (skew), B = [[−(AW + (AW)ᵀ + HV + (HV)ᵀ), (HW)ᵀ − HW + mV], [its transpose, 0]] (symmetric).
inline void coriolisComposite(const Matrix6d& I, const Vector6d& v, Matrix6d& B) {
  const Matrix3d W = skew(v.head<3>()), V = skew(v.tail<3>());
  const Matrix3d A = I.topLeftCorner<3, 3>(), H = I.topRightCorner<3, 3>();
  const double m = I(3, 3);
  const Matrix3d AW = A * W, HV = H * V, HW = H * W;
  B.topLeftCorner<3, 3>() = -(AW + AW.transpose() + HV + HV.transpose());
  const Matrix3d B12 = HW.transpose() - HW + m * V;
  B.topRightCorner<3, 3>() = B12;
  B.bottomLeftCorner<3, 3>() = B12.transpose();
  B.bottomRightCorner<3, 3>().setZero();
}

// The passes of the RNEA derivatives. With `solve_for_qdd` (ABA derivatives) the accelerations are not given:
// pass 1 runs with q̈ = 0, pass 2 gives M and the bias torques b, q̈ = M⁻¹(τ − b) (data.ddq, data.llt), and
// pass 3 adds the accelerations' share to the body accelerations and forces; otherwise q̈ = `qdd` from the start.
void rneaDerivativesCore(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd_or_tau,
                         const Matrix6Xd* fext, bool solve_for_qdd) {
  const auto n = static_cast<size_t>(model.nq);
  const Vector6d a0 = baseAcceleration(model);
  const Vector6d zero6 = Vector6d::Zero();
  data.dtau_dq.setZero();  // entries of joints on different branches stay zero
  data.dtau_dqd.setZero();
  data.M.setZero();
  // Pass 1 (forward, base coordinates): v_i = v_λ + S_i q̇_i, Ṡ_i = v_i × S_i, a_i = a_λ + S_i q̈_i + Ṡ_i q̇_i,
  // f_i = I_i a_i + v_i ×* I_i v_i − fext_i, h_i = I_i v_i, B_i, u_i = S_i × v_λ.
  for (size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    const int parent = model.parents[i];
    Placement& X = data.liMi[i];
    jointPlacement(model, i, q[ii], X);
    data.oMi[i] = parent < 0 ? X : data.oMi[static_cast<size_t>(parent)] * X;
    const Vector6d& S = data.oS[i] = worldAxis(model, i, data.oMi[i]);
    const Vector6d& v_par = parent < 0 ? zero6 : data.ov[static_cast<size_t>(parent)];
    const Vector6d& a_par = parent < 0 ? a0 : data.oa[static_cast<size_t>(parent)];
    data.ov[i] = v_par + S * qd[ii];
    data.odS[i] = crossMotion(data.ov[i], S);
    data.oa[i] = a_par + data.odS[i] * qd[ii];
    if (!solve_for_qdd) data.oa[i] += S * qdd_or_tau[ii];
    data.ou[i] = crossMotion(S, v_par);
    Matrix6d& I = data.oI[i];
    worldInertia(model, i, data.oMi[i], I);
    data.oIc[i] = I;
    data.oh[i].noalias() = I * data.ov[i];
    data.oF[i].noalias() = I * data.oa[i];
    data.oF[i] += crossForce(data.ov[i], data.oh[i]);
    if (fext != nullptr) data.oF[i] -= forceToParent(data.oMi[i], fext->col(ii));  // body-fixed wrench
    coriolisComposite(I, data.ov[i], data.oB[i]);
  }
  // Pass 2 (backward): sums over each subtree; M(i, k) = S_k·(Ic_i S_i) for k on the path to the root.
  for (size_t i = n; i-- > 0;) {
    const auto ii = static_cast<Eigen::Index>(i);
    data.oP[i].noalias() = data.oIc[i] * data.oS[i];
    for (int k = static_cast<int>(i); k >= 0; k = model.parents[static_cast<size_t>(k)])
      data.M(k, ii) = data.M(ii, k) = data.oS[static_cast<size_t>(k)].dot(data.oP[i]);
    data.M(ii, ii) += model.armature[ii];
    // ABA mode: the bias torques b(q, q̇) into data.nle (data.tau may be the caller's τ).
    (solve_for_qdd ? data.nle : data.tau)[ii] = data.oS[i].dot(data.oF[i]);
    const int parent = model.parents[i];
    if (parent < 0) continue;
    const auto pp = static_cast<size_t>(parent);
    data.oIc[pp] += data.oIc[i];
    data.oF[pp] += data.oF[i];
    data.oh[pp] += data.oh[i];
    data.oB[pp] += data.oB[i];
  }
  if (solve_for_qdd) {
    data.llt.compute(data.M);
    if (data.llt.info() != Eigen::Success)
      throw InputError("joint-space inertia matrix of robot '" + model.name + "' is not positive definite");
    data.ddq = qdd_or_tau - data.nle;  // τ − b(q, q̇)
    data.llt.solveInPlace(data.ddq);
    data.tau = qdd_or_tau;
  } else {
    for (Eigen::Index i = 0; i < model.nq; ++i) data.tau[i] += model.armature[i] * qdd_or_tau[i];
  }
  const VecRef& qdd = solve_for_qdd ? VecRef(data.ddq) : qdd_or_tau;
  // Pass 3 (forward): c_i = S_i × a_λ − u_i × v_λ; with q̈ solved for, the accelerations' share Δa_i = Δa_λ + S_i q̈_i
  // of a_i and its force I_i Δa_i (kept in oDF, summed over the subtrees in pass 4).
  for (size_t i = 0; i < n; ++i) {
    const int parent = model.parents[i];
    const Vector6d& v_par = parent < 0 ? zero6 : data.ov[static_cast<size_t>(parent)];
    if (solve_for_qdd) {
      data.oDa[i] = data.oS[i] * qdd[static_cast<Eigen::Index>(i)];
      if (parent >= 0) data.oDa[i] += data.oDa[static_cast<size_t>(parent)];
      data.oa[i] += data.oDa[i];
      data.oDF[i].noalias() = data.oI[i] * data.oDa[i];
    }
    const Vector6d& a_par = parent < 0 ? a0 : data.oa[static_cast<size_t>(parent)];
    data.oc[i] = crossMotion(data.oS[i], a_par) - crossMotion(data.ou[i], v_par);
  }
  // Pass 4 (backward): the derivative entries of row i (columns on the path to the root) and of column i (rows
  // of the ancestors).
  for (size_t i = n; i-- > 0;) {
    const auto ii = static_cast<Eigen::Index>(i);
    const int parent = model.parents[i];
    if (solve_for_qdd) {
      data.oF[i] += data.oDF[i];  // oF holds the subtree sums of pass 2; oDF the subtree sums so far
      if (parent >= 0) data.oDF[static_cast<size_t>(parent)] += data.oDF[i];
    }
    const Vector6d& S = data.oS[i];
    const Vector6d& P = data.oP[i];
    const Vector6d Q = crossForce(S, data.oh[i]) - data.oB[i] * S;  // B symmetric: Bᵀ S = B S
    const Vector6d Psi = crossForce(S, data.oF[i]) - data.oIc[i] * data.oc[i] - crossForce(data.ou[i], data.oh[i]) -
                         data.oB[i] * data.ou[i];
    const Vector6d Omega = 2.0 * (data.oIc[i] * data.odS[i]) + data.oB[i] * S + crossForce(S, data.oh[i]);
    for (int k = static_cast<int>(i); k >= 0; k = model.parents[static_cast<size_t>(k)]) {
      const auto kk = static_cast<size_t>(k);
      data.dtau_dq(ii, k) = -data.oc[kk].dot(P) + data.ou[kk].dot(Q);
      data.dtau_dqd(ii, k) = 2.0 * data.odS[kk].dot(P) - data.oS[kk].dot(Q);
      if (k != static_cast<int>(i)) {  // column i of the ancestor rows k (joint i lies below k)
        data.dtau_dq(k, ii) = data.oS[kk].dot(Psi);
        data.dtau_dqd(k, ii) = data.oS[kk].dot(Omega);
      }
    }
  }
}

}  // namespace

void computeRneaDerivatives(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd,
                            const Matrix6Xd* fext) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  checkSize(model, data, qdd, "qdd");
  checkFext(model, fext);
  rneaDerivativesCore(model, data, q, qd, qdd, fext, false);
}

void computeAbaDerivatives(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& tau,
                           const Matrix6Xd* fext) {
  checkSize(model, data, q, "q");
  checkSize(model, data, qd, "qd");
  checkSize(model, data, tau, "tau");
  checkFext(model, fext);
  // q̈ = M⁻¹(τ − b(q, q̇)) ⇒ ∂q̈/∂x = −M⁻¹ ∂RNEA/∂x at (q, q̇, q̈) for x = q, q̇, and ∂q̈/∂τ = M⁻¹; q̈ itself from
  // the Cholesky factor of the M that the derivative passes build anyway (no separate ABA).
  rneaDerivativesCore(model, data, q, qd, tau, fext, true);
  data.Minv.setIdentity();
  data.llt.solveInPlace(data.Minv);
  data.ddq_dq.noalias() = -data.Minv * data.dtau_dq;
  data.ddq_dqd.noalias() = -data.Minv * data.dtau_dqd;
}

}  // namespace jointsim::multibody
