// The clamping experiment of [Olsson2017] on the whole IRB140: the orthogonal-compliance model edit, the
// ClampingPathPlanning reference, and the clamping curves against stiffnesses derived independently
// (clamp and bending springs mapped to joint space with the frame Jacobian), backlash and friction.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/control/clamping_path.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/orthogonal_compliance.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/clamped_robot.hpp"
#include "test_util.hpp"

using namespace jointsim;
using namespace jointsim::systems;

namespace {

multibody::Model irb140() { return multibody::loadRobot(test::sourcePath("config/robots/irb140.yaml")); }

// The IRB140 with all axes holding except `loaded`, which swings (3 segments of 3 s). Every axis:
// c = 10 N·m/rad (wrist 1), light damping, no backlash, stiff bending springs. The other motors are
// braked (50 N·m of stiction, like `breaksOn` in [Olsson2017]), so their springs hold the structure as in the
// derivation below; the loaded axis has a constant Coulomb friction F.
ClampingSetup setup(const std::string& loaded, double c_loaded, double b_loaded, double F_loaded, double clamp_k,
                    double d_loaded = 0.02) {
  ClampingSetup s;
  s.name = "test";
  s.arm = irb140();
  const double ratio[6] = {104.4, 104.4, 100.74, 1, 1, 1};
  const double cratio[6] = {104.4, 104.4, 100.74, 60.45, 65.1, 61.03};
  for (int k = 0; k < 6; ++k) {
    ClampingAxisParams a;
    a.joint = "joint" + std::to_string(k + 1);
    a.ratio = ratio[k];
    a.inertia = 0.014;
    a.c = k < 3 ? 10.0 : 1.0;
    a.d = 0.02;
    a.b = 0.0;
    a.tau_pos = {{{0.0, 50.0}, {1.0, 50.0}}};
    a.c_orth = k < 3 ? 1e8 : 0.0;
    a.d_orth = 30;
    a.kp = 0.008;
    a.ks = 0.01;
    a.Ts = 0.12;
    a.controller_ratio = cratio[k];
    a.path = {0.0, 0.4, 0.8, 3.0, 3};
    if (a.joint == loaded) {
      a.c = c_loaded;
      a.b = b_loaded;
      a.d = d_loaded;
      a.tau_pos = {{{0.0, F_loaded}, {1.0, F_loaded}}};
      a.path.q_pos = M_PI / 10;
    }
    s.axes.push_back(a);
  }
  s.coupling = drive::CouplingMatrix::irb140Wrist();
  s.coupled_joints = {"joint4", "joint5", "joint6"};
  s.clamp.frame = "flange";
  s.clamp.c_lin = s.clamp.c_rot = clamp_k * Eigen::Matrix3d::Identity();
  s.clamp.d_lin = s.clamp.d_rot = 9001.0 * Eigen::Matrix3d::Identity();
  s.duration = 9.0;
  s.log_interval = 0.01;
  return s;
}

// Motor-side series stiffness of axis `k` derived without the simulator: the joint-space stiffness of the
// clamped structure K = Jᵀ diag(c_lin, c_rot) J (frame Jacobian at the start posture) + bending springs +
// the other axes' drive springs (N² c through the coupling) — the loaded axis's own spring excluded —
// in series with that spring: 1/k = 1/c + N² (K⁻¹)_jj.
double seriesStiffness(const ClampingSetup& s, int k) {
  const ClampedRobot robot(s);
  const multibody::Model& m = robot.model();
  multibody::Data data(m);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(m.nq);
  const Eigen::MatrixXd J = multibody::frameJacobian(m, data, q, m.frameIndex("flange"));
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(6, 6);
  C.topLeftCorner(3, 3) = s.clamp.c_lin;
  C.bottomRightCorner(3, 3) = s.clamp.c_rot;
  Eigen::MatrixXd K = J.transpose() * C * J;
  // Drive springs in gear-output coordinates, mapped to joints: K += G⁻ᵀ diag(N² c) G⁻¹.
  Eigen::MatrixXd G = Eigen::MatrixXd::Identity(6, 6);
  G.bottomRightCorner(3, 3) = s.coupling;
  const Eigen::MatrixXd Ginv = G.inverse();
  Eigen::VectorXd kd(6);
  for (int a = 0; a < 6; ++a) {
    const auto& ax = s.axes[static_cast<size_t>(a)];
    kd[a] = a == k ? 0.0 : ax.ratio * ax.ratio * ax.c;
  }
  const Eigen::MatrixXd Kd = Ginv.transpose() * kd.asDiagonal() * Ginv;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) K(robot.jointOfAxis(a), robot.jointOfAxis(b)) += Kd(a, b);
  for (int a = 0; a < 6; ++a)
    for (int j : robot.orthOfAxis(a))
      if (j >= 0) K(j, j) += s.axes[static_cast<size_t>(a)].c_orth;
  // Compliance of the loaded axis's gear output (not coupled here: joints 1-3).
  const double compliance = K.inverse()(robot.jointOfAxis(k), robot.jointOfAxis(k));
  const auto& ax = s.axes[static_cast<size_t>(k)];
  return 1.0 / (1.0 / ax.c + ax.ratio * ax.ratio * compliance);
}

