// One algorithm against another on the shipped robots and on a branched tree with prismatic joints
// and arbitrary axes: RNEA vs CRBA columns, ABA vs RNEA round trip, ABA vs CRBA + Cholesky, external
// wrenches vs Jᵀf, Jacobian vs finite differences of forward kinematics, energy vs M.
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

using namespace jointsim::multibody;
using jointsim::test::MatricesNear;
using jointsim::test::randomVector;

namespace {

// A branched tree: a torso with two arms, one with a prismatic joint, skewed axes, fixed joints and
// armature, so that every code path of the algorithms is exercised.
Model branchedTree() {
  ModelBuilder b("tree");
  b.setGravity({0.3, -1.2, -9.7});
  auto inertia = [](double m, Eigen::Vector3d c, double a, double bb, double cc) {
    Eigen::Matrix3d I;
    const double s = 0.2 * std::min({a, bb, cc});  // small products of inertia keep I positive definite
    I << a, s, -0.5 * s, s, bb, 0.7 * s, -0.5 * s, 0.7 * s, cc;
    return BodyInertia{m, c, I};
  };
  Placement X;
  X.R = rotationFromRpy(0.1, -0.4, 0.7);
  X.p = {0.1, 0.05, 0.3};
  b.addLink("base", {"torso", JointType::Revolute, X, Eigen::Vector3d(0.2, 0.1, 1.0), 0.05, {}}, "torso",
            inertia(5.0, {0.0, 0.02, 0.2}, 0.3, 0.35, 0.2));
  X.R = rotationFromRpy(-0.5, 0.2, 0.1);
  X.p = {0.2, 0.15, 0.4};
  b.addLink("torso", {"l_shoulder", JointType::Revolute, X, Eigen::Vector3d(1, -0.3, 0.2), 0.02, {}}, "l_upper",
            inertia(2.0, {0.1, 0.0, -0.05}, 0.05, 0.06, 0.04));
  X.R = rotationFromRpy(0.3, 0.3, -0.2);
  X.p = {0.3, 0, 0};
  b.addLink("l_upper", {"l_slide", JointType::Prismatic, X, Eigen::Vector3d(0.1, 1, 0.3), 0.5, {}}, "l_lower",
            inertia(1.2, {0.05, 0.1, 0.0}, 0.03, 0.02, 0.04));
  X.R = rotationFromRpy(0.0, 0.5, 0.0);
  X.p = {0.0, 0.1, 0.05};
  b.addLink("l_lower", {"l_fixed", JointType::Fixed, X, Eigen::Vector3d::UnitZ(), 0, {}}, "l_tool",
            inertia(0.4, {0.02, 0.0, 0.03}, 0.005, 0.006, 0.004));
  X.R = rotationFromRpy(0.7, -0.1, 0.3);
  X.p = {-0.2, 0.15, 0.4};
  b.addLink("torso", {"r_shoulder", JointType::Revolute, X, Eigen::Vector3d(0, 1, 0), 0.0, {}}, "r_upper",
            inertia(2.2, {0.12, 0.01, 0.0}, 0.05, 0.07, 0.05));
  X.R = rotationFromRpy(-0.2, 0.0, 0.4);
  X.p = {0.35, 0.0, 0.02};
  b.addLink("r_upper", {"r_elbow", JointType::Revolute, X, Eigen::Vector3d(0, 0, 1), 0.01, {}}, "r_lower",
            inertia(1.0, {0.15, 0.0, 0.0}, 0.01, 0.03, 0.03));
  X.R = Eigen::Matrix3d::Identity();
  X.p = {0.3, 0.0, 0.0};
  b.addFrame("r_hand", "r_lower", X);
  return b.build();
}

struct NamedModel {
  std::string name;
  Model model;
};

std::vector<NamedModel> allModels() {
  using jointsim::test::sourcePath;
  return {{"ur5_yaml", loadRobot(sourcePath("config/robots/ur5.yaml"))},
          {"ur5_urdf", loadRobot(sourcePath("config/robots/ur5.urdf"))},
          {"irb140", loadRobot(sourcePath("config/robots/irb140.yaml"))},
          {"tree", branchedTree()}};
}

class CrossCheck : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    models_ = allModels();
    entry_ = &models_[static_cast<size_t>(GetParam())];
  }
  const Model& model() const { return entry_->model; }
  std::vector<NamedModel> models_;
  const NamedModel* entry_ = nullptr;
  std::mt19937 rng_{1234};
};

}  // namespace

