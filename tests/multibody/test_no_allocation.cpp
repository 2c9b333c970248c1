// The algorithms must not touch the heap once Data is constructed (they run inside the ODE right-hand
// side). glibc's malloc is wrapped for this test binary (under AddressSanitizer: the sanitizer's allocation hook):
// every call is counted while the guard is armed.
#include <atomic>
#include <cstdlib>

#include <gtest/gtest.h>

#include "jointsim/control/trajectory.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

namespace {
std::atomic<bool> g_armed{false};
std::atomic<long> g_allocations{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__)
#define JOINTSIM_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define JOINTSIM_ASAN 1
#endif
#endif

#ifdef JOINTSIM_ASAN
// Under AddressSanitizer malloc belongs to the sanitizer: count through its allocation hook instead.
#include <sanitizer/allocator_interface.h>
namespace {
void countAllocation(const volatile void*, size_t) {
  if (g_armed.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
void ignoreFree(const volatile void*) {}
// Both hooks are required (a null one makes the call fail and return 0).
const int g_hook_installed = __sanitizer_install_malloc_and_free_hooks(countAllocation, ignoreFree);
}  // namespace
#else
extern "C" void* __libc_malloc(size_t size);  // NOLINT: glibc's real allocator
extern "C" void* malloc(size_t size) {        // NOLINT
  if (g_armed.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif

using namespace jointsim::multibody;

TEST(NoAllocation, GuardDetectsAllocation) {
  // The guard itself must be able to fail: an allocation while armed is counted.
#ifdef JOINTSIM_ASAN
  ASSERT_NE(g_hook_installed, 0) << "the sanitizer's allocation hook is not installed";
#endif
  g_allocations = 0;
  g_armed = true;
  Eigen::VectorXd* v = new Eigen::VectorXd(100);
  asm volatile("" : : "g"(v) : "memory");  // the compiler may not elide the allocation (clang does otherwise)
  g_armed = false;
  delete v;
  EXPECT_GE(g_allocations.load(), 2) << "the vector object and its coefficients";
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

// ------------------------------------------------------------------------------ RobotSystem::derivatives
namespace {

/// Heap allocations of `calls` evaluations of the robot's right-hand side (after one warm-up call).
long rhsAllocations(const jointsim::systems::RobotSystem& sys, const jointsim::sim::PlantState& state,
                    const Eigen::VectorXd& y, int calls = 5) {
  Eigen::VectorXd yd(sys.stateSize());
  sys.derivatives(state, 0.0, y, yd);
  g_allocations = 0;
  g_armed = true;
  for (int k = 0; k < calls; ++k) sys.derivatives(state, 0.01 * k, y, yd);
  g_armed = false;
  EXPECT_TRUE(yd.allFinite());
  return g_allocations.load();
}

std::shared_ptr<const jointsim::control::JointTrajectory> fourier(int n) {
  jointsim::control::FourierParams p;
  p.base_frequency = 0.2;
  p.offset = Eigen::VectorXd::Constant(n, 0.3);
  p.a = Eigen::MatrixXd::Constant(n, 2, 0.05);
  p.b = Eigen::MatrixXd::Constant(n, 2, -0.03);
  p.fade_in = 0.5;
  p.duration = 5.0;
  return std::make_shared<jointsim::control::FourierTrajectory>(p);
}

}  // namespace

TEST(NoAllocation, RobotSystemTwinContinuousAndSampled) {
  // The UR5 twin (strain-wave gears, LuGre, electrics, cascade controllers) following a trajectory.
  for (const bool sampled : {false, true}) {
    jointsim::systems::RobotSystem sys =
        jointsim::systems::loadRobotWithDrives(jointsim::test::sourcePath("config/robots/ur5_drives.yaml"));
    if (sampled) sys.setSampledControl(20000.0, 3);
    sys.setTrajectory(fourier(6));
    const Eigen::VectorXd y = sys.initialState();
    const auto state = sys.makeState();
    sys.start(*state, 0.0, y);
    EXPECT_EQ(rhsAllocations(sys, *state, y), 0) << (sampled ? "sampled" : "continuous");
  }
}

TEST(NoAllocation, RobotSystemCoupledRigidWithExternalWrenches) {
  // Coupled rigid drives (the CRBA + Cholesky path) with an external wrench on the tool: the path that
  // allocated a zero vector on every call before.
  using namespace jointsim;
  const Model model = loadRobot(jointsim::test::sourcePath("config/robots/irb140.yaml"));
  std::vector<systems::DriveSpec> drives;
  for (int k = 0; k < model.nq; ++k) {
    systems::DriveSpec d;
    d.joint = model.joint_names[static_cast<size_t>(k)];
    d.motor.J_M = 0.014;
    d.electrics = false;
    d.transmission = std::make_shared<drive::RigidGear>(k < 3 ? 100.0 : 1.0);
    d.controller.type = control::ControllerType::TorqueCascade;
    d.controller.kp = 0.008;
    d.controller.ks = 0.01;
    d.controller.Ts = 0.1;
    drives.push_back(d);
  }
  Eigen::MatrixXd G = Eigen::MatrixXd::Identity(6, 6);
  G.bottomRightCorner(3, 3) = drive::CouplingMatrix::irb140Wrist();
  systems::RobotSystem sys(model, drives, G);
  sys.setTrajectory(fourier(6));
  const int tip = model.nq - 1;
  sys.setExternalWrenches([tip](double t, const Model&, const Data&, const Eigen::Ref<const Eigen::VectorXd>&,
                                const Eigen::Ref<const Eigen::VectorXd>&, Matrix6Xd& fext) {
    fext(5, tip) = -20.0 - t;  // a downward force on the last body [N]
  });
  const Eigen::VectorXd y = sys.initialState();
  EXPECT_EQ(rhsAllocations(sys, *sys.makeState(), y), 0);
  // The same robot without the wrench takes ABA-free CRBA too; with identity coupling it takes ABA.
  systems::RobotSystem plain(model, drives);
  plain.setTrajectory(fourier(6));
  EXPECT_EQ(rhsAllocations(plain, *plain.makeState(), plain.initialState()), 0);
}
