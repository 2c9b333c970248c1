// The algorithms must not touch the heap once Data is constructed (they run inside the ODE right-hand
// side). glibc's malloc is wrapped for this test binary: every call is counted while the guard is armed.
#include <atomic>
#include <cstdlib>

#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

namespace {
std::atomic<bool> g_armed{false};
std::atomic<long> g_allocations{0};
}  // namespace

extern "C" void* __libc_malloc(size_t size);  // NOLINT: glibc's real allocator
extern "C" void* malloc(size_t size) {        // NOLINT
  if (g_armed.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}

using namespace jointsim::multibody;

TEST(NoAllocation, GuardDetectsAllocation) {
  // The guard itself must be able to fail: an allocation while armed is counted.
  g_allocations = 0;
  g_armed = true;
  Eigen::VectorXd* v = new Eigen::VectorXd(100);
  g_armed = false;
  delete v;
  EXPECT_GE(g_allocations.load(), 1);
}

TEST(NoAllocation, AlgorithmsDoNotAllocate) {
  const Model model = loadRobot(jointsim::test::sourcePath("config/robots/ur5.yaml"));
  Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(6, -1, 1), qd = -q, qdd = 2 * q;
  Matrix6Xd fext = Matrix6Xd::Ones(6, 6);
  const int frame = model.frameIndex(model.tip_frame);
  g_allocations = 0;
  g_armed = true;
  forwardKinematics(model, data, q);
  rnea(model, data, q, qd, qdd);
  rnea(model, data, q, qd, qdd, &fext);
  gravityTorques(model, data, q);
  nonLinearEffects(model, data, q, qd);
  crba(model, data, q);
  aba(model, data, q, qd, qdd);
  aba(model, data, q, qd, qdd, &fext);
  forwardDynamicsCrba(model, data, q, qd, qdd);
  frameJacobian(model, data, q, frame);
  const double e = kineticEnergy(model, data, q, qd) + potentialEnergy(model, data, q);
  g_armed = false;
  EXPECT_TRUE(std::isfinite(e));
  EXPECT_EQ(g_allocations.load(), 0);
}