TEST_P(CrossCheck, CrbaColumnsEqualRneaWithUnitAcceleration) {
  Data data(model());
  const auto n = model().nq;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Eigen::MatrixXd M = crba(model(), data, q);
    const Eigen::VectorXd g = gravityTorques(model(), data, q);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::VectorXd col = rnea(model(), data, q, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Unit(n, i)) - g;
      EXPECT_TRUE(MatricesNear(M.col(i), col, 1e-12)) << entry_->name << " column " << i;
    }
    EXPECT_TRUE(MatricesNear(M, M.transpose(), 0.0)) << "M not symmetric";
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << entry_->name << ": M not positive definite";
  }
}

TEST_P(CrossCheck, AbaInvertsRnea) {
  Data data(model());
  const auto n = model().nq;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Eigen::VectorXd qd = randomVector(rng_, n, -3, 3);
    const Eigen::VectorXd qdd = randomVector(rng_, n, -10, 10);
    const Eigen::VectorXd tau = rnea(model(), data, q, qd, qdd);
    EXPECT_TRUE(MatricesNear(aba(model(), data, q, qd, tau), qdd, 1e-10)) << entry_->name;
    EXPECT_TRUE(MatricesNear(forwardDynamicsCrba(model(), data, q, qd, tau), qdd, 1e-10)) << entry_->name;
  }
}

TEST_P(CrossCheck, AbaMatchesCrbaCholeskyWithExternalWrenches) {
  Data data(model());
  const auto n = model().nq;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Eigen::VectorXd qd = randomVector(rng_, n, -2, 2);
    const Eigen::VectorXd tau = randomVector(rng_, n, -20, 20);
    Matrix6Xd fext(6, n);
    for (Eigen::Index i = 0; i < n; ++i) fext.col(i) = randomVector(rng_, 6, -5, 5);
    const Eigen::VectorXd a1 = aba(model(), data, q, qd, tau, &fext);
    const Eigen::VectorXd a2 = forwardDynamicsCrba(model(), data, q, qd, tau, &fext);
    EXPECT_TRUE(MatricesNear(a1, a2, 1e-9)) << entry_->name;
  }
}

TEST_P(CrossCheck, ExternalWrenchEqualsJacobianTransposeForce) {
  // A world-frame force F at the tip frame origin enters RNEA as −Jᵀ[F; 0]; a pure world moment N as −Jᵀ[0; N].
  Data data(model());
  const auto n = model().nq;
  const int tip = model().frameIndex(model().tip_frame);
  const Frame& fr = model().frames[static_cast<size_t>(tip)];
  if (fr.joint < 0) GTEST_SKIP();
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Eigen::VectorXd qd = randomVector(rng_, n, -2, 2);
    const Eigen::VectorXd qdd = randomVector(rng_, n, -5, 5);
    const Eigen::Vector3d F = randomVector(rng_, 3, -10, 10), N = randomVector(rng_, 3, -2, 2);
    const Matrix6Xd J = frameJacobian(model(), data, q, tip);
    const Placement oMb = data.oMi[static_cast<size_t>(fr.joint)];
    const Eigen::Vector3d p_tip_body = fr.placement.p;  // tip origin in the body frame
    // Body wrench about the body origin, body coordinates.
    const Eigen::Vector3d f_body = oMb.R.transpose() * F;
    Matrix6Xd fext = Matrix6Xd::Zero(6, n);
    fext.col(fr.joint).head<3>() = p_tip_body.cross(f_body) + oMb.R.transpose() * N;
    fext.col(fr.joint).tail<3>() = f_body;
    const Eigen::VectorXd tau_free = rnea(model(), data, q, qd, qdd);
    const Eigen::VectorXd tau_ext = rnea(model(), data, q, qd, qdd, &fext);
    Eigen::Matrix<double, 6, 1> w;
    w << F, N;
    EXPECT_TRUE(MatricesNear(tau_ext, tau_free - J.transpose() * w, 1e-11)) << entry_->name;
  }
}

TEST_P(CrossCheck, JacobianMatchesFiniteDifferencesOfKinematics) {
  Data data(model());
  const auto n = model().nq;
  const int tip = model().frameIndex(model().tip_frame);
  const double h = 1e-6;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Matrix6Xd J = frameJacobian(model(), data, q, tip);
    Matrix6Xd Jfd(6, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      forwardKinematics(model(), data, q + h * Eigen::VectorXd::Unit(n, i));
      const Placement plus = data.oMf[static_cast<size_t>(tip)];
      forwardKinematics(model(), data, q - h * Eigen::VectorXd::Unit(n, i));
      const Placement minus = data.oMf[static_cast<size_t>(tip)];
      Jfd.col(i).head<3>() = (plus.p - minus.p) / (2 * h);
      // Angular velocity from the rotation difference: log(R+ R−ᵀ)/(2h), resolved in the world.
      const Eigen::AngleAxisd aa(plus.R * minus.R.transpose());
      Jfd.col(i).tail<3>() = aa.axis() * aa.angle() / (2 * h);
    }
    EXPECT_TRUE(MatricesNear(J, Jfd, 1e-7)) << entry_->name;
  }
}