struct Curve {
  std::vector<double> angle, torque, spring, speed;
};

Curve simulate(const ClampingSetup& s, int k) {
  ClampedRobot robot(s);
  Curve c;
  sim::simulate(robot, robot.simulateOptions(), [&](const Eigen::VectorXd& row) {
    c.angle.push_back(row[1 + 10 * k]);
    c.speed.push_back(row[1 + 10 * k + 1]);
    c.torque.push_back(row[1 + 10 * k + 2]);
    c.spring.push_back(row[1 + 10 * k + 3]);
  });
  return c;
}

struct Line {
  double slope = 0, intercept = 0;
  size_t n = 0;
};
Line fit(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i] / n, my += y[i] / n;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < n; ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  Line l;
  l.slope = sxy / sxx;
  l.intercept = my - l.slope * mx;
  l.n = n;
  return l;
}

// Branches = maximal runs of samples in which the motor never moves against `direction` for 10 samples
// in a row (a momentary stick or bounce when the motor lands on the far side of the backlash gap does
// not end a branch; only samples moving in `direction` enter the fits). Fits, per branch, a line to the samples whose spring torque lies in [lo, hi]·max|τ_s|, and a second
// one for [lo2, hi2] (if given); only branches with at least 20 samples in each range count.
std::vector<std::pair<Line, Line>> branchFits2(const Curve& c, int direction, double lo, double hi, double lo2,
                                               double hi2) {
  double amax = 0;
  for (double t : c.spring) amax = std::max(amax, std::abs(t));
  std::vector<std::pair<Line, Line>> lines;
  std::vector<double> x, y, x2, y2;
  auto flush = [&] {
    if (x.size() >= 20 && (lo2 > hi2 || x2.size() >= 20))
      lines.emplace_back(fit(x, y), lo2 > hi2 ? Line{} : fit(x2, y2));
    x.clear(), y.clear(), x2.clear(), y2.clear();
  };
  int against = 0;
  for (size_t i = 0; i < c.angle.size(); ++i) {
    against = direction * c.speed[i] < -1e-6 ? against + 1 : 0;
    if (against >= 10) flush();  // moving back for 10 samples: a real reversal, not a bounce on landing
    if (against > 0) continue;
    if (direction * c.speed[i] <= 1e-6) continue;
    const double r = c.spring[i] / amax;
    if (r >= lo && r <= hi) x.push_back(c.angle[i]), y.push_back(c.torque[i]);
    if (r >= lo2 && r <= hi2) x2.push_back(c.angle[i]), y2.push_back(c.torque[i]);
  }
  flush();
  return lines;
}
std::vector<Line> branchFits(const Curve& c, int direction, double lo, double hi) {
  std::vector<Line> out;
  for (const auto& p : branchFits2(c, direction, lo, hi, 1.0, 0.0)) out.push_back(p.first);
  return out;
}

double meanSlope(const Curve& c) {
  double sum = 0;
  int n = 0;
  for (int dir : {1, -1})
    for (const Line& l : branchFits(c, dir, -0.8, 0.8)) sum += l.slope, ++n;
  EXPECT_GE(n, 3) << "too few loading branches";
  return sum / n;
}

}  // namespace

