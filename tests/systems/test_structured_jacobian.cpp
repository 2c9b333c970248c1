// The robot-with-drives Jacobian built from its structure (hub = multibody, one block per drive) and the block
// elimination of the Newton matrix: against plain difference quotients of the whole right-hand side, against
// the dense LU, and whole runs against CVODE's own dense difference-quotient Jacobian.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "sim/block_linear_solver.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

systems::RobotSystem twin() { return systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives.yaml")); }

/// A state away from equilibrium: joints moving, motors and gear states displaced, controllers off their rest.
Eigen::VectorXd movingState(const systems::RobotSystem& sys, unsigned seed) {
  Eigen::VectorXd q0(sys.dof());
  q0 << 0.3, -1.2, 1.2, -1.5, -1.5708, 0.2;
  q0.conservativeResize(sys.dof());
  Eigen::VectorXd y = sys.initialState(q0);
  std::srand(seed);
  const Eigen::VectorXd r = Eigen::VectorXd::Random(y.size());
  for (Eigen::Index i = 0; i < y.size(); ++i) y[i] *= 1.0 + 1e-3 * r[i];  // relative: keeps the scales
  y.segment(sys.dof(), sys.dof()) = 0.4 * r.head(sys.dof());
  return y;
}

/// Forward-difference increments of 1e-5 of each state's magnitude (at least 1e-2 of its unit): large enough that
/// rounding stays far below the compared accuracy, so that two ways of organising the same differences can be
/// compared column by column. (With CVODE's own increments, down to 1e-10 for a state at zero, the plain
/// quotients of the wrist accelerations carry rounding noise of 1e-3 of the column, the structured ones do not:
/// they difference the drive torque, not q̈.)
Eigen::VectorXd increments(const Eigen::VectorXd& y) { return 1e-5 * y.cwiseAbs().cwiseMax(1e-2); }

/// Forward differences of the whole right-hand side, one state at a time.
Eigen::MatrixXd plainDifferences(const sim::Plant& p, const sim::PlantState& state, double t, const Eigen::VectorXd& y,
                                 const Eigen::VectorXd& f, const Eigen::VectorXd& inc) {
  const Eigen::Index n = y.size();
  Eigen::MatrixXd J(n, n);
  Eigen::VectorXd yp = y, fp(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    yp[j] += inc[j];
    p.derivatives(state, t, yp, fp);
    J.col(j) = (fp - f) / inc[j];
    yp[j] = y[j];
  }
  return J;
}

/// Central differences of the whole right-hand side (truncation error O(inc²)).
Eigen::MatrixXd centralDifferences(const sim::Plant& p, const sim::PlantState& state, double t,
                                   const Eigen::VectorXd& y, const Eigen::VectorXd& inc) {
  const Eigen::Index n = y.size();
  Eigen::MatrixXd J(n, n);
  Eigen::VectorXd yp = y, fp(n), fm(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    yp[j] = y[j] + inc[j];
    p.derivatives(state, t, yp, fp);
    yp[j] = y[j] - inc[j];
    p.derivatives(state, t, yp, fm);
    J.col(j) = (fp - fm) / (2.0 * inc[j]);
    yp[j] = y[j];
  }
  return J;
}

/// The structured Jacobian equals the plain one column by column (1e-6 of the column's largest entry), and the
/// plain one is zero wherever the structure says two drives do not couple. With JacobianKind::Analytic the
/// accelerations' rows of the multibody's columns may instead equal central differences: the joint-local path takes
/// the multibody's part from the analytic ABA derivatives, which the forward differences miss by their truncation
/// error (1e-6 of a column with rigid gears at these increments).
void expectStructuredEqualsPlain(const systems::RobotSystem& sys, unsigned seed, bool coupled = false,
                                 const std::function<void(sim::PlantState&)>& setup = {}) {
  const Eigen::VectorXd y = movingState(sys, seed);
  const Eigen::Index n = y.size();
  Eigen::VectorXd f(n);
  const auto state = sys.makeState();
  if (setup) setup(*state);
  sys.start(*state, 0.37, y);
  sys.derivatives(*state, 0.37, y, f);
  const Eigen::VectorXd inc = increments(y);
  const Eigen::MatrixXd plain = plainDifferences(sys, *state, 0.37, y, f, inc);
  const Eigen::MatrixXd central = centralDifferences(sys, *state, 0.37, y, inc);
  const Eigen::Index dof = sys.dof();
  for (sim::JacobianKind kind : {sim::JacobianKind::Differences, sim::JacobianKind::Analytic}) {
    const bool analytic = kind == sim::JacobianKind::Analytic;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
    sys.jacobian(*state, 0.37, y, f, inc, J, kind);
    for (Eigen::Index j = 0; j < n; ++j) {
      const double scale = std::max(plain.col(j).cwiseAbs().maxCoeff(), 1e-300);
      for (Eigen::Index i = 0; i < n; ++i) {
        const bool qdd_of_hub = j < 2 * dof && i >= dof && i < 2 * dof;
        const double err = std::abs(J(i, j) - plain(i, j));
        if (analytic && qdd_of_hub && err > 1e-6 * scale)
          EXPECT_LE(std::abs(J(i, j) - central(i, j)), 1e-6 * scale)
              << "analytic: row " << i << ", column " << j << " (forward difference " << plain(i, j) << ")";
        else
          EXPECT_LE(err, 1e-6 * scale) << (analytic ? "analytic" : "differences") << ": row " << i << ", column " << j;
      }
    }
  }
  const sim::JacobianStructure st = sys.jacobianStructure();
  st.validate(static_cast<int>(n));
  EXPECT_EQ(st.blocks.size(), static_cast<size_t>(sys.dof()));
  for (size_t a = 0; a < st.blocks.size(); ++a) {
    for (size_t b = 0; b < st.blocks.size(); ++b) {
      if (a == b) continue;
      for (int i : st.blocks[a])
        for (int j : st.blocks[b]) EXPECT_EQ(plain(i, j), 0.0) << "drive " << a << " row " << i << ", col " << j;
    }
  }
  // The declared couplings of a block to the hub (the elimination reads nothing else): every other entry of the
  // block's rows in the hub's columns, and of the hub's rows in the block's columns, is zero.
  EXPECT_EQ(st.block_hub_columns.empty(), coupled);  // (a coupling matrix mixes the joints: no lists)
  for (size_t a = 0; a < st.block_hub_columns.size(); ++a)
    for (int j : st.hub) {
      const auto& c = st.block_hub_columns[a];
      if (std::find(c.begin(), c.end(), j) != c.end()) continue;
      for (int i : st.blocks[a]) EXPECT_EQ(plain(i, j), 0.0) << "drive " << a << " row " << i << ", hub col " << j;
    }
  for (size_t a = 0; a < st.block_hub_rows.size(); ++a)
    for (int i : st.hub) {
      const auto& r = st.block_hub_rows[a];
      if (std::find(r.begin(), r.end(), i) != r.end()) continue;
      for (int j : st.blocks[a]) EXPECT_EQ(plain(i, j), 0.0) << "drive " << a << " hub row " << i << ", col " << j;
    }
}

TEST(StructuredJacobian, Ur5TwinEqualsPlainDifferenceQuotients) {
  systems::RobotSystem sys = twin();
  expectStructuredEqualsPlain(sys, 1);
  expectStructuredEqualsPlain(sys, 2);
  // Drives on ports that bypass the controller (whose states then get no column evaluation: the plain columns must
  // be exactly 0) beside drives whose controller runs from another entry.
  expectStructuredEqualsPlain(sys, 4, false, [&sys](sim::PlantState& state) {
    using systems::CommandPort;
    const CommandPort ports[] = {CommandPort::Voltage,       CommandPort::MotorTorque, CommandPort::Current,
                                 CommandPort::MotorVelocity, CommandPort::Voltage,     CommandPort::Setpoint};
    for (int k = 0; k < 6; ++k) sys.setCommandPort(state, k, ports[k]);
  });
}

TEST(StructuredJacobian, TheMemoisedFrictionIsBitForBitAFreshEvaluationAndFollowsAParameterFault) {
  // RobotSystem memoises each drive's last friction evaluation by (model, v, z) bits: a state that evaluated other
  // points in between gives exactly what a fresh one gives, and a parameter fault (a new friction model of the drive
  // at the same v and z) is not served the old value.
  systems::RobotSystem sys = twin();
  const Eigen::VectorXd y1 = movingState(sys, 5), y2 = movingState(sys, 6);
  const Eigen::Index n = y1.size();
  Eigen::VectorXd fresh(n), f(n), other(n);
  const auto a = sys.makeState(), b = sys.makeState();
  sys.start(*a, 0.1, y1);
  sys.derivatives(*a, 0.1, y1, fresh);
  sys.start(*b, 0.1, y1);
  for (const Eigen::VectorXd* y : {&y2, &y1, &y1}) {
    sys.derivatives(*b, 0.1, *y, f);
    if (y == &y2) other = f;
  }
  EXPECT_EQ(std::memcmp(f.data(), fresh.data(), sizeof(double) * static_cast<size_t>(n)), 0);
  EXPECT_NE(other, fresh);
  // The elbow's Coulomb friction doubled from 0.05 s: the memo filled before the onset must not answer after it.
  systems::Fault fault;
  fault.type = systems::FaultType::CoulombFrictionScale;
  fault.joint = "elbow_joint";
  fault.value = 2.0;
  fault.onset = 0.05;
  sys.setFaults({fault});
  const int z = sys.layout(2).friction;
  ASSERT_GE(z, 0);
  Eigen::VectorXd y = y1;
  y[z] = 1e-6;  // a loaded bristle (about f_c / σ0): ż depends on f_c
  const auto c = sys.makeState(), d = sys.makeState();
  Eigen::VectorXd before(n), after(n), want(n);
  sys.start(*c, 0.0, y);
  sys.derivatives(*c, 0.0, y, before);
  sys.start(*c, 0.06, y);
  sys.derivatives(*c, 0.06, y, after);
  sys.start(*d, 0.06, y);
  sys.derivatives(*d, 0.06, y, want);
  EXPECT_NE(before[z], after[z]);
  EXPECT_EQ(after[z], want[z]);
  EXPECT_EQ(after, want);
}

TEST(StructuredJacobian, SampledControlAndCoupledRigidDrivesEqualPlainDifferenceQuotients) {
  {  // sampled control: the controller states leave the ODE, the blocks shrink
    systems::RobotSystem sys = twin();
    sys.setSampledControl(20000.0, 1);
    expectStructuredEqualsPlain(sys, 3);
  }
  // Rigid gears with a coupling matrix (the CRBA path with reflected rotor inertias) and elastic gears with
  // friction: both multibody paths and the torque map G⁻ᵀ.
  const multibody::Model ur5 = multibody::loadRobot(test::sourcePath("config/robots/ur5.yaml"));
  for (bool rigid : {true, false}) {
    std::vector<systems::DriveSpec> drives;
    for (int k = 0; k < 6; ++k) {
      systems::DriveSpec d;
      d.joint = ur5.joint_names[static_cast<size_t>(k)];
      d.motor = drive::DcMotorParams::ur5(k + 1);
      if (rigid)
        d.transmission = std::make_shared<drive::RigidGear>(101.0);
      else
        d.transmission = std::make_shared<drive::ElasticGear>(
            drive::ElasticGearParams{101.0, 2e4, 5.0, drive::ComplianceSide::Output});
      d.friction = std::make_shared<drive::CoulombViscousFriction>(drive::CoulombViscousParams{0.5, 0.3, 1e-2});
      d.controller.type = control::ControllerType::VoltageCascade;
      d.controller.P_pos = 3000;
      d.controller.P_vel = 1.0;
      d.controller.I_vel = 0.2;
      d.controller.P_cur = 10;
      d.controller.I_cur = 10000;
      drives.push_back(d);
    }
    Eigen::MatrixXd G = Eigen::MatrixXd::Identity(6, 6);
    G(4, 3) = 0.2;
    G(5, 3) = -0.1;
    G(5, 4) = 0.3;
    systems::RobotSystem sys(ur5, drives, G);
    expectStructuredEqualsPlain(sys, 4, true);
    // Without the coupling: the joint-local path (analytic ABA derivatives, the rigid rotors as armature), also with
    // end stops acting (a joint range the moving state lies beyond).
    systems::RobotSystem plain(ur5, drives);
    expectStructuredEqualsPlain(plain, 5);
    multibody::Model limited = ur5;
    limited.limits[1].upper = -1.3;  // the state's shoulder angle is -1.2 rad: in contact with the stop
    systems::RobotSystem stopped(limited, drives);
    systems::JointLimitSettings stops;
    stops.mode = systems::JointLimitMode::Stop;
    stopped.setJointLimits(stops);
    expectStructuredEqualsPlain(stopped, 6);
  }
}

/// ẏ = A y with a bordered block-diagonal A (hub of 2, blocks of 3 and 2), stiff: y(t) = e^{At} y0.
TEST(StructuredJacobian, BlockEliminationSolvesLikeTheDenseLu) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(7, 7);
  // hub {0, 5}; blocks {1, 2, 6} and {3, 4}
  A << -1, 0.5, 0, 0.2, 0, 0.3, -0.1,  //
      2, -900, 40, 0, 0, 1, 7,         //
      0, 30, -50, 0, 0, 0, 2,          //
      1, 0, 0, -3000, 200, -1, 0,      //
      0, 0, 0, -200, -10, 0.5, 0,      //
      0.1, 0.3, 0, 0.4, 0.2, -2, 0.1,  //
      0, 5, 1, 0, 0, 0, -20;
  Eigen::VectorXd y0(7);
  y0 << 1, -1, 0.5, 2, 0.3, -0.7, 0.1;
  auto run = [&](bool structured) {
    sim::CvodeOptions o = sim::stiffDriveSolver(1e-10, 1e-12);
    sim::CvodeIntegrator integ(
        7, [&](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) { yd = A * y; }, o,
        [&](double, const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
            Eigen::Ref<Eigen::MatrixXd> J) { J = A; });
    if (structured) integ.setJacobianStructure({{0, 5}, {{1, 2, 6}, {3, 4}}});
    integ.initialize(0.0, y0);
    Eigen::VectorXd y(7);
    integ.advance(0.5, y);
    return y;
  };
  // Reference: the matrix exponential by eigen-decomposition (A is diagonalisable).
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  const Eigen::VectorXcd c = es.eigenvectors().fullPivLu().solve(y0.cast<std::complex<double>>());
  const Eigen::VectorXd exact =
      (es.eigenvectors() * (es.eigenvalues() * 0.5).array().exp().matrix().asDiagonal() * c).real();
  const Eigen::VectorXd dense = run(false), blocks = run(true);
  EXPECT_LE((blocks - exact).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LE((blocks - dense).cwiseAbs().maxCoeff(), 1e-8);
  // A structure that misses a state, lists one twice or names one outside: InputError.
  sim::CvodeIntegrator integ(7, [&](double, const Eigen::Ref<const Eigen::VectorXd>& y,
                                    Eigen::Ref<Eigen::VectorXd> yd) { yd = A * y; });
  EXPECT_THROW(integ.setJacobianStructure({{0}, {{1, 2, 6}, {3, 4}}}), InputError);
  EXPECT_THROW(integ.setJacobianStructure({{0, 5}, {{1, 2, 6}, {3, 4, 4}}}), InputError);
  EXPECT_THROW(integ.setJacobianStructure({{0, 5, 9}, {{1, 2, 6}, {3, 4}}}), InputError);
  // The optional lists of a block's hub couplings: one list per block, hub states only, each once.
  EXPECT_THROW(integ.setJacobianStructure({{0, 5}, {{1, 2, 6}, {3, 4}}, {{0, 5}}, {}}), InputError);
  EXPECT_THROW(integ.setJacobianStructure({{0, 5}, {{1, 2, 6}, {3, 4}}, {{0, 5}, {0, 1}}, {}}), InputError);
  EXPECT_THROW(integ.setJacobianStructure({{0, 5}, {{1, 2, 6}, {3, 4}}, {}, {{0, 5}, {5, 5}}}), InputError);
}

// A stiff 7-state system whose block {3, 4} reads only hub state 0 and acts only on hub row 5, and whose block
// {1, 2, 6} reads hub state 5 only and acts on both hub rows (hub {0, 5}).
Eigen::MatrixXd coupledSevenStates() {
  Eigen::MatrixXd A(7, 7);
  A << -1, 0.5, 0, 0, 0, 0.3, -0.1,    //
      0, -900, 40, 0, 0, 1, 7,         //
      0, 30, -50, 0, 0, 0, 2,          //
      1, 0, 0, -3000, 200, 0, 0,       //
      0.7, 0, 0, -200, -10, 0, 0,      //
      0.1, 0.3, 0, 0.4, 0.2, -2, 0.1,  //
      0, 5, 1, 0, 0, 0, -20;
  return A;
}

TEST(StructuredJacobian, DeclaredHubCouplingsOfABlockAreAllTheEliminationReads) {
  // Block {3, 4} reads only hub state 0 and acts only on hub row 5; block {1, 2, 6} reads hub state 5 only and acts
  // on both hub rows. Declared so, the elimination skips the other entries: the same solution as the dense LU and
  // the matrix exponential. Declared too narrowly (block {3, 4} said not to act on row 5), it solves another system.
  const Eigen::MatrixXd A = coupledSevenStates();
  Eigen::VectorXd y0(7);
  y0 << 1, -1, 0.5, 2, 0.3, -0.7, 0.1;
  auto run = [&](const sim::JacobianStructure* st) {
    sim::CvodeOptions o = sim::stiffDriveSolver(1e-10, 1e-12);
    sim::CvodeIntegrator integ(
        7, [&](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) { yd = A * y; }, o,
        [&](double, const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
            Eigen::Ref<Eigen::MatrixXd> J) { J = A; });
    if (st) integ.setJacobianStructure(*st);
    integ.initialize(0.0, y0);
    Eigen::VectorXd y(7);
    integ.advance(0.5, y);
    return std::make_pair(Eigen::VectorXd(y), integ.stats());
  };
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  const Eigen::VectorXcd c = es.eigenvectors().fullPivLu().solve(y0.cast<std::complex<double>>());
  const Eigen::VectorXd exact =
      (es.eigenvectors() * (es.eigenvalues() * 0.5).array().exp().matrix().asDiagonal() * c).real();
  const sim::JacobianStructure declared{{0, 5}, {{1, 2, 6}, {3, 4}}, {{5}, {0}}, {{0, 5}, {5}}};
  const auto [dense, s_dense] = run(nullptr);
  const auto [lists, s_lists] = run(&declared);
  EXPECT_LE((lists - exact).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LE((lists - dense).cwiseAbs().maxCoeff(), 1e-8);
  // One solve with I − 0.01 A (both entry points): the dense LU's solution to rounding; declared too narrowly (block
  // {3, 4} said to act on row 0 instead of 5), another system's.
  const sim::JacobianStructure wrong{{0, 5}, {{1, 2, 6}, {3, 4}}, {{5}, {0}}, {{0, 5}, {0}}};
  const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(7, 7) - 0.01 * A;
  const Eigen::VectorXd b = y0, want = M.partialPivLu().solve(b);
  for (const auto* st : {&declared, &wrong}) {
    sim::DirectSolver by_entries(7, *st), by_matrix(7, *st);
    ASSERT_TRUE(by_entries.factorIdentityMinus(A, 0.01));
    ASSERT_TRUE(by_matrix.factor(M));
    Eigen::VectorXd x1(7), x2(7);
    by_entries.solve(b, x1);
    by_matrix.solve(b, x2);
    EXPECT_EQ(by_entries.denseFallbacks() + by_matrix.denseFallbacks(), 0);  // the elimination itself solved
    if (st == &declared) {
      EXPECT_LE((x1 - want).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LE((x2 - want).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_EQ(by_entries.determinantSign(), M.determinant() < 0 ? -1 : 1);
    } else {
      EXPECT_GT((x1 - want).cwiseAbs().maxCoeff(), 1e-4);
    }
  }
}

TEST(StructuredJacobian, ExplicitInversesSolveAsTheSubstitutionsFromTheThirdSolveAndFollowEachFactorisation) {
  // DirectSolver::useExplicitInverses (the fixed step's kept Jacobians): the first two solves after a factorisation
  // substitute (bit for bit the plain solver), from the third the blocks' and the Schur complement's inverses are
  // multiplied (the dense LU's solution to rounding); a new factorisation (another matrix) is solved with its own
  // factors, also after a factorisation that failed in between (a singular block: the dense fallback).
  const Eigen::MatrixXd A = coupledSevenStates();
  const sim::JacobianStructure st{{0, 5}, {{1, 2, 6}, {3, 4}}, {{5}, {0}}, {{0, 5}, {5}}};
  sim::DirectSolver plain(7, st), inverses(7, st);
  inverses.useExplicitInverses();
  Eigen::VectorXd b(7), x1(7), x2(7);
  for (double c : {0.01, 0.002}) {
    const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(7, 7) - c * A;
    ASSERT_TRUE(plain.factorIdentityMinus(A, c));
    ASSERT_TRUE(inverses.factorIdentityMinus(A, c));
    double by_inverse = 0.0;
    for (int k = 0; k < 5; ++k) {
      b = Eigen::VectorXd::LinSpaced(7, 1.0 + k, -2.0 + 3.0 * k);
      plain.solve(b, x1);
      inverses.solve(b, x2);
      const Eigen::VectorXd want = M.partialPivLu().solve(b);
      EXPECT_LE((x2 - want).cwiseAbs().maxCoeff(), 1e-13 * want.cwiseAbs().maxCoeff()) << c << " " << k;
      if (k < 2) {
        EXPECT_EQ(x1, x2) << c << " " << k;  // substituted
      } else {
        by_inverse = std::max(by_inverse, (x1 - x2).cwiseAbs().maxCoeff());
      }
    }
    EXPECT_GT(by_inverse, 0.0) << c;  // multiplied: other roundings than the substitutions'
    // Block {3, 4} of I − cJ made singular ([[0, 0], [0, 1 + 10c]]; the matrix is not, through its hub column 0):
    // the factorisation falls back to the dense LU, whose solution is returned, inverses formed before or not.
    Eigen::MatrixXd J = A;
    J(3, 3) = 1.0 / c;
    J(3, 4) = J(4, 3) = 0.0;
    ASSERT_TRUE(inverses.factorIdentityMinus(J, c));
    EXPECT_EQ(inverses.denseFallbacks(), c == 0.01 ? 1 : 2);
    const Eigen::MatrixXd MJ = Eigen::MatrixXd::Identity(7, 7) - c * J;
    for (int k = 0; k < 4; ++k) {
      b = Eigen::VectorXd::Constant(7, 1.0 + k);
      inverses.solve(b, x2);
      EXPECT_LE((x2 - MJ.partialPivLu().solve(b)).cwiseAbs().maxCoeff(), 1e-12) << c << " " << k;
    }
  }
  ASSERT_TRUE(inverses.factorIdentityMinus(A, 0.01));
  const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(7, 7) - 0.01 * A;
  for (int k = 0; k < 4; ++k) {
    b = Eigen::VectorXd::Constant(7, 1.0 + k);
    inverses.solve(b, x2);
    EXPECT_LE((x2 - M.partialPivLu().solve(b)).cwiseAbs().maxCoeff(), 1e-13) << k;
  }
}

TEST(StructuredJacobian, TheStructuresEntriesAreWhatTheMatrixOperationsTouch) {
  // structureRuns (the entries the Jacobian's zeroing, copies and A = cA + I touch) against the structure's
  // definition entry by entry, with and without the blocks' declared hub couplings: hub × hub, block × itself, a
  // block's rows × the hub columns it reads, the hub rows it acts on × its columns; each entry once, the diagonal in.
  for (bool lists : {false, true}) {
    sim::JacobianStructure st{{0, 5}, {{1, 2, 6}, {3, 4}}};
    if (lists) {
      st.block_hub_columns = {{5}, {0}};
      st.block_hub_rows = {{0, 5}, {5}};
    }
    const int n = 7;
    Eigen::MatrixXi want = Eigen::MatrixXi::Zero(n, n), got = Eigen::MatrixXi::Zero(n, n);
    auto has = [](const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); };
    for (int i : st.hub)
      for (int j : st.hub) want(i, j) = 1;
    for (size_t k = 0; k < st.blocks.size(); ++k)
      for (int a : st.blocks[k]) {
        for (int b : st.blocks[k]) want(a, b) = 1;
        for (int h : st.hub) {
          if (!lists || has(st.block_hub_columns[k], h)) want(a, h) = 1;
          if (!lists || has(st.block_hub_rows[k], h)) want(h, a) = 1;
        }
      }
    for (const sim::EntryRun& r : sim::structureRuns(st, n))
      for (int i = 0; i < r.len; ++i) got(r.row + i, r.col) += 1;
    EXPECT_EQ(got, want) << (lists ? "with lists" : "without lists");
    EXPECT_EQ(got.diagonal().minCoeff(), 1);
  }
  EXPECT_TRUE(sim::structureRuns(sim::JacobianStructure{}, 3).empty());
}

TEST(StructuredJacobian, TheDenseFallbackReadsOnlyTheStructuresEntriesAsTheEliminationDoes) {
  // Hub {0}, blocks {1} and {2}: J(1, 2) and J(2, 1) lie outside the structure, and a Jacobian may leave anything
  // there (the structured zeroing does not reach them). With J(1, 1) = 1/c the block {1} of I − cJ is exactly 0, so
  // the elimination fails and the dense LU takes over: it must solve the structure's matrix (outside entries 0), not
  // the one in memory, through all three entry points (by entries, by matrix, CVODE's linear solver).
  const double c = 0.5;
  Eigen::MatrixXd J(3, 3);
  J << -1, 3, 0.5,  //
      4, 2, 1e3,    // J(1, 1) = 1/c
      -2, -1e3, -6;
  Eigen::MatrixXd Js = J;
  Js(1, 2) = Js(2, 1) = 0.0;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd b = Eigen::Vector3d(1.0, -2.0, 0.5);
  const Eigen::VectorXd want = (I - c * Js).partialPivLu().solve(b);
  const Eigen::VectorXd garbage = (I - c * J).partialPivLu().solve(b);
  ASSERT_GT((want - garbage).cwiseAbs().maxCoeff(), 1e-3);  // the outside entries matter if read
  const sim::JacobianStructure st{{0}, {{1}, {2}}};
  sim::DirectSolver by_entries(3, st), by_matrix(3, st);
  ASSERT_TRUE(by_entries.factorIdentityMinus(J, c));
  ASSERT_TRUE(by_matrix.factor(I - c * J));
  Eigen::VectorXd x1(3), x2(3);
  by_entries.solve(b, x1);
  by_matrix.solve(b, x2);
  EXPECT_LE((x1 - want).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LE((x2 - want).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(by_entries.denseFallbacks(), 1);  // (the dense LU did)
  EXPECT_EQ(by_matrix.denseFallbacks(), 1);

  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
  SUNMatrix A = SUNDenseMatrix(3, 3, ctx);
  N_Vector nb = N_VNew_Serial(3, ctx), nx = N_VNew_Serial(3, ctx);
  SUNLinearSolver LS = sim::makeEigenDenseSolver(3, ctx, st);
  ASSERT_TRUE(A && nb && nx && LS);
  Eigen::Map<Eigen::MatrixXd>(SM_DATA_D(A), 3, 3) = I - c * J;
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(nb), 3) = b;
  EXPECT_EQ(SUNLinSolSetup(LS, A), 0);
  EXPECT_EQ(SUNLinSolSolve(LS, A, nx, nb, 0.0), 0);
  EXPECT_LE((Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(nx), 3) - want).cwiseAbs().maxCoeff(), 1e-14);
  SUNLinSolFree(LS);
  N_VDestroy(nx);
  N_VDestroy(nb);
  SUNMatDestroy(A);
  SUNContext_Free(&ctx);
}

TEST(StructuredJacobian, ANonFiniteEntryOfABlockFailsTheFactorisationEvenBehindAZeroMultiplier) {
  // Block {1, 2} of I − cJ is [[1, 0], [NaN, 1]]: the NaN is never a pivot and its column's update is skipped (its
  // U entry is 0), so without a check it would stay in L unseen. The factorisation must fail (so that the fixed step
  // names the entry), by the elimination and by the dense fallback alike.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, 3);
  J(0, 0) = -1.0;
  J(2, 1) = std::numeric_limits<double>::quiet_NaN();
  sim::DirectSolver solver(3, sim::JacobianStructure{{0}, {{1, 2}}});
  EXPECT_FALSE(solver.factorIdentityMinus(J, 0.1));
  J(2, 1) = 3.0;
  EXPECT_TRUE(solver.factorIdentityMinus(J, 0.1));
}

TEST(StructuredJacobian, TwinRunsAgreeWithCvodeDenseDifferenceQuotients) {
  // 0.3 s of the UR5 excitation at rtol 1e-9: the structured Jacobian with block elimination and CVODE's own dense
  // difference quotients with a dense LU reach the same states (both errors are far below the difference
  // allowed), with fewer right-hand-side evaluations for the Jacobians.
  auto run = [](bool plant_jacobian, sim::SolverStats* stats) {
    auto e = experiments::loadExperiment(test::sourcePath("config/experiments/ur5_excitation.yaml"),
                                         {"duration=0.3", "solver.rtol=1e-9", "solver.atol=1e-12"});
    sim::SimulateOptions o = e->simulateOptions();
    o.solver.plant_jacobian = plant_jacobian;
    sim::SimulationResult r;
    const sim::SignalTable t = sim::simulateTable(e->plant(), o, &r);
    *stats = r.stats;
    return t;
  };
  sim::SolverStats s_struct, s_dense;
  const sim::SignalTable a = run(true, &s_struct), b = run(false, &s_dense);
  ASSERT_EQ(a.values.rows(), b.values.rows());
  for (const char* col : {"q_shoulder_pan_joint", "q_elbow_joint", "q_wrist_3_joint"})
    EXPECT_LE((a[col] - b[col]).cwiseAbs().maxCoeff(), 1e-7) << col;
  for (const char* col : {"current_shoulder_lift_joint", "current_wrist_2_joint"})
    EXPECT_LE((a[col] - b[col]).cwiseAbs().maxCoeff(), 1e-4 * b[col].cwiseAbs().maxCoeff()) << col;
  EXPECT_EQ(s_struct.rhs_evals_jacobian, 0);  // the plant's Jacobian: not counted by CVODE
  EXPECT_GT(s_dense.rhs_evals_jacobian, 0);
}

}  // namespace
