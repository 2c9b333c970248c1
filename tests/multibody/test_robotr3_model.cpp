// Manutec r3 ([MSL, RobotR3.FullRobot]) multibody model config/robots/robotr3.yaml against the data of
// [MSL, RobotR3.Utilities.MechanicalStructure] (moving mass) and our computed check values (joint frames, load
// CoM, static holding torques; docs/validation.md).
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

using namespace jointsim::multibody;
using jointsim::test::MatricesNear;
using jointsim::test::sourcePath;

namespace {
constexpr double kPi = 3.14159265358979323846;

Model loadR3() { return loadRobot(sourcePath("config/robots/robotr3.yaml")); }

// FullRobot start angles ([MSL, RobotR3.FullRobot]).
Eigen::VectorXd startAngles() {
  Eigen::VectorXd q(6);
  q << -60, 20, 90, 0, -110, 0;
  return q * (kPi / 180.0);
}

struct JointCheck {
  Eigen::Vector3d origin0, axis0, originStart, axisStart;
};

// Our computed check values: joint origin/axis in world coordinates at q = 0 and at q = q_start.
std::vector<JointCheck> jointChecks() {
  using V = Eigen::Vector3d;
  return {
      {V(0, 0.351, 0), V(0, 1, 0), V(0, 0.351, 0), V(0, 1, 0)},
      {V(0, 0.675, 0.3), V(1, 0, 0), V(-0.259808, 0.675, 0.15), V(0.5, 0, 0.866025)},
      {V(0, 1.325, 0.3), V(1, 0, 0), V(-0.452336, 1.285800, 0.261157), V(0.5, 0, 0.866025)},
      {V(0, 1.739, 0.145), V(0, 1, 0), V(-0.835159, 1.289856, 0.482179), V(-0.813798, -0.342020, 0.469846)},
      {V(0, 1.925, 0.145), V(1, 0, 0), V(-0.986526, 1.226240, 0.569571), V(0.5, 0, 0.866025)},
      {V(0, 2.05, 0.145), V(0, 1, 0), V(-0.986526, 1.351240, 0.569571), V(0, 1, 0)},
  };
}

// The document prints 6 decimals: allow half a unit of the last digit plus rounding.
constexpr double kDocTol = 6e-7;
}  // namespace

TEST(RobotR3Model, StructureGravityAndMass) {
  const Model model = loadR3();
  ASSERT_EQ(model.nq, 6);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(model.joint_names[static_cast<size_t>(j)], "r" + std::to_string(j + 1));
    EXPECT_EQ(model.body_names[static_cast<size_t>(j)], "b" + std::to_string(j + 1));
    EXPECT_EQ(model.parents[static_cast<size_t>(j)], j - 1);
    EXPECT_EQ(model.joint_types[static_cast<size_t>(j)], JointType::Revolute);
    EXPECT_EQ(model.armature[j], 0.0);
  }
  EXPECT_EQ(model.base_name, "b0");
  EXPECT_EQ(model.tip_frame, "load");
  EXPECT_TRUE(MatricesNear(model.gravity, Eigen::Vector3d(0, -9.81, 0), 0.0));
  // Moving mass b1..load (derived from [MSL, RobotR3.Utilities.MechanicalStructure]):
  // 1 + 56.5 + 26.4 + 28.7 + 5.2 + 0.5 + 15 = 133.3 kg.
  double m = 0.0;
  for (double mi : model.mass) m += mi;
  EXPECT_NEAR(m, 133.3, 1e-12);
  // The load is merged into b6: 0.5 kg at (0.05, 0.05, 0.05) + 15 kg at (0.1, 0.25, 0.1).
  EXPECT_NEAR(model.mass[5], 15.5, 1e-12);
  EXPECT_TRUE(MatricesNear(model.inertias[5].com,
                           (0.5 * Eigen::Vector3d(0.05, 0.05, 0.05) + 15.0 * Eigen::Vector3d(0.1, 0.25, 0.1)) / 15.5,
                           1e-14));
  // b2's tensor entry I21 = -0.46 is used as it is ([MSL, RobotR3.Utilities.MechanicalStructure]).
  EXPECT_DOUBLE_EQ(model.inertias[1].inertia(1, 0), -0.46);
  EXPECT_DOUBLE_EQ(model.inertias[1].inertia(0, 1), -0.46);
}

