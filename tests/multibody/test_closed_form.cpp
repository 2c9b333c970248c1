// Multibody algorithms against closed-form dynamics: a single pendulum and the two-link planar arm
// (Spong, Hutchinson & Vidyasagar, Robot Modeling and Control, §7.3), both with prismatic-joint and
// off-axis variants.
#include <cmath>

#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "test_util.hpp"

using namespace jointsim::multibody;
using jointsim::test::MatricesNear;

namespace {
constexpr double kG = 9.81;

// Planar arm in the x–y plane, joints about z, gravity along −y, link frames at the joints.
Model twoLinkArm(double m1, double l1, double lc1, double I1, double m2, double lc2, double I2) {
  ModelBuilder b("arm2");
  b.setGravity({0, -kG, 0});
  JointSpec j1{"j1", JointType::Revolute, Placement{}, Eigen::Vector3d::UnitZ(), 0.0, {}};
  BodyInertia b1{m1, {lc1, 0, 0}, Eigen::Vector3d(0.3 * I1, I1 * 0.9, I1).asDiagonal()};
  b.addLink("base", j1, "link1", b1);
  JointSpec j2 = j1;
  j2.name = "j2";
  j2.origin.p = {l1, 0, 0};
  BodyInertia b2{m2, {lc2, 0, 0}, Eigen::Vector3d(0.2 * I2, I2 * 0.95, I2).asDiagonal()};
  b.addLink("link1", j2, "link2", b2);
  return b.build();
}
}  // namespace

TEST(ClosedForm, SinglePendulum) {
  const double m = 2.5, l = 0.4, Izz = 0.03, armature = 0.07;
  ModelBuilder b("pendulum");
  b.setGravity({0, -kG, 0});
  b.addLink("base", {"j", JointType::Revolute, {}, Eigen::Vector3d::UnitZ(), armature, {}}, "bob",
            {m, {l, 0, 0}, Eigen::Vector3d(0.01, 0.02, Izz).asDiagonal()});
  const Model model = b.build();
  Data data(model);
  for (double q : {-2.0, -0.3, 0.0, 0.7, 1.9}) {
    Eigen::VectorXd Q(1), QD(1), QDD(1);
    Q << q;
    QD << 1.3;
    QDD << -0.8;
    const double M = Izz + m * l * l + armature;
    const double g = m * kG * l * std::cos(q);
    EXPECT_NEAR(crba(model, data, Q)(0, 0), M, 1e-14);
    EXPECT_NEAR(gravityTorques(model, data, Q)[0], g, 1e-13);
    EXPECT_NEAR(rnea(model, data, Q, QD, QDD)[0], M * QDD[0] + g, 1e-13);  // no Coriolis for 1 DOF
    Eigen::VectorXd tau(1);
    tau << 0.4;
    EXPECT_NEAR(aba(model, data, Q, QD, tau)[0], (0.4 - g) / M, 1e-13);
    EXPECT_NEAR(kineticEnergy(model, data, Q, QD), 0.5 * M * 1.3 * 1.3, 1e-14);
    EXPECT_NEAR(potentialEnergy(model, data, Q), m * kG * l * std::sin(q), 1e-13);
  }
}

TEST(ClosedForm, TwoLinkPlanarArm) {
  const double m1 = 3.0, l1 = 0.7, lc1 = 0.3, I1 = 0.06, m2 = 2.0, lc2 = 0.2, I2 = 0.03;
  const Model model = twoLinkArm(m1, l1, lc1, I1, m2, lc2, I2);
  Data data(model);
  std::mt19937 rng(42);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = jointsim::test::randomVector(rng, 2, -3.1, 3.1);
    const Eigen::VectorXd qd = jointsim::test::randomVector(rng, 2, -4, 4);
    const Eigen::VectorXd qdd = jointsim::test::randomVector(rng, 2, -10, 10);
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    Eigen::Matrix2d M;
    M(0, 0) = m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2 * l1 * lc2 * c2) + I1 + I2;
    M(0, 1) = M(1, 0) = m2 * (lc2 * lc2 + l1 * lc2 * c2) + I2;
    M(1, 1) = m2 * lc2 * lc2 + I2;
    const double h = -m2 * l1 * lc2 * s2;
    Eigen::Vector2d C(h * (2 * qd[0] * qd[1] + qd[1] * qd[1]), -h * qd[0] * qd[0]);
    Eigen::Vector2d g((m1 * lc1 + m2 * l1) * kG * std::cos(q[0]) + m2 * lc2 * kG * std::cos(q[0] + q[1]),
                      m2 * lc2 * kG * std::cos(q[0] + q[1]));
    EXPECT_TRUE(MatricesNear(crba(model, data, q), M, 1e-13));
    EXPECT_TRUE(MatricesNear(gravityTorques(model, data, q), g, 1e-13));
    EXPECT_TRUE(MatricesNear(nonLinearEffects(model, data, q, qd), C + g, 1e-12));
    EXPECT_TRUE(MatricesNear(rnea(model, data, q, qd, qdd), M * qdd + C + g, 1e-12));
    // Tip position (end of link 2 has no frame here: check the link-2 frame origin instead).
    forwardKinematics(model, data, q);
    EXPECT_TRUE(MatricesNear(data.oMi[1].p, Eigen::Vector3d(l1 * std::cos(q[0]), l1 * std::sin(q[0]), 0), 1e-15));
  }
}

TEST(ClosedForm, PrismaticJointUnderGravity) {
  // A carriage sliding along an inclined axis in the x–z plane, carrying a revolute pendulum.
  const double m1 = 4.0, m2 = 1.5, l = 0.5, Izz = 0.02, incline = 0.4;
  ModelBuilder b("cart_pendulum");  // gravity −z
  JointSpec slide{"slide", JointType::Prismatic, {}, Eigen::Vector3d(std::cos(incline), 0, std::sin(incline)), 0, {}};
  b.addLink("base", slide, "cart", {m1, {0, 0, 0}, Eigen::Matrix3d::Identity() * 0.1});
  // Pendulum swings about y (in the x–z plane): com at (l, 0, 0) in its frame.
  b.addLink("cart", {"swing", JointType::Revolute, {}, Eigen::Vector3d::UnitY(), 0, {}}, "bob",
            {m2, {l, 0, 0}, Eigen::Vector3d(0.01, Izz, 0.01).asDiagonal()});
  const Model model = b.build();
  Data data(model);
  // Lagrangian: x_c = s e, bob at s e + l (cos φ, 0, −sin φ) (rotation about +y takes x toward −z).
  const Eigen::Vector3d e(std::cos(incline), 0, std::sin(incline));
  for (double phi : {-1.0, 0.2, 2.0}) {
    Eigen::VectorXd q(2);
    q << 0.3, phi;
    const Eigen::Vector3d dr(-l * std::sin(phi), 0, -l * std::cos(phi));  // ∂(bob)/∂φ
    Eigen::Matrix2d M;
    M(0, 0) = m1 + m2;
    M(0, 1) = M(1, 0) = m2 * e.dot(dr);
    M(1, 1) = m2 * l * l + Izz;
    const Eigen::Vector2d g((m1 + m2) * kG * e.z(), m2 * kG * dr.z());
    EXPECT_TRUE(MatricesNear(crba(model, data, q), M, 1e-13));
    EXPECT_TRUE(MatricesNear(gravityTorques(model, data, q), g, 1e-13));
  }
}
