// The validation protocol's noisy case (issue of the fixed-step method, docs/design.md "Fixed-step integration"):
// config/experiments/ur5_excitation_realtime.yaml (20 kHz sampled control, quantised and noisy sensors) over several
// noise seeds, once with the fixed-step method and once with CVODE's BDF at rtol 1e-9 (the reference). Per joint three
// closed-loop statistics over the run, from the log at the control rate: the tracking RMS of q − q_set [rad], the RMS
// of the motor current [A], and the RMS of its sample-to-sample change [A] (the current's high-frequency content,
// where the sensor noise and the current loop show). For every statistic the counters compare the fixed-step mean
// over the seeds with the reference's: worst_z is the largest |mean_fixed − mean_ref| / std_ref, worst_rel the largest
// |mean_fixed − mean_ref| / mean_ref (and where: worst_z_index = 3·joint + statistic).
// Run: ./build/bench/bench_noise_seeds   (about 70 s: the reference costs ~12 s per seed; a table on stderr)
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"

using namespace jointsim;

namespace {

constexpr int kSeeds = 5;
constexpr double kDuration = 0.3;  // s

// Per joint: tracking RMS, current RMS, RMS of the current's increments.
std::vector<double> statistics(const sim::SignalTable& log, const std::vector<std::string>& joints) {
  std::vector<double> out;
  for (const std::string& j : joints) {
    const Eigen::VectorXd e = log["q_" + j + "[rad]"] - log["q_set_" + j + "[rad]"];
    const Eigen::VectorXd i = log["current_" + j + "[A]"];
    const Eigen::Index n = i.size();
    const Eigen::VectorXd di = i.tail(n - 1) - i.head(n - 1);
    out.push_back(std::sqrt(e.squaredNorm() / static_cast<double>(e.size())));
    out.push_back(std::sqrt(i.squaredNorm() / static_cast<double>(n)));
    out.push_back(std::sqrt(di.squaredNorm() / static_cast<double>(n - 1)));
  }
  return out;
}

// The reference's statistics per seed (computed once for all arguments) and its wall time [s].
const std::vector<std::vector<double>>& reference(const std::string& file, const std::vector<std::string>& joints,
                                                  double& wall) {
  static std::vector<std::vector<double>> ref;
  static double wall_ref = 0.0;
  if (ref.empty())
    for (int seed = 1; seed <= kSeeds; ++seed) {
      auto r = experiments::loadExperiment(file, {"duration=" + std::to_string(kDuration), "log_rate=20000",
                                                  "control.seed=" + std::to_string(seed), "solver.method=bdf",
                                                  "solver.rtol=1e-9", "solver.atol=1e-11"});
      const auto rr = experiments::runInMemory(*r);
      ref.push_back(statistics(rr.log, joints));
      wall_ref += rr.result.wall_time_s;
    }
  wall = wall_ref;
  return ref;
}

}  // namespace

// Argument: fixed steps per control period (1: solver.step = 50 µs, 2: 25 µs).
static void NoiseSeeds_FixedStepAgainstBdfReference(benchmark::State& st) {
  const std::string file = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/ur5_excitation_realtime.yaml";
  const std::vector<std::string> joints = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                           "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  std::vector<std::vector<double>> fixed;
  double wall_fixed = 0.0, wall_ref = 0.0;
  for (auto _ : st) {
    for (int seed = 1; seed <= kSeeds; ++seed) {
      auto f =
          experiments::loadExperiment(file, {"duration=" + std::to_string(kDuration), "log_rate=20000",
                                             "control.seed=" + std::to_string(seed),
                                             "+solver.step=" + formatNumber(5e-5 / static_cast<double>(st.range(0)))});
      const auto rf = experiments::runInMemory(*f);
      fixed.push_back(statistics(rf.log, joints));
      wall_fixed += rf.result.wall_time_s;
    }
  }
  const auto& ref = reference(file, joints, wall_ref);
  const char* names[] = {"tracking RMS [rad]", "current RMS [A]", "current increment RMS [A]"};
  const size_t m = fixed.front().size();
  double worst_z = 0.0, worst_rel = 0.0, worst_index = -1.0, spread_rel = 0.0;
  for (size_t k = 0; k < m; ++k) {
    double mf = 0.0, mr = 0.0;
    for (int s = 0; s < kSeeds; ++s) {
      mf += fixed[static_cast<size_t>(s)][k] / kSeeds;
      mr += ref[static_cast<size_t>(s)][k] / kSeeds;
    }
    double var = 0.0;
    for (int s = 0; s < kSeeds; ++s) var += std::pow(ref[static_cast<size_t>(s)][k] - mr, 2) / (kSeeds - 1);
    const double sd = std::sqrt(var);
    const double z = std::abs(mf - mr) / sd;
    if (z > worst_z) {
      worst_z = z;
      worst_index = static_cast<double>(k);
    }
    worst_rel = std::max(worst_rel, std::abs(mf - mr) / mr);
    std::fprintf(stderr, "%-20s %-26s reference %.6g ± %.2g, fixed step %.6g (z = %.2f)\n", joints[k / 3].c_str(),
                 names[k % 3], mr, sd, mf, z);
    spread_rel = std::max(spread_rel, sd / mr);
  }
  st.counters["seeds"] = kSeeds;
  st.counters["worst_z"] = worst_z;
  st.counters["worst_z_index"] = worst_index;
  st.counters["worst_rel"] = worst_rel;
  st.counters["largest_ref_spread_rel"] = spread_rel;
  st.counters["rtf_fixed"] = kSeeds * kDuration / wall_fixed;
  st.counters["rtf_ref"] = kSeeds * kDuration / wall_ref;
}
BENCHMARK(NoiseSeeds_FixedStepAgainstBdfReference)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond);

BENCHMARK_MAIN();
