// Whole-simulation timings: the passive UR5 fall (ABA inside CVODE Adams), reported as a real-time
// factor counter (simulated seconds per wall-clock second). Run: ./build/bench/bench_simulation
#include <benchmark/benchmark.h>

#include "jointsim/experiments/passive_robot.hpp"
#include "jointsim/multibody/robot_loader.hpp"

using namespace jointsim;

static void UR5_Fall_1s_Adams(benchmark::State& state) {
  const auto model = multibody::loadRobot(std::string(JOINTSIM_SOURCE_DIR) + "/config/robots/ur5.yaml");
  experiments::PassiveRobotParams p;
  p.q0.resize(6);
  p.q0 << 0.0, -1.2, 0.8, -0.5, 0.7, 0.0;
  p.duration = 1.0;
  p.log_rate = 100.0;
  p.solver.rtol = static_cast<double>(state.range(0)) * 1e-10;  // 1e-8 by default
  long steps = 0;
  for (auto _ : state) {
    const auto r = experiments::simulatePassiveRobot(model, p, [](const Eigen::VectorXd& row) {
      benchmark::DoNotOptimize(row.data());
    });
    steps = r.stats.steps;
  }
  state.counters["real_time_factor"] =
      benchmark::Counter(p.duration * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["cvode_steps"] = static_cast<double>(steps);
}
BENCHMARK(UR5_Fall_1s_Adams)->Arg(100)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
