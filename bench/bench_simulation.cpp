// Whole-simulation timings: the passive UR5 fall (ABA inside CVODE Adams), reported as a real-time
// factor counter (simulated seconds per wall-clock second). Run: ./build/bench/bench_simulation
#include <benchmark/benchmark.h>

#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "jointsim/systems/passive_robot.hpp"

using namespace jointsim;

static void UR5_Fall_1s_Adams(benchmark::State& state) {
  const auto model = multibody::loadRobot(std::string(JOINTSIM_SOURCE_DIR) + "/config/robots/ur5.yaml");
  systems::PassiveRobotParams p;
  p.q0.resize(6);
  p.q0 << 0.0, -1.2, 0.8, -0.5, 0.7, 0.0;
  p.duration = 1.0;
  p.log_rate = 100.0;
  p.solver.rtol = static_cast<double>(state.range(0)) * 1e-10;  // 1e-8 by default
  systems::PassiveRobot plant(model, p);
  long steps = 0;
  for (auto _ : state) {
    const auto r = sim::simulate(plant, plant.simulateOptions(),
                                 [](const Eigen::VectorXd& row) { benchmark::DoNotOptimize(row.data()); });
    steps = r.stats.steps;
  }
  state.counters["real_time_factor"] =
      benchmark::Counter(p.duration * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["cvode_steps"] = static_cast<double>(steps);
}
BENCHMARK(UR5_Fall_1s_Adams)->Arg(100)->Unit(benchmark::kMillisecond);

// The UR5 base joint on the rig (config/experiments/ur5_swg_joint_velocity.yaml): DC motor, size-A
// strain-wave gear, UR5 LuGre friction, load 1.279 kg·m², motor-velocity PI on the voltage; 10 s.
static void UR5_SwgJointRig_10s(benchmark::State& state) {
  systems::JointRigSetup s;
  s.name = "bench";
  s.motor = drive::DcMotorParams::ur5(1);
  s.transmission = std::make_shared<drive::StrainWaveGear>(drive::StrainWaveGearParams::ur5SizeA());
  drive::LuGreUr5Params f;
  f.f_c = 4.0;
  f.f_v = 2.0;
  f.k_q = 0.0;
  s.friction = std::make_shared<drive::LuGreUr5Friction>(f);
  s.friction_side = systems::Side::Output;
  s.load_inertia = 1.279;
  s.input = systems::RigInput::VelocityPI;
  s.pi = {0.5, 20.0, 48.0, true, systems::Side::Motor};
  s.profile = control::Profile::piecewise({0, 1, 4, 5, 8, 9, 10}, {0, 101, 101, 0, 0, -50.5, -50.5});
  s.duration = 10.0;
  s.log_rate = 1000.0;
  s.solver.rtol = 1e-6;
  s.solver.atol = 1e-9;
  systems::JointRig rig(s);
  long steps = 0;
  for (auto _ : state) {
    const auto r = sim::simulate(rig, rig.simulateOptions(),
                                 [](const Eigen::VectorXd& row) { benchmark::DoNotOptimize(row.data()); });
    steps = r.stats.steps;
  }
  state.counters["real_time_factor"] =
      benchmark::Counter(s.duration * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["cvode_steps"] = static_cast<double>(steps);
}
BENCHMARK(UR5_SwgJointRig_10s)->Unit(benchmark::kMillisecond);

// Shipped experiment files through the experiment runner (CSV and summary written to a scratch directory):
// the UR5 digital twin (config/experiments/ur5_excitation.yaml, 10 s, 500 Hz log; the README's main job) and
// seed 000's IRB140 clamping demo (config/experiments/irb140_clamping.yaml, 15 s, all six axes swinging,
// 42 states with the clamp and bending modes and exact stick-slip, 200 Hz log and per-axis curves).
static void ExperimentFile(benchmark::State& state, const std::string& name) {
  experiments::RunOptions o;
  o.output_dir = "/tmp/jointsim_bench_" + name;
  double rtf = 0;
  long steps = 0;
  for (auto _ : state) {
    const auto r =
        experiments::runExperimentFile(std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/" + name + ".yaml", o);
    rtf = r.real_time_factor;
    steps = r.stats.steps;
  }
  state.counters["real_time_factor"] = rtf;
  state.counters["cvode_steps"] = static_cast<double>(steps);
}
BENCHMARK_CAPTURE(ExperimentFile, UR5_Twin_Excitation_10s, std::string("ur5_excitation"))
    ->Unit(benchmark::kSecond)
    ->Iterations(2);
BENCHMARK_CAPTURE(ExperimentFile, IRB140_Clamping_15s, std::string("irb140_clamping"))
    ->Unit(benchmark::kSecond)
    ->Iterations(2);

BENCHMARK_MAIN();
