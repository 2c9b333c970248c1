// Analytic derivatives of RNEA and ABA against central differences of the algorithms themselves (UR5, RobotR3 and a
// branched tree with revolute joints about general axes, a prismatic joint and armature, with and without
// external wrenches), and ∂ABA = −M⁻¹ ∂RNEA with M⁻¹ = ∂q̈/∂τ.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

using namespace jointsim::multibody;

namespace {

/// A tree: base → a (revolute, oblique axis) → b (revolute z) and base → a → c (prismatic) → d (revolute x),
/// with armature on two joints: two branches below a.
Model tree() {
  ModelBuilder b("tree");
  auto body = [](double m, Eigen::Vector3d c, double Ix, double Iy, double Iz) {
    BodyInertia I;
    I.mass = m;
    I.com = c;
    I.inertia = Eigen::Vector3d(Ix, Iy, Iz).asDiagonal();
    return I;
  };
  JointSpec ja;
  ja.name = "ja";
  ja.origin.p = {0.1, 0.0, 0.3};
  ja.axis = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  ja.armature = 0.05;
  b.addLink("base", ja, "a", body(3.0, {0.05, 0.02, 0.2}, 0.05, 0.06, 0.02));
  JointSpec jb;
  jb.name = "jb";
  jb.origin.p = {0.0, 0.1, 0.4};
  jb.origin.R = rotationFromRpy(0.3, -0.4, 0.2);
  jb.axis = Eigen::Vector3d::UnitZ();
  b.addLink("a", jb, "b", body(1.5, {0.2, 0.0, 0.01}, 0.01, 0.03, 0.03));
  JointSpec jc;
  jc.name = "jc";
  jc.type = JointType::Prismatic;
  jc.origin.p = {0.0, -0.1, 0.35};
  jc.axis = Eigen::Vector3d(1.0, 0.5, 0.2).normalized();
  jc.armature = 0.2;
  b.addLink("a", jc, "c", body(2.0, {0.0, 0.0, 0.05}, 0.02, 0.02, 0.01));
  JointSpec jd;
  jd.name = "jd";
  jd.origin.p = {0.1, 0.0, 0.1};
  jd.axis = Eigen::Vector3d::UnitX();
  b.addLink("c", jd, "d", body(0.7, {0.0, 0.1, 0.0}, 0.004, 0.002, 0.004));
  return b.build();
}

struct Point {
  Eigen::VectorXd q, qd, qdd, tau;
  Matrix6Xd fext;
};

Point point(const Model& m, unsigned seed) {
  std::srand(seed);
  Point p;
  p.q = Eigen::VectorXd::Random(m.nq);
  p.qd = 2.0 * Eigen::VectorXd::Random(m.nq);
  p.qdd = 3.0 * Eigen::VectorXd::Random(m.nq);
  p.tau = 10.0 * Eigen::VectorXd::Random(m.nq);
  p.fext = 5.0 * Matrix6Xd::Random(6, m.nq);
  return p;
}

/// Central differences of x ↦ fun(x) (a vector function), step h per coordinate.
template <class F>
Eigen::MatrixXd central(F fun, const Eigen::VectorXd& x, double h) {
  const Eigen::Index n = x.size();
  Eigen::MatrixXd J(fun(x).size(), n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    J.col(j) = (fun(xp) - fun(xm)) / (2.0 * h);
  }
  return J;
}

void expectClose(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& fd, const char* what) {
  const double scale = std::max(1.0, fd.cwiseAbs().maxCoeff());
  EXPECT_LE((analytic - fd).cwiseAbs().maxCoeff(), 1e-6 * scale) << what << "\nanalytic\n"
                                                                 << analytic << "\nfd\n"
                                                                 << fd;
}

void checkModel(const Model& m) {
  Data d(m), ref(m);
  for (unsigned seed : {1u, 2u, 3u})
    for (bool with_fext : {false, true}) {
      const Point p = point(m, seed);
      const Matrix6Xd* fext = with_fext ? &p.fext : nullptr;
      // RNEA derivatives.
      computeRneaDerivatives(m, d, p.q, p.qd, p.qdd, fext);
      auto rq = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(rnea(m, ref, x, p.qd, p.qdd, fext)); };
      auto rv = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(rnea(m, ref, p.q, x, p.qdd, fext)); };
      expectClose(d.dtau_dq, central(rq, p.q, 1e-6), "dtau/dq");
      expectClose(d.dtau_dqd, central(rv, p.qd, 1e-6), "dtau/dqd");
      expectClose(d.M, crba(m, ref, p.q), "M");
      expectClose(d.tau, rnea(m, ref, p.q, p.qd, p.qdd, fext), "tau");
      // ABA derivatives.
      computeAbaDerivatives(m, d, p.q, p.qd, p.tau, fext);
      auto aq = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(aba(m, ref, x, p.qd, p.tau, fext)); };
      auto av = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(aba(m, ref, p.q, x, p.tau, fext)); };
      auto at = [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(aba(m, ref, p.q, p.qd, x, fext)); };
      expectClose(d.ddq_dq, central(aq, p.q, 1e-6), "dqdd/dq");
      expectClose(d.ddq_dqd, central(av, p.qd, 1e-6), "dqdd/dqd");
      expectClose(d.Minv, central(at, p.tau, 1e-3), "Minv");  // q̈ is affine in τ
      // ∂ABA = −M⁻¹ ∂RNEA at q̈ = ABA(q, q̇, τ), from a separate RNEA-derivative call.
      const Eigen::VectorXd qdd = aba(m, ref, p.q, p.qd, p.tau, fext);
      Data r(m);
      computeRneaDerivatives(m, r, p.q, p.qd, qdd, fext);
      const Eigen::MatrixXd Minv = r.M.inverse();
      expectClose(d.ddq_dq, -Minv * r.dtau_dq, "dqdd/dq = -M^-1 dtau/dq");
      expectClose(d.ddq_dqd, -Minv * r.dtau_dqd, "dqdd/dqd = -M^-1 dtau/dqd");
    }
}

