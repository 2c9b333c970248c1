// Pinocchio 4.1 (the pin wheel's headers, compiled with -O3 -march=native by compare.sh) on the UR5 of
// config/robots/ur5.yaml (read from dump_ur5's output): the same algorithms and the same ring of 64 random states as
// bench/bench_multibody.cpp.
#include <benchmark/benchmark.h>
#include <pinocchio/multibody.hpp>
#include <random>

#include <cstdlib>
#include <fstream>
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>
namespace pin = pinocchio;
struct F {
  pin::Model model;
  pin::Data* data;
  std::vector<Eigen::VectorXd> q, qd, qdd;
  F() {
    // The UR5 of config/robots/ur5.yaml, built joint by joint (header-only Pinocchio: the wheel's compiled
    // library uses another alignment than this -march=native translation unit).
    std::ifstream in(std::getenv("UR5_TXT") ? std::getenv("UR5_TXT") : "ur5.txt");  // dump_ur5 output
    int nq;
    Eigen::Vector3d g;
    in >> nq >> g.x() >> g.y() >> g.z();
    for (int i = 0; i < nq; ++i) {
      int par, kind;
      Eigen::Matrix3d R, Ic;
      Eigen::Vector3d p, axis, com;
      double mass;
      in >> par >> kind;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) in >> R(r, c);
      for (int r = 0; r < 3; ++r) in >> p[r];
      for (int r = 0; r < 3; ++r) in >> axis[r];
      in >> mass;
      for (int r = 0; r < 3; ++r) in >> com[r];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) in >> Ic(r, c);
      pin::SE3 placement(R, p);
      const int parent = par < 0 ? 0 : par + 1;
      pin::JointIndex id;
      const std::string name = "j" + std::to_string(i);
      switch (kind) {
        case 0: id = model.addJoint(parent, pin::JointModelRX(), placement, name); break;
        case 1: id = model.addJoint(parent, pin::JointModelRY(), placement, name); break;
        case 2: id = model.addJoint(parent, pin::JointModelRZ(), placement, name); break;
        default: id = model.addJoint(parent, pin::JointModelRevoluteUnaligned(axis), placement, name);
      }
      model.appendBodyToJoint(id, pin::Inertia(mass, com, Ic), pin::SE3::Identity());
    }
    model.gravity.linear(g);
    data = new pin::Data(model);
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
F& f() {
  static F x;
  return x;
}
static void PIN_RNEA(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    benchmark::DoNotOptimize(pin::rnea(x.model, *x.data, x.q[i], x.qd[i], x.qdd[i]).data());
  }
}
static void PIN_CRBA(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    benchmark::DoNotOptimize(pin::crba(x.model, *x.data, x.q[i], pin::Convention::WORLD).data());
  }
}
static void PIN_CRBA_LOCAL(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    benchmark::DoNotOptimize(pin::crba(x.model, *x.data, x.q[i], pin::Convention::LOCAL).data());
  }
}
static void PIN_ABA(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    benchmark::DoNotOptimize(pin::aba(x.model, *x.data, x.q[i], x.qd[i], x.qdd[i], pin::Convention::WORLD).data());
  }
}
static void PIN_RNEA_Derivatives(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    pin::computeRNEADerivatives(x.model, *x.data, x.q[i], x.qd[i], x.qdd[i]);
    benchmark::DoNotOptimize(x.data->dtau_dq.data());
  }
}
static void PIN_ABA_Derivatives(benchmark::State& s) {
  auto& x = f();
  size_t k = 0;
  for (auto _ : s) {
    size_t i = k++ & 63;
    pin::computeABADerivatives(x.model, *x.data, x.q[i], x.qd[i], x.qdd[i]);
    benchmark::DoNotOptimize(x.data->ddq_dq.data());
  }
}
BENCHMARK(PIN_RNEA);
BENCHMARK(PIN_CRBA);
BENCHMARK(PIN_CRBA_LOCAL);
BENCHMARK(PIN_ABA);
BENCHMARK(PIN_RNEA_Derivatives);
BENCHMARK(PIN_ABA_Derivatives);
BENCHMARK_MAIN();
