// Google Benchmark timings of the rigid-body algorithms on the UR5 (config/robots/ur5.yaml).
// Inputs are generated outside the timed loop; a ring of 64 random states defeats branch-history luck.
// Run: ./build/bench/bench_multibody --benchmark_min_time=1
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"

using namespace jointsim::multibody;

namespace {
struct Ur5Fixture {
  Model model = loadRobot(std::string(JOINTSIM_SOURCE_DIR) + "/config/robots/ur5.yaml");
  Data data{model};
  std::vector<Eigen::VectorXd> q, qd, qdd;
  Ur5Fixture() {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    for (int k = 0; k < 64; ++k) {
      Eigen::VectorXd a(6), b(6), c(6);
      for (int i = 0; i < 6; ++i) {
        a[i] = u(rng);
        b[i] = u(rng);
        c[i] = u(rng);
      }
      q.push_back(a);
      qd.push_back(b);
      qdd.push_back(c);
    }
  }
};
Ur5Fixture& fixture() {
  static Ur5Fixture f;
  return f;
}
}  // namespace

static void UR5_FK(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    forwardKinematics(f.model, f.data, f.q[k++ & 63]);
    benchmark::DoNotOptimize(f.data.oMf.back());
  }
}
BENCHMARK(UR5_FK);

static void UR5_RNEA(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ & 63;
    benchmark::DoNotOptimize(rnea(f.model, f.data, f.q[i], f.qd[i], f.qdd[i]).data());
  }
}
BENCHMARK(UR5_RNEA);

static void UR5_CRBA(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(crba(f.model, f.data, f.q[k++ & 63]).data());
}
BENCHMARK(UR5_CRBA);

static void UR5_ABA(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ & 63;
    benchmark::DoNotOptimize(aba(f.model, f.data, f.q[i], f.qd[i], f.qdd[i]).data());
  }
}
BENCHMARK(UR5_ABA);

static void UR5_CRBA_Cholesky_FD(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ & 63;
    benchmark::DoNotOptimize(forwardDynamicsCrba(f.model, f.data, f.q[i], f.qd[i], f.qdd[i]).data());
  }
}
BENCHMARK(UR5_CRBA_Cholesky_FD);

// Analytic derivatives: ∂τ/∂q, ∂τ/∂q̇ and M of RNEA; ∂q̈/∂q, ∂q̈/∂q̇ and M⁻¹ of ABA (Pinocchio's
// computeRNEADerivatives / computeABADerivatives compute the same sets).
static void UR5_RNEA_Derivatives(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ & 63;
    computeRneaDerivatives(f.model, f.data, f.q[i], f.qd[i], f.qdd[i]);
    benchmark::DoNotOptimize(f.data.dtau_dq.data());
  }
}
BENCHMARK(UR5_RNEA_Derivatives);

static void UR5_ABA_Derivatives(benchmark::State& state) {
  auto& f = fixture();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ & 63;
    computeAbaDerivatives(f.model, f.data, f.q[i], f.qd[i], f.qdd[i]);
    benchmark::DoNotOptimize(f.data.ddq_dq.data());
  }
}
BENCHMARK(UR5_ABA_Derivatives);

static void UR5_Jacobian(benchmark::State& state) {
  auto& f = fixture();
  const int frame = f.model.frameIndex(f.model.tip_frame);
  size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(frameJacobian(f.model, f.data, f.q[k++ & 63], frame).data());
}
BENCHMARK(UR5_Jacobian);

BENCHMARK_MAIN();