TEST(RobotR3Model, JointFramesAtZeroPosture) {
  const Model model = loadR3();
  Data data(model);
  forwardKinematics(model, data, Eigen::VectorXd::Zero(6));
  const auto checks = jointChecks();
  for (int j = 0; j < 6; ++j) {
    SCOPED_TRACE("joint r" + std::to_string(j + 1));
    const Placement& X = data.oMi[static_cast<size_t>(j)];
    EXPECT_TRUE(MatricesNear(X.p, checks[static_cast<size_t>(j)].origin0, 1e-12));
    EXPECT_TRUE(MatricesNear(X.R * model.axes[static_cast<size_t>(j)], checks[static_cast<size_t>(j)].axis0, 1e-12));
    // Joint frame = link frame b_j.
    const Placement& F = data.oMf[static_cast<size_t>(model.frameIndex("b" + std::to_string(j + 1)))];
    EXPECT_TRUE(MatricesNear(F.p, checks[static_cast<size_t>(j)].origin0, 1e-12));
  }
  // Tool flange (load frame) and load CoM at q = 0.
  const Placement& L = data.oMf[static_cast<size_t>(model.frameIndex("load"))];
  EXPECT_TRUE(MatricesNear(L.p, Eigen::Vector3d(0, 2.05, 0.145), 1e-12));
  EXPECT_TRUE(MatricesNear(L.act(Eigen::Vector3d(0.1, 0.25, 0.1)), Eigen::Vector3d(0.1, 2.3, 0.245), 1e-12));
}

TEST(RobotR3Model, JointFramesAtStartPosture) {
  const Model model = loadR3();
  Data data(model);
  forwardKinematics(model, data, startAngles());
  const auto checks = jointChecks();
  for (int j = 0; j < 6; ++j) {
    SCOPED_TRACE("joint r" + std::to_string(j + 1));
    const Placement& X = data.oMi[static_cast<size_t>(j)];
    EXPECT_TRUE(MatricesNear(X.p, checks[static_cast<size_t>(j)].originStart, kDocTol));
    EXPECT_TRUE(
        MatricesNear(X.R * model.axes[static_cast<size_t>(j)], checks[static_cast<size_t>(j)].axisStart, kDocTol));
  }
  const Placement& L = data.oMf[static_cast<size_t>(model.frameIndex("load"))];
  EXPECT_TRUE(MatricesNear(L.p, checks[5].originStart, kDocTol));
  EXPECT_TRUE(
      MatricesNear(L.act(Eigen::Vector3d(0.1, 0.25, 0.1)), Eigen::Vector3d(-1.023128, 1.601240, 0.706173), kDocTol));
}

TEST(RobotR3Model, GravityHoldingTorquesAtStartPosture) {
  // Our computed check values (docs/validation.md): G_j = dV/dq_j, the torque the drive must deliver to hold
  // the arm (tau_j = G_j).
  // jointsim's gravityTorques is the holding torque g(q) = dV/dq: same sign convention.
  const Model model = loadR3();
  Data data(model);
  const Eigen::VectorXd q = startAngles();
  Eigen::VectorXd G(6);
  G << 0.0, -460.573448, -256.400068, 14.058037, -14.960250, 0.0;
  const Eigen::VectorXd g = gravityTorques(model, data, q);
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(g[j], G[j], kDocTol) << "axis " << j + 1;
  // Independent check of the sign: central differences of the potential energy.
  Data d2(model);
  for (int j = 0; j < 6; ++j) {
    const double h = 1e-6;
    Eigen::VectorXd qp = q, qm = q;
    qp[j] += h;
    qm[j] -= h;
    const double dV = (potentialEnergy(model, d2, qp) - potentialEnergy(model, d2, qm)) / (2 * h);
    EXPECT_NEAR(dV, g[j], 1e-5) << "axis " << j + 1;
  }
  // Static equilibrium: rnea with q̇ = q̈ = 0 gives the same torques.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(6);
  EXPECT_TRUE(MatricesNear(rnea(model, data, q, zero, zero), G, 1e-8 * 500));
}

TEST(RobotR3Model, RaisedB1TransverseInertiaHasNoEffectOnJointDynamics) {
  // The file raises b1's Ixx, Izz from 0.001 to 0.58 (triangle inequality); b1 only rotates about its y
  // axis, so M, C q̇ + g and the joint torques must not depend on them.
  const Model model = loadR3();
  EXPECT_DOUBLE_EQ(model.inertias[0].inertia(1, 1), 1.16);
  Model other = model;
  other.inertias[0].inertia.diagonal() << 7.0, 1.16, 3.0;  // any other transverse values
  other.updateDerived();
  Data d1(model), d2(other);
  std::mt19937 rng(42);
  for (int k = 0; k < 5; ++k) {
    const Eigen::VectorXd q = jointsim::test::randomVector(rng, 6, -kPi, kPi);
    const Eigen::VectorXd qd = jointsim::test::randomVector(rng, 6, -3, 3);
    const Eigen::VectorXd qdd = jointsim::test::randomVector(rng, 6, -15, 15);
    EXPECT_TRUE(MatricesNear(crba(model, d1, q), crba(other, d2, q), 1e-12));
    EXPECT_TRUE(MatricesNear(rnea(model, d1, q, qd, qdd), rnea(other, d2, q, qd, qdd), 1e-12));
  }
  // Joint-1 inertia at q = 0 contains b1's Iyy = 1.16 kg m^2.
  Model no_b1 = model;
  no_b1.inertias[0].inertia.setZero();
  no_b1.updateDerived();
  Data d3(no_b1);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(6);
  EXPECT_NEAR(crba(model, d1, q0)(0, 0) - crba(no_b1, d3, q0)(0, 0), 1.16, 1e-12);
}