TEST(OrthogonalCompliance, ExtendedModelAtZeroBendingEqualsTheRigidArm) {
  const multibody::Model arm = irb140();
  const multibody::Model ext = multibody::withOrthogonalCompliance(arm, {"joint1", "joint2", "joint3"});
  ASSERT_EQ(ext.nq, 12);
  // getOrthVectors: J1 (n = y): u = e_x × n = z, v = n × u = x; J2 (n = z): u = e_x × z = −y, v = x.
  EXPECT_TRUE(test::MatricesNear(ext.axes[static_cast<size_t>(ext.jointIndex("joint1_orth_u"))],
                                 Eigen::Vector3d(0, 0, 1), 1e-15));
  EXPECT_TRUE(test::MatricesNear(ext.axes[static_cast<size_t>(ext.jointIndex("joint1_orth_v"))],
                                 Eigen::Vector3d(1, 0, 0), 1e-15));
  EXPECT_TRUE(test::MatricesNear(ext.axes[static_cast<size_t>(ext.jointIndex("joint2_orth_u"))],
                                 Eigen::Vector3d(0, -1, 0), 1e-15));
  multibody::Data da(arm), de(ext);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = test::randomVector(rng, 6, -1.5, 1.5), qd = test::randomVector(rng, 6, -1, 1);
    Eigen::VectorXd qe = Eigen::VectorXd::Zero(12), qde = Eigen::VectorXd::Zero(12);
    for (int i = 0; i < 6; ++i) {
      qe[ext.jointIndex(arm.joint_names[static_cast<size_t>(i)])] = q[i];
      qde[ext.jointIndex(arm.joint_names[static_cast<size_t>(i)])] = qd[i];
    }
    multibody::forwardKinematics(arm, da, q);
    multibody::forwardKinematics(ext, de, qe);
    const int fa = arm.frameIndex("flange"), fe = ext.frameIndex("flange");
    EXPECT_TRUE(test::MatricesNear(de.oMf[static_cast<size_t>(fe)].homogeneous(),
                                   da.oMf[static_cast<size_t>(fa)].homogeneous(), 1e-12));
    const Eigen::MatrixXd Ma = multibody::crba(arm, da, q), Me = multibody::crba(ext, de, qe);
    const Eigen::VectorXd ha = multibody::nonLinearEffects(arm, da, q, qd),
                          he = multibody::nonLinearEffects(ext, de, qe, qde);
    for (int i = 0; i < 6; ++i) {
      const int ei = ext.jointIndex(arm.joint_names[static_cast<size_t>(i)]);
      EXPECT_NEAR(he[ei], ha[i], 1e-9);
      for (int j = 0; j < 6; ++j)
        EXPECT_NEAR(Me(ei, ext.jointIndex(arm.joint_names[static_cast<size_t>(j)])), Ma(i, j), 1e-12);
    }
    // Bending DOFs carry inertia (M stays positive definite).
    EXPECT_GT(Me.llt().matrixL().toDenseMatrix().diagonal().minCoeff(), 0.0);
  }
  EXPECT_THROW(multibody::withOrthogonalCompliance(arm, {"nope"}), InputError);
}

TEST(ClampingPath, Seed000TimingsAndTruncatedSwings) {
  // [Olsson2017, §3.11, Table 3.8, A.14], [MSL, Blocks.Sources.KinematicPTP2] (timings derived):
  // path (π/10, 0.4, 0.8): first segment ends at 1.285 s, full swings 2.071 s.
  const control::ClampingPath p({M_PI / 10, 0.4, 0.8, 3.0, 5});
  double q, qd, qdd;
  p.evaluate(1.29, q, qd, qdd);
  EXPECT_NEAR(q, M_PI / 10, 1e-12);
  EXPECT_EQ(qd, 0.0);
  p.evaluate(1.28, q, qd, qdd);
  EXPECT_LT(q, M_PI / 10);
  p.evaluate(3.0 + 2.08, q, qd, qdd);
  EXPECT_NEAR(q, -M_PI / 10, 1e-12);
  p.evaluate(20.0, q, qd, qdd);
  EXPECT_NEAR(q, M_PI / 10, 1e-15);
  EXPECT_EQ(qd, 0.0);
  // path2 (π/6, 0.4, 0.8): a full swing needs 3.118 s, so at 6 s the reference is cut 0.00557 rad short
  // of −π/6 moving at 0.0944 rad/s, then jumps to the next segment's start (derived from [Olsson2017, A.14]
  // and Listing 4.1).
  const control::ClampingPath p2({M_PI / 6, 0.4, 0.8, 3.0, 5});
  p2.evaluate(6.0 - 1e-12, q, qd, qdd);
  EXPECT_NEAR(q + M_PI / 6, 0.00557, 2e-5);
  EXPECT_NEAR(qd, -0.0944, 2e-4);
  p2.evaluate(6.0, q, qd, qdd);
  EXPECT_NEAR(q, -M_PI / 6, 1e-12);
  const auto bp = p2.breakpoints();
  for (double t : {3.0, 6.0, 9.0, 12.0, 15.0}) EXPECT_NE(std::find(bp.begin(), bp.end(), t), bp.end()) << t;
  EXPECT_THROW(control::ClampingPath({0.1, 0.0, 0.8, 3.0, 5}), InputError);
}

