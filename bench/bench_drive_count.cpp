// Cost over the number of drives: a generated serial chain of n revolute joints (n = 6, 12, 24, 48), one UR5 drive
// per joint (the six drives of config/robots/ur5_drives.yaml repeated in order: DC motor with electrics, strain-wave
// gear, LuGre friction, voltage cascade), following a Fourier excitation. Counters: solver steps, wall time per step
// [µs] and the real-time factor (simulated seconds per wall-clock second), for continuous control (CVODE BDF, rtol
// 1e-6, atol 1e-9, the structured Jacobian, as `type: tracking`) and sampled control at 20 kHz (the drives' own
// sensors), with CVODE and with the fixed-step method (ROS2, one step per control period, solver.method rosenbrock).
// The per-step cost growth with the number of drives (docs/performance.md).
// Run: ./build/bench/bench_drive_count
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "jointsim/control/trajectory.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

using namespace jointsim;

namespace {

// n revolute joints about the vertical axis, 0.12 m apart along x (a horizontal arm: gravity exerts no joint
// torque, so the UR5's drives hold any length), links of 0.8 kg with the inertia of a 0.12 m rod and a 0.03 m
// radius.
multibody::Model chain(int n) {
  multibody::ModelBuilder b("chain" + std::to_string(n), "base");
  std::string parent = "base";
  for (int k = 0; k < n; ++k) {
    multibody::JointSpec j;
    j.name = "j" + std::to_string(k + 1);
    j.axis = Eigen::Vector3d::UnitZ();
    if (k > 0) j.origin.p = Eigen::Vector3d(0.12, 0.0, 0.0);
    multibody::BodyInertia I;
    I.mass = 0.8;
    I.com = Eigen::Vector3d(0.06, 0.0, 0.0);
    const double rod = I.mass * 0.12 * 0.12 / 12.0, disc = 0.5 * I.mass * 0.03 * 0.03;
    I.inertia = Eigen::Vector3d(disc, rod, rod).asDiagonal();
    const std::string link = "link" + std::to_string(k + 1);
    b.addLink(parent, j, link, I);
    parent = link;
  }
  return b.build();
}

// The chain with one UR5 drive per joint, following a Fourier excitation of two harmonics at 0.5 Hz about zero
// (amplitudes decreasing along the chain, no fade-in beyond 0.05 s so the run is mostly motion).
std::unique_ptr<systems::RobotSystem> robot(int n) {
  static const systems::RobotSystem ur5 =
      systems::loadRobotWithDrives(std::string(JOINTSIM_SOURCE_DIR) + "/config/robots/ur5_drives.yaml");
  std::vector<systems::DriveSpec> drives;
  for (int k = 0; k < n; ++k) {
    systems::DriveSpec d = ur5.drives()[static_cast<size_t>(k % 6)];
    d.joint = "j" + std::to_string(k + 1);
    drives.push_back(d);
  }
  auto sys = std::make_unique<systems::RobotSystem>(chain(n), drives);
  control::FourierParams f;
  f.base_frequency = 0.5;
  f.offset = Eigen::VectorXd::Zero(n);
  f.a = Eigen::MatrixXd::Zero(n, 2);
  f.b = Eigen::MatrixXd::Zero(n, 2);
  for (int k = 0; k < n; ++k) {
    f.a(k, 0) = 0.6 / (1.0 + 0.05 * k);  // rad/s
    f.b(k, 1) = 0.3 / (1.0 + 0.05 * k);
  }
  f.fade_in = 0.05;
  f.duration = 10.0;
  sys->setTrajectory(std::make_shared<control::FourierTrajectory>(f));
  return sys;
}

// One run of `duration` per iteration; range(0): the number of drives; range(1): 0 continuous control, else the
// sampled control rate [Hz]; `fixed_step`: ROS2 with one step per control period instead of CVODE, its Jacobian renewed
// at every step or (`adaptive`) kept while it describes the steps (jacobian_every: adaptive).
void DriveCount(benchmark::State& state, double duration, bool fixed_step, bool adaptive = false) {
  const int n = static_cast<int>(state.range(0));
  const double rate = static_cast<double>(state.range(1));
  std::unique_ptr<systems::RobotSystem> sys = robot(n);
  if (rate > 0) sys->setSampledControl(rate, 1);
  sim::SimulateOptions o = sim::SimulateOptions::atRate(duration, 100.0, sim::stiffDriveSolver(1e-6, 1e-9));
  if (fixed_step) o.solver.method = sim::Method::Rosenbrock;  // step 0: the control period
  if (adaptive) sim::setAdaptiveJacobian(o.solver);
  long steps = 0, jacobians = 0;
  double wall = 0.0;  // [s], summed over the iterations
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = sim::simulate(*sys, o, [](const Eigen::VectorXd& row) { benchmark::DoNotOptimize(row.data()); });
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    steps = r.stats.steps;
    jacobians = r.stats.jac_evals;
  }
  const double runs = static_cast<double>(state.iterations());
  state.counters["drives"] = n;
  state.counters["states"] = sys->stateSize();
  state.counters["solver_steps"] = static_cast<double>(steps);
  state.counters["jacobians"] = static_cast<double>(jacobians);
  state.counters["real_time_factor"] = duration * runs / wall;
  state.counters["us_per_step"] = 1e6 * wall / (runs * static_cast<double>(steps));
}

}  // namespace

// Continuous control: 0.25 s of the excitation.
BENCHMARK_CAPTURE(DriveCount, continuous, 0.25, false)
    ->ArgsProduct({{6, 12, 24, 48}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
// Sampled control at 20 kHz: 0.05 s (1,000 control periods).
BENCHMARK_CAPTURE(DriveCount, sampled_20kHz, 0.05, false)
    ->ArgsProduct({{6, 12, 24, 48}, {20000}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
// The same with the fixed-step method. (Not longer: at 24 drives the fixed step stops at 0.066 s, a growing mode of a
// wrist-like joint no halving follows — STEP_UNSTABLE —, with the Jacobian renewed at every step or adaptive.)
BENCHMARK_CAPTURE(DriveCount, sampled_20kHz_fixed_step, 0.05, true)
    ->ArgsProduct({{6, 12, 24, 48}, {20000}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
// The same with the adaptive Jacobian.
BENCHMARK_CAPTURE(DriveCount, sampled_20kHz_fixed_step_adaptive, 0.05, true, true)
    ->ArgsProduct({{6, 12, 24, 48}, {20000}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK_MAIN();
