// UR5 "robot equivalent inertia": the diagonal of the joint-space inertia matrix, M_ii(q), scanned over
// configurations, against [Raviola2023, App. A, Table A1]. Acceptance criterion of the UR5 digital-twin
// issue: the shipped model config/robots/ur5.yaml ([Raviola2023, Table 4] kinematics + [Raviola2023, Table 5]
// dynamics, missing entries from [URDH]) reproduces each of the 18 max/mean/min entries within 6 %.
//
// What M_ii contains. Table A1 includes the rotor inertia reflected through the gear, J_M τ² (our reading:
// M_66 = 0.212 ≈ J_M τ² = 0.2118). ur5.yaml has armature 0 (the drive models carry the rotor), so the test
// adds J_M τ² itself, from [Raviola2023, §2.2, Table 2] (J_M = 1.877e-4 kg·m² for joints 1–3,
// 2.076e-5 kg·m² for joints 4–6) and τ = 101 ([Raviola2023, eq. 2], Z_CS = 202, Z_FS = 200).
//
// How the scan is done. [Raviola2023, App. A]: "Figure A2 shows how the robot equivalent inertia acting on the base
// (M11), shoulder (M22), elbow (M33), and first wrist (M44) joints varies as a function of the position of
// the two consecutive joints." Caption: "(a) Base inertia as a function of shoulder and elbow angles;
// (b) shoulder inertia as a function of elbow and wrist 1 angles; (c) elbow inertia as a function of
// wrist 1 and 2 angles; (d) wrist 1 inertia as a function of wrist 2 and 3 angles." So M_ii is scanned over
// q_{i+1}, q_{i+2} with every other joint at 0. M_ii depends only on the distal joints q_{i+1}..q_6, so:
//   - M_55 has one following joint: scanned over q_6 alone (the text: "no sensitive variations are present
//     for the last two joints");
//   - M_66 depends on no joint angle: evaluated once (q = 0).
// The ranges are not stated in [Raviola2023]. We use a uniform 72-point grid (5°) on [−π, π) per scanned joint: M(q)
// is 2π-periodic in every revolute angle, so the ±2π joint limits of ur5.yaml (UR controller) give exactly
// the same set of values; a 360-point grid changes no entry by more than about 1e-4 kg·m².
// Alternative checked while writing this test: scanning all distal joints q_{i+1}..q_5 (as our earlier
// validation of the reconstruction did) also passes, but raises max M_11 to 5.916 (+5.1 % vs 5.628) where the two-joint
// scan gives 5.668 (+0.7 %); it is slightly closer only on mean/min M_11 (3.194/2.074 vs 3.202/2.096).
// The two-joint scan is what Fig. A2 describes; its worst entry is min M_11 at +1.7 %.
//
// Pitfall documented by the second test: the standard ROS UR5 URDF (config/robots/ur5.urdf) carries the
// radius="0.6" wrist-cylinder typo (≈100× too large wrist inertias); its wrist entries miss Table A1 by far
// more than 6 %, so it must not be used where the dynamics of [Raviola2023] matter.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

using namespace jointsim::multibody;
using jointsim::test::sourcePath;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kJoints = 6;
constexpr int kGrid = 72;            // points per scanned joint on [−π, π) (5° steps)
constexpr double kTolerance = 0.06;  // acceptance criterion: 6 % relative per entry

// [Raviola2023, Table 2] rotor inertias [kg·m²] and [Raviola2023, eq. 2] gear ratio.
constexpr double kRotorInertiaArm = 1.877e-4;    // base, shoulder, elbow
constexpr double kRotorInertiaWrist = 2.076e-5;  // wrist 1, 2, 3
constexpr double kGearRatio = 101.0;

const char* const kJointLabels[kJoints] = {"Base", "Shoulder", "Elbow", "Wrist 1", "Wrist 2", "Wrist 3"};
const char* const kStatLabels[3] = {"max", "mean", "min"};

// [Raviola2023, App. A, Table A1] [kg·m²], rows max / mean / min, columns joints 1–6.
constexpr double kTableA1[3][kJoints] = {
    {5.628, 5.719, 2.649, 0.228, 0.215, 0.212},  // maximum
    {3.194, 4.144, 2.526, 0.227, 0.215, 0.212},  // mean
    {2.061, 2.752, 2.405, 0.226, 0.215, 0.212},  // minimum
};

/// Reflected rotor inertia J_M τ² of joint i (0-based) [kg·m²]: 1.9147 (joints 1–3), 0.21177 (joints 4–6).
double reflectedRotorInertia(int i) {
  return (i < 3 ? kRotorInertiaArm : kRotorInertiaWrist) * kGearRatio * kGearRatio;
}

/// stats[s][i]: s = 0 max, 1 mean, 2 min of M_ii + J_M τ² over the Fig. A2 scan.
using Stats = std::array<std::array<double, kJoints>, 3>;