TEST(ClampedRobotCurve, SlopeEqualsDerivedSeriesStiffnessStiffAndSoftClamp) {
  // Stiff clamp (2e7, as in [Olsson2017]) and stiff bending springs. The derived slope is 9.58, not 10: the clamp fixes
  // the flange, but joint 3 and the wrist can rotate to keep it there, so joint 2 also works against
  // the braked drives' springs of those joints (N² c ≈ 1e5 N·m/rad for joint 3).
  const ClampingSetup stiff = setup("joint2", 10.0, 0.0, 0.1, 2e7);
  const double k_stiff = seriesStiffness(stiff, 1);
  EXPECT_GT(k_stiff, 9.0);
  const double slope_stiff = meanSlope(simulate(stiff, 1));
  EXPECT_NEAR(slope_stiff / k_stiff, 1.0, 0.05) << "slope " << slope_stiff << " derived " << k_stiff;
  // A soft clamp (2e5 N/m, N·m/rad) puts the structure in series: the slope drops by ~30 %.
  const ClampingSetup soft = setup("joint2", 10.0, 0.0, 0.1, 2e5);
  const double k_soft = seriesStiffness(soft, 1);
  EXPECT_LT(k_soft, 8.0);
  const double slope_soft = meanSlope(simulate(soft, 1));
  EXPECT_NEAR(slope_soft / k_soft, 1.0, 0.05) << "slope " << slope_soft << " derived " << k_soft;
  std::printf("joint 2 clamping-curve slope: stiff clamp %.4f (derived %.4f), soft clamp %.4f (derived %.4f) N·m/rad\n",
              slope_stiff, k_stiff, slope_soft, k_soft);
}

TEST(ClampedRobotCurve, DoublingTheSpringNearlyDoublesTheSlope) {
  const double s10 = meanSlope(simulate(setup("joint1", 10.0, 0.0, 0.1, 2e7), 0));
  const double s20 = meanSlope(simulate(setup("joint1", 20.0, 0.0, 0.1, 2e7), 0));
  // [Olsson2017, §4.4]: 9.24 and 17.08 (ratio 1.85). The other compliances in series keep the ratio just below 2.
  EXPECT_GT(s20 / s10, 1.9);
  EXPECT_LT(s20 / s10, 2.0);
  std::printf("joint 1 slopes: c = 10: %.4f, c = 20: %.4f N·m/rad (ratio %.4f)\n", s10, s20, s20 / s10);
}

TEST(ClampedRobotCurve, BacklashIsAFlatSegmentOfItsWidth) {
  const double b = 0.05;  // rad, motor side
  // d = 0.5 N·m·s/rad (Table 4.1's joint 1): with a lighter damper the motor rings on its spring (4.3 Hz)
  // after it lands on the far side of the gap, and J ω̇ then bends the curve.
  ClampingSetup s = setup("joint2", 10.0, b, 0.1, 2e7, 0.5);
  // Slow swings (0.04 rad/s, 17 s slots): the motor creeps at ~0.04 rad/s, so the damper's d·δ̇ hardly
  // varies along a branch and the curve's outer parts are straight.
  s.axes[1].path.qd_max = 0.04;
  s.axes[1].path.segment_time = 17.0;
  s.duration = 51.0;
  s.log_interval = 0.02;
  const Curve c = simulate(s, 1);
  // On every loading branch, the outer linear parts (|τ_s| > 0.5 max, beyond the damper-limited contact onset) are parallel lines shifted
  // horizontally by the gap: the flat segment between them (torque = friction only) is b wide. (The
  // samples with zero spring torque span more than b: ElastoBacklash's damper cannot pull, so while the
  // contact opens at speed the torque is zero a little outside the gap.)
  int n = 0;
  for (int dir : {1, -1}) {
    const auto fits = branchFits2(c, dir, -0.9, -0.5, 0.5, 0.9);
    for (size_t i = 0; i < fits.size(); ++i) {
      const Line& neg = fits[i].first;
      const Line& pos = fits[i].second;
      const double k = 0.5 * (neg.slope + pos.slope);
      const double shift = (neg.intercept - pos.intercept) / k;
      EXPECT_NEAR(shift, b, 0.05 * b) << "branch " << i << " direction " << dir;
      std::printf("direction %+d: flat segment %.5f rad (b = %.5f)\n", dir, shift, b);
      ++n;
    }
  }
  EXPECT_GE(n, 2);  // the full swings +q → −q and −q → +q (the first segment starts from zero torque)
}