TEST(Derivatives, Ur5RneaAndAbaAgainstCentralDifferences) {
  checkModel(loadRobot(jointsim::test::sourcePath("config/robots/ur5.yaml")));
}

TEST(Derivatives, RobotR3AndIrb140AgainstCentralDifferences) {
  checkModel(loadRobot(jointsim::test::sourcePath("config/robots/robotr3.yaml")));
  checkModel(loadRobot(jointsim::test::sourcePath("config/robots/irb140.yaml")));
}

TEST(Derivatives, AbaDerivativesAcceptTheTorquesOfTheSameWorkspace) {
  // rnea(...) then computeAbaDerivatives(..., data.tau): the torques live in the workspace the passes write.
  const Model m = loadRobot(jointsim::test::sourcePath("config/robots/ur5.yaml"));
  Data d(m);
  const Point p = point(m, 5);
  rnea(m, d, p.q, p.qd, p.qdd);
  computeAbaDerivatives(m, d, p.q, p.qd, d.tau);
  EXPECT_LE((d.ddq - p.qdd).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Derivatives, BranchedTreeWithPrismaticJointAndArmature) {
  const Model m = tree();
  ASSERT_EQ(m.nq, 4);
  ASSERT_EQ(m.parents, (std::vector<int>{-1, 0, 0, 2}));
  checkModel(m);
  // Joints on different branches (jb below a; jc, jd below a on the other branch) do not act on each other.
  Data d(m);
  const Point p = point(m, 9);
  computeRneaDerivatives(m, d, p.q, p.qd, p.qdd);
  EXPECT_EQ(d.dtau_dq(1, 2), 0.0);
  EXPECT_EQ(d.dtau_dqd(3, 1), 0.0);
  EXPECT_EQ(d.M(1, 3), 0.0);
}

}  // namespace
