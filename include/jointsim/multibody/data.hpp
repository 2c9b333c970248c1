#pragma once
/// \file
/// Mutable workspace of the multibody algorithms. Construct one Data per Model (and per thread); the
/// algorithms then run without heap allocation.

#include <vector>

#include <Eigen/Cholesky>

#include "jointsim/multibody/model.hpp"

namespace jointsim::multibody {

struct Data {
  explicit Data(const Model& model);

  int nq;  ///< size of the model this workspace was made for

  // Kinematics (forwardKinematics and the dynamics algorithms update them; crba only liMi).
  std::vector<Placement> liMi;  ///< (nq) body frame i in its parent body frame
  std::vector<Placement> oMi;   ///< (nq) body frame i in the base frame
  std::vector<Placement> oMf;   ///< (nframes) frames in the base frame (forwardKinematics / updateFrames)

  // Recursive Newton–Euler / ABA quantities, resolved in the body frames.
  std::vector<Vector6d> v;   ///< (nq) body twists [ω; v]
  std::vector<Vector6d> a;   ///< (nq) spatial accelerations (gravity included as a base acceleration)
  std::vector<Vector6d> f;   ///< (nq) joint wrenches [n; f] transmitted from parent to body
  std::vector<Vector6d> c;   ///< (nq) velocity-product accelerations v × S q̇ (ABA)
  std::vector<Matrix6d> IA;  ///< (nq) articulated-body inertias (ABA)
  std::vector<Vector6d> pA;  ///< (nq) articulated bias forces (ABA)
  std::vector<Vector6d> U;   ///< (nq) IA S (ABA)
  Eigen::VectorXd D;         ///< (nq) S^T IA S + armature (ABA)
  Eigen::VectorXd u;         ///< (nq) τ - S^T pA (ABA)

  // Composite rigid bodies (CRBA) as (m, h, I_O) in body frames.
  std::vector<double> Yc_m;
  std::vector<Eigen::Vector3d> Yc_h;
  std::vector<Eigen::Matrix3d> Yc_I;

  // Results.
  Eigen::VectorXd tau;              ///< (nq) inverse-dynamics torques (rnea)
  Eigen::VectorXd g;                ///< (nq) gravity torques (gravityTorques)
  Eigen::VectorXd nle;              ///< (nq) bias torques C(q,q̇)q̇ + g(q) (nonLinearEffects)
  Eigen::VectorXd ddq;              ///< (nq) accelerations (aba / forwardDynamicsCrba)
  Eigen::MatrixXd M;                ///< (nq×nq) joint-space inertia (crba), full symmetric
  Eigen::LLT<Eigen::MatrixXd> llt;  ///< Cholesky factor of M (forwardDynamicsCrba)
  Matrix6Xd J;                      ///< (6×nq) frame Jacobian (frameJacobian)
  Eigen::VectorXd zeros;            ///< (nq) zero vector used internally

  // Derivatives (computeRneaDerivatives, computeAbaDerivatives).
  Eigen::MatrixXd dtau_dq;   ///< (nq×nq) ∂τ/∂q of RNEA
  Eigen::MatrixXd dtau_dqd;  ///< (nq×nq) ∂τ/∂q̇ of RNEA
  Eigen::MatrixXd ddq_dq;    ///< (nq×nq) ∂q̈/∂q of ABA
  Eigen::MatrixXd ddq_dqd;   ///< (nq×nq) ∂q̈/∂q̇ of ABA
  Eigen::MatrixXd Minv;      ///< (nq×nq) M⁻¹ = ∂q̈/∂τ (computeAbaDerivatives)
  // World-frame workspace, base coordinates about the base origin: joint motion subspaces S_i, twists,
  // accelerations (gravity as base acceleration), composite inertias, forces, momenta, B = [v×*]I − I[v×] and
  // the per-joint vectors of the derivative recursions.
  std::vector<Vector6d> oS, ov, oa, oF, oh, ou, oc, odS, oP, oDa, oDF;
  std::vector<Matrix6d> oI, oIc, oB;
};

}  // namespace jointsim::multibody
