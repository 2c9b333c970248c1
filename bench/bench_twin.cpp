// The UR5 digital twin's right-hand side and Jacobian (config/robots/ur5_drives.yaml: 6 joints, strain-wave
// gears, LuGre friction, cascaded controllers), the costs that set the twin's real-time factor.
// Run: ./build/bench/bench_twin
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>

#include "jointsim/systems/robot_with_drives.hpp"
#include "sim/block_linear_solver.hpp"

using namespace jointsim;

namespace {
systems::RobotSystem& twin() {
  static systems::RobotSystem sys =
      systems::loadRobotWithDrives(std::string(JOINTSIM_SOURCE_DIR) + "/config/robots/ur5_drives.yaml");
  return sys;
}
Eigen::VectorXd state(const systems::RobotSystem& sys) {
  Eigen::VectorXd q0(6);
  q0 << 0.3, -1.2, 1.2, -1.5, -1.5708, 0.2;
  Eigen::VectorXd y = sys.initialState(q0);
  y.segment(6, 6).setConstant(0.4);  // joints moving
  return y;
}
/// The twin at state(): its run state started there, f = f(0.5, y) and the difference increments of the Jacobians.
struct TwinPoint {
  explicit TwinPoint(const systems::RobotSystem& sys) : y(state(sys)), run(sys.makeState()), f(y.size()) {
    sys.start(*run, 0.0, y);
    sys.derivatives(*run, 0.5, y, f);
    inc = 1e-7 * y.cwiseAbs().cwiseMax(1e-2);
  }
  Eigen::VectorXd y;
  std::unique_ptr<sim::PlantState> run;
  Eigen::VectorXd f, inc;
};
}  // namespace

static void UR5_Twin_RHS(benchmark::State& st) {
  auto& sys = twin();
  const Eigen::VectorXd y = state(sys);
  const std::unique_ptr<sim::PlantState> run = sys.makeState();
  sys.start(*run, 0.0, y);
  Eigen::VectorXd yd(y.size());
  for (auto _ : st) {
    sys.derivatives(*run, 0.5, y, yd);
    benchmark::DoNotOptimize(yd.data());
  }
  st.counters["states"] = static_cast<double>(y.size());
}
BENCHMARK(UR5_Twin_RHS);

// The structured Jacobian (hub columns plus one evaluation per drive-state index; RobotSystem::jacobian) against
// plain forward differences of every column (what CVODE's dense difference quotients cost), same increments.
static void UR5_Twin_Jacobian(benchmark::State& st) {
  auto& sys = twin();
  const TwinPoint p(sys);
  const Eigen::VectorXd &y = p.y, &f = p.f, &inc = p.inc;
  const std::unique_ptr<sim::PlantState>& run = p.run;
  const Eigen::Index n = y.size();
  Eigen::MatrixXd J(n, n);
  Eigen::VectorXd yp = y, fp(n);
  for (auto _ : st) {
    J.setZero();
    if (st.range(0) >= 1) {
      sys.jacobian(*run, 0.5, y, f, inc, J,
                   st.range(0) == 2 ? sim::JacobianKind::Analytic : sim::JacobianKind::Differences);
    } else {
      for (Eigen::Index j = 0; j < n; ++j) {
        yp[j] += inc[j];
        sys.derivatives(*run, 0.5, yp, fp);
        J.col(j) = (fp - f) / inc[j];
        yp[j] = y[j];
      }
    }
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(UR5_Twin_Jacobian)->Arg(2)->Arg(1)->Arg(0)->ArgName("structured");  // 2: analytic multibody, 1: differences

// The fixed-step method's Newton matrix I − γhJ (ROS2's γ = 1 + 1/√2, FixedStepIntegrator) of the twin's structured
// Jacobian: its block factorisation (one per step) and one solve (two per step), at h = 1 ms (the 1 kHz user loops)
// and 50 µs (20 kHz).
static void UR5_Twin_NewtonMatrix(benchmark::State& st) {
  auto& sys = twin();
  const TwinPoint p(sys);
  const Eigen::Index n = p.y.size();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  sys.jacobian(*p.run, 0.5, p.y, p.f, p.inc, J, sim::JacobianKind::Analytic);
  sim::DirectSolver solver(n, sys.jacobianStructure());
  const double gh = (1.0 + std::sqrt(0.5)) * (st.range(1) == 0 ? 1e-3 : 5e-5);
  Eigen::VectorXd x(n);
  if (!solver.factorIdentityMinus(J, gh)) st.SkipWithError("singular");
  for (auto _ : st) {
    if (st.range(0) == 0) {
      benchmark::DoNotOptimize(solver.factorIdentityMinus(J, gh));
    } else {
      solver.solve(p.f, x);
      benchmark::DoNotOptimize(x.data());
    }
  }
}
BENCHMARK(UR5_Twin_NewtonMatrix)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"solve", "h50us"});

BENCHMARK_MAIN();