TEST(ClampedRobotCurve, FrictionWidensTheLoopByTwiceItsLevel) {
  // Loop width = vertical distance between the loading (ω > 0) and unloading (ω < 0) branches at the same
  // motor angle. Raising the Coulomb level from 0.05 to 0.30 N·m must widen it by 2·0.25 N·m.
  auto width = [](double F) {
    const Curve c = simulate(setup("joint2", 10.0, 0.0, F, 2e7), 1);
    const auto up = branchFits(c, 1, -0.7, 0.7), down = branchFits(c, -1, -0.7, 0.7);
    EXPECT_GE(up.size(), 1u);
    EXPECT_GE(down.size(), 1u);
    double w = 0;
    int n = 0;
    for (const Line& a : up)
      for (const Line& b : down) w += a.intercept - b.intercept, ++n;  // at φ = 0 (parallel lines)
    return w / n;
  };
  const double w_low = width(0.05), w_high = width(0.30);
  EXPECT_NEAR(w_high - w_low, 0.5, 0.025) << "widths " << w_low << " and " << w_high;
  EXPECT_NEAR(w_low, 0.1, 0.03);  // 2 F plus the damper d·δ̇ on both branches (d = 0.02 N·m·s/rad, δ̇ ≈ 0.3 rad/s)
}

TEST(ClampingExperiment, Irb140DemoRunsAndWritesCurves) {
  const test::TempDir tmp;
  const std::string dir = (tmp / "jointsim_clamping_demo").string();
  experiments::RunOptions o;
  o.output_dir = dir;
  o.overrides = {"duration=3", "log_rate=100"};
  const experiments::RunReport r =
      experiments::runExperimentFile(test::sourcePath("config/experiments/irb140_clamping.yaml"), o);
  EXPECT_EQ(r.status, "ok");
  for (int j = 1; j <= 6; ++j)
    EXPECT_TRUE(std::filesystem::exists(dir + "/irb140_clamping_joint" + std::to_string(j) + "_curve.csv")) << j;
  std::ifstream in(dir + "/irb140_clamping_joint2_curve.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "time[s],motor_angle[rad],motor_torque[N·m]");
}

TEST(ClampingExperiment, BadInputNamesTheKey) {
  const test::TempDir tmp;
  const std::string dir = (tmp / "jointsim_clamping_bad").string();
  auto fails = [&](const std::string& override_, const std::string& expected) {
    experiments::RunOptions o;
    o.output_dir = dir;
    o.overrides = {override_};
    try {
      experiments::runExperimentFile(test::sourcePath("config/experiments/irb140_clamping.yaml"), o);
      ADD_FAILURE() << override_ << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("irb140_clamping.yaml:"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir + "/irb140_clamping.csv"));
  };
  // A value an override set: the override is named, not the line of the file that held the old value.
  fails("axes[1].c=-3",
        "irb140_clamping.yaml: axes[1].c: expected a finite value > 0 N·m/rad, got -3 (from the override --set "
        "axes[1].c=-3)");
  fails("axes[0].friction.peak=0.5", ": axes[0].friction.peak: expected a finite value >= 1 (-), got 0.5");
  fails("clamp.frame=nowhere", "no frame named 'nowhere'");
  fails("axes[2].joint=joint1", "already has an axis");
  fails("load=some", "'all' or a list of joint names");
  fails("axes[3].path.qd_max=0", ": axes[3].path.qd_max: expected a finite value > 0 rad/s, got 0");
  fails("clamp.frame=base", "is on the fixed base");
  fails("coupling.joints[1]=joint4", "appears twice in the coupling");
  fails("axes[0].controller.ks=-0.01", ": axes[0].controller.ks: expected a finite value >= 0 N·m·s/rad, got -0.01");
}
