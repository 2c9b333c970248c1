#pragma once
/// \file
/// Rigid multibody algorithms on a (Model, Data) pair. All are O(nq) except CRBA and the Cholesky
/// solve; none allocates heap memory once Data is constructed. Vector arguments must have size nq
/// (checked: InputError otherwise).
///
/// External wrenches `fext` (optional, may be nullptr): column i is the wrench [n; f] applied to body i
/// by the environment, resolved in body frame i, moment about its origin [N·m; N].

#include "jointsim/multibody/data.hpp"

namespace jointsim::multibody {

using VecRef = Eigen::Ref<const Eigen::VectorXd>;

/// Placements of every body (data.liMi, data.oMi) and frame (data.oMf) at q.
void forwardKinematics(const Model& model, Data& data, const VecRef& q);

/// Recomputes data.oMf from data.oMi (after any algorithm that updated the body placements).
void updateFramePlacements(const Model& model, Data& data);

/// Recursive Newton–Euler inverse dynamics: τ = M(q) q̈ + C(q, q̇) q̇ + g(q) − Σ J_iᵀ fext_i.
/// Includes the armature term armature_i q̈_i. Result in data.tau.
const Eigen::VectorXd& rnea(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd,
                            const Matrix6Xd* fext = nullptr);

/// Gravity torques g(q) (the torques that hold the robot still). Result in data.g.
const Eigen::VectorXd& gravityTorques(const Model& model, Data& data, const VecRef& q);

/// Bias torques C(q, q̇) q̇ + g(q). Result in data.nle.
const Eigen::VectorXd& nonLinearEffects(const Model& model, Data& data, const VecRef& q, const VecRef& qd);

/// Composite-rigid-body algorithm: joint-space inertia M(q) including armature on the diagonal.
/// Result in data.M (both triangles filled).
const Eigen::MatrixXd& crba(const Model& model, Data& data, const VecRef& q);

/// Articulated-body algorithm: q̈ = FD(q, q̇, τ, fext). Result in data.ddq.
const Eigen::VectorXd& aba(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& tau,
                           const Matrix6Xd* fext = nullptr);

/// Analytic derivatives of inverse dynamics τ = RNEA(q, q̇, q̈, fext) in the base frame ([Carpentier2018]; body-fixed
/// external wrenches): data.dtau_dq = ∂τ/∂q, data.dtau_dqd = ∂τ/∂q̇, data.M = ∂τ/∂q̈ (with armature, both
/// triangles), data.tau = τ. No heap allocation. With D_i the subtree of joint i, Ic, F, h the sums over D_i of
/// the world spatial inertias, forces and momenta, B = Σ([v×*]I − I[v×]), u_k = S_k × v_λ(k),
/// c_k = S_k × a_λ(k) − u_k × v_λ(k) and Ṡ_k = v_k × S_k:
///   ∂τ_i/∂q_k = −c_k·(Ic_i S_i) + u_k·(S_i ×* h_i − B_i S_i),  ∂τ_i/∂q̇_k = 2 Ṡ_k·(Ic_i S_i) − S_k·(S_i ×* h_i − B_i S_i)
///     for k ancestor of i or i itself;
///   ∂τ_i/∂q_k = S_i·(S_k ×* F_k − Ic_k c_k − u_k ×* h_k − B_k u_k),  ∂τ_i/∂q̇_k = S_i·(2 Ic_k Ṡ_k + B_k S_k + S_k ×* h_k)
///     for k a descendant of i (zero for joints on other branches).
void computeRneaDerivatives(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& qdd,
                            const Matrix6Xd* fext = nullptr);

/// Analytic derivatives of forward dynamics q̈ = ABA(q, q̇, τ, fext): data.ddq_dq = ∂q̈/∂q = −M⁻¹ ∂τ/∂q,
/// data.ddq_dqd = ∂q̈/∂q̇ = −M⁻¹ ∂τ/∂q̇ (the RNEA derivatives at the computed q̈), data.Minv = ∂q̈/∂τ = M⁻¹,
/// data.ddq = q̈. No heap allocation.
void computeAbaDerivatives(const Model& model, Data& data, const VecRef& q, const VecRef& qd, const VecRef& tau,
                           const Matrix6Xd* fext = nullptr);

/// Forward dynamics by CRBA + Cholesky (independent cross-check of aba): q̈ = M⁻¹(τ − C q̇ − g + Jᵀfext).
/// Result in data.ddq; data.M and data.llt hold the factorised inertia.
const Eigen::VectorXd& forwardDynamicsCrba(const Model& model, Data& data, const VecRef& q, const VecRef& qd,
                                           const VecRef& tau, const Matrix6Xd* fext = nullptr);

/// Geometric Jacobian of a frame at q, "world aligned": rows 0–2 map q̇ to the linear velocity of the
/// frame origin, rows 3–5 to the angular velocity, both resolved in the base frame. Result in data.J.
const Matrix6Xd& frameJacobian(const Model& model, Data& data, const VecRef& q, int frame);

/// Kinetic energy ½ q̇ᵀ M(q) q̇ [J] (computed from body twists, plus ½ armature q̇²).
double kineticEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& qd);

/// Gravitational potential energy −Σ m_i gᵀ c_i [J], zero when every CoM is at the base origin height.
double potentialEnergy(const Model& model, Data& data, const VecRef& q);

/// Total centre of mass of the moving bodies in the base frame [m] (updates kinematics).
Eigen::Vector3d centerOfMass(const Model& model, Data& data, const VecRef& q);

}  // namespace jointsim::multibody