TEST_P(CrossCheck, KineticEnergyIsHalfQdMQd) {
  Data data(model());
  const auto n = model().nq;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
    const Eigen::VectorXd qd = randomVector(rng_, n, -3, 3);
    const double T = kineticEnergy(model(), data, q, qd);
    const Eigen::MatrixXd M = crba(model(), data, q);
    EXPECT_NEAR(T, 0.5 * qd.dot(M * qd), 1e-12 * std::max(1.0, T)) << entry_->name;
  }
}

TEST_P(CrossCheck, GravityTorqueIsGradientOfPotentialEnergy) {
  Data data(model());
  const auto n = model().nq;
  const double h = 1e-6;
  const Eigen::VectorXd q = randomVector(rng_, n, -3, 3);
  const Eigen::VectorXd g = gravityTorques(model(), data, q);
  Eigen::VectorXd grad(n);
  for (Eigen::Index i = 0; i < n; ++i)
    grad[i] = (potentialEnergy(model(), data, q + h * Eigen::VectorXd::Unit(n, i)) -
               potentialEnergy(model(), data, q - h * Eigen::VectorXd::Unit(n, i))) /
              (2 * h);
  EXPECT_TRUE(MatricesNear(g, grad, 1e-7)) << entry_->name;
}

TEST_P(CrossCheck, CoriolisMatrixPropertyPowerBalance) {
  // d/dt(T + V) = q̇ᵀτ along any motion: check with a central difference in time of the energy
  // along q(t) = q0 + q̇0 t + ½ q̈0 t², where τ = RNEA(q, q̇, q̈).
  Data data(model());
  const auto n = model().nq;
  const Eigen::VectorXd q0 = randomVector(rng_, n, -3, 3);
  const Eigen::VectorXd qd0 = randomVector(rng_, n, -2, 2);
  const Eigen::VectorXd qdd0 = randomVector(rng_, n, -4, 4);
  const double h = 1e-5;
  auto energy = [&](double t) {
    const Eigen::VectorXd q = q0 + qd0 * t + 0.5 * qdd0 * t * t;
    const Eigen::VectorXd qd = qd0 + qdd0 * t;
    return kineticEnergy(model(), data, q, qd) + potentialEnergy(model(), data, q);
  };
  const double dEdt = (energy(h) - energy(-h)) / (2 * h);
  const double power = qd0.dot(rnea(model(), data, q0, qd0, qdd0));
  EXPECT_NEAR(dEdt, power, 1e-6 * std::max(1.0, std::abs(power))) << entry_->name;
}

namespace {
std::string robotName(const ::testing::TestParamInfo<int>& info) {
  static const char* names[] = {"UR5yaml", "UR5urdf", "IRB140", "BranchedTree"};
  return names[info.param];
}
}  // namespace

INSTANTIATE_TEST_SUITE_P(Robots, CrossCheck, ::testing::Values(0, 1, 2, 3), robotName);

// Was: Data's Cholesky member was constructed without a factorisation, so its status was an uninitialised
// enum, and copying a Data (as every tracking and RobotR3 run does) read it: undefined behaviour that UBSan
// reports (this test fails under scripts/sanitize.sh on a build without the fix). A copy of a fresh Data
// has a defined status and gives the same forward dynamics as ABA.
TEST(DataCopy, FreshDataCopiesWithADefinedCholeskyStatus) {
  const Model model = loadRobot(jointsim::test::sourcePath("config/robots/ur5.yaml"));
  const Data fresh(model);
  Data copy = fresh;  // NOLINT(performance-unnecessary-copy-initialization): the copy is the point
  EXPECT_EQ(copy.llt.info(), Eigen::Success);
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(model.nq, -0.4, 0.9);
  const Eigen::VectorXd qd = Eigen::VectorXd::Constant(model.nq, 0.2);
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(model.nq, 1.0, -2.0);
  Data other(model);
  EXPECT_TRUE(MatricesNear(forwardDynamicsCrba(model, copy, q, qd, tau), aba(model, other, q, qd, tau), 1e-10));
}
