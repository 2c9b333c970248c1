// Writes the UR5 of config/robots/ur5.yaml (joint placements, axes, inertias, gravity) as plain numbers for
// pin_ur5.cpp, which builds the same model joint by joint in Pinocchio (bench/pinocchio/compare.sh).
#include "jointsim/multibody/robot_loader.hpp"
#include <cstdio>
int main(int argc, char** argv) {
  const auto m = jointsim::multibody::loadRobot(argc > 1 ? argv[1] : "config/robots/ur5.yaml");
  std::printf("%d %.17g %.17g %.17g\n", m.nq, m.gravity.x(), m.gravity.y(), m.gravity.z());
  for (int i = 0; i < m.nq; ++i) {
    const auto& X = m.joint_placements[i];
    std::printf("%d %d", m.parents[i], m.axis_kind[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) std::printf(" %.17g", X.R(r, c));
    for (int r = 0; r < 3; ++r) std::printf(" %.17g", X.p[r]);
    for (int r = 0; r < 3; ++r) std::printf(" %.17g", m.axes[i][r]);
    const auto& I = m.inertias[i];
    std::printf(" %.17g", I.mass);
    for (int r = 0; r < 3; ++r) std::printf(" %.17g", I.com[r]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) std::printf(" %.17g", I.inertia(r, c));
    std::printf("\n");
  }
}