/// Scans M_ii over q_{i+1}, q_{i+2} (those that exist), uniform kGrid-point grid on [−π, π) each, every
/// other joint at 0, and adds the reflected rotor inertia.
Stats scanTableA1(const Model& model) {
  Data data(model);
  Stats stats{};
  for (int i = 0; i < kJoints; ++i) {
    const int j1 = i + 1;
    const int j2 = i + 2;
    const int n1 = j1 < kJoints ? kGrid : 1;
    const int n2 = j2 < kJoints ? kGrid : 1;
    double max = -HUGE_VAL;
    double min = HUGE_VAL;
    double sum = 0.0;
    Eigen::VectorXd q = Eigen::VectorXd::Zero(kJoints);
    for (int a = 0; a < n1; ++a) {
      for (int b = 0; b < n2; ++b) {
        if (j1 < kJoints) q[j1] = -kPi + 2.0 * kPi * a / kGrid;
        if (j2 < kJoints) q[j2] = -kPi + 2.0 * kPi * b / kGrid;
        const double mii = crba(model, data, q)(i, i) + reflectedRotorInertia(i);
        max = std::max(max, mii);
        min = std::min(min, mii);
        sum += mii;
      }
    }
    stats[0][static_cast<size_t>(i)] = max;
    stats[1][static_cast<size_t>(i)] = sum / (static_cast<double>(n1) * n2);
    stats[2][static_cast<size_t>(i)] = min;
  }
  return stats;
}

double relativeDifference(const Stats& stats, int s, int i) {
  return (stats[static_cast<size_t>(s)][static_cast<size_t>(i)] - kTableA1[s][i]) / kTableA1[s][i];
}

const char* scanLabel(int i) {
  static const char* const labels[kJoints] = {"q2,q3", "q3,q4", "q4,q5", "q5,q6", "q6", "(none)"};
  return labels[i];
}

void printTable(const std::string& title, const Stats& stats) {
  std::printf("\n%s\n", title.c_str());
  std::printf("M_ii [kg m^2] incl. J_M tau^2; scan: 2 following joints, %d-pt grid on [-pi, pi), others 0\n", kGrid);
  std::printf("  %-9s %-7s %-5s %9s %10s %10s\n", "joint", "scan", "stat", "Table A1", "jointsim", "rel.diff");
  for (int i = 0; i < kJoints; ++i) {
    for (int s = 0; s < 3; ++s) {
      std::printf("  %-9s %-7s %-5s %9.3f %10.4f %+9.2f%%\n", s == 0 ? kJointLabels[i] : "", s == 0 ? scanLabel(i) : "",
                  kStatLabels[s], kTableA1[s][i], stats[static_cast<size_t>(s)][static_cast<size_t>(i)],
                  100.0 * relativeDifference(stats, s, i));
    }
  }
  std::fflush(stdout);
}
}  // namespace

TEST(Ur5TableA1, ShippedModelReproducesSeed002TableA1) {
  const Model model = loadRobot(sourcePath("config/robots/ur5.yaml"));
  ASSERT_EQ(model.nq, kJoints);
  // The test adds J_M τ² itself; a non-zero armature in the file would count the rotor twice.
  ASSERT_TRUE(model.armature.isZero()) << "ur5.yaml armature: " << model.armature.transpose();

  const Stats stats = scanTableA1(model);
  printTable("[Raviola2023, Table A1] vs jointsim, config/robots/ur5.yaml", stats);
  for (int i = 0; i < kJoints; ++i) {
    for (int s = 0; s < 3; ++s) {
      EXPECT_LE(std::abs(relativeDifference(stats, s, i)), kTolerance)
          << kStatLabels[s] << " M_" << i + 1 << i + 1 << " (" << kJointLabels[i] << "): jointsim "
          << stats[static_cast<size_t>(s)][static_cast<size_t>(i)] << " vs [Raviola2023, Table A1] " << kTableA1[s][i];
    }
  }
}

TEST(Ur5TableA1, RosUrdfWristInertiaTypoMissesTableA1) {
  // The standard ROS UR5 URDF (ur_description, cylinder inertias with radius="0.6" on the wrists) is NOT a
  // substitute for ur5.yaml: every wrist entry of Table A1 is off by more than the 6 % tolerance
  // (wrist 1 and 2 roughly doubled). Documents the pitfall; see the header of config/robots/ur5.urdf.
  const Model model = loadRobot(sourcePath("config/robots/ur5.urdf"));
  ASSERT_EQ(model.nq, kJoints);
  ASSERT_TRUE(model.armature.isZero()) << "ur5.urdf armature: " << model.armature.transpose();

  const Stats stats = scanTableA1(model);
  printTable("[Raviola2023, Table A1] vs jointsim, config/robots/ur5.urdf (ROS, wrist radius 0.6 typo)", stats);
  for (int i = 3; i < kJoints; ++i) {
    for (int s = 0; s < 3; ++s) {
      EXPECT_GT(std::abs(relativeDifference(stats, s, i)), kTolerance)
          << kStatLabels[s] << " M_" << i + 1 << i + 1 << " (" << kJointLabels[i] << "): ur5.urdf "
          << stats[static_cast<size_t>(s)][static_cast<size_t>(i)] << " vs [Raviola2023, Table A1] " << kTableA1[s][i];
    }
  }
}
