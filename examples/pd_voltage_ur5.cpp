// A user's own controller closing the loop around the UR5 digital twin: a PD law with gravity feed-forward at
// 1 kHz commands the six motor voltages (the voltage command port: the drives' cascade controllers are
// bypassed, the PWM saturation at ±V_supply still applies). The arm steps by 0.1 rad on every joint at 0.2 s.
// The P term acts on the joint angle, the damping on the motor speed (the motor encoder's rate, collocated with
// the voltage): damping injected through the compliant gear from the link rate would excite the gear and
// friction modes the twin models, which a real drive avoids the same way.
//
//   pd_voltage_ur5 [ROBOT_WITH_DRIVES.yaml] [DURATION_S] [RTOL] [FIXED_STEP_S]
//
// FIXED_STEP_S > 0: the fixed-step method (ROS2, solver method rosenbrock; docs/design.md "Fixed-step integration")
// with that step instead of BDF at RTOL; a step dividing the 1 ms period keeps every loop iteration at the same cost.
//
// Prints the tracking error at the end and the real-time factor of the loop; exits 1 when a joint is further
// than 5 mrad from its reference 1.5 s after the step (the test suite runs it).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include <jointsim/jointsim.hpp>

using namespace jointsim;

int main(int argc, char** argv) try {
  const std::string robot_file = argc > 1 ? argv[1] : "config/robots/ur5_drives.yaml";
  const double duration = argc > 2 ? std::stod(argv[2]) : 2.0;
  const double rtol = argc > 3 ? std::stod(argv[3]) : 1e-4;
  const double fixed_step = argc > 4 ? std::stod(argv[4]) : 0.0;
  // A fifth argument "adaptive": the fixed step keeps its Jacobian while it describes the steps (jacobian_every:
  // adaptive of the experiment files, sim::CvodeOptions::jacobian_defect).
  const bool adaptive = argc > 5 && std::string(argv[5]) == "adaptive";

  systems::RobotSystem robot = systems::loadRobotWithDrives(robot_file);
  const int n = robot.dof();
  Eigen::VectorXd q0(n);
  q0 << 0.0, -1.2, 1.2, -1.5, -1.5708, 0.0;
  robot.setInitialPositions(q0);

  // BDF2 with a direct solver: the gear and friction modes are stiff (docs/design.md). rtol 1e-4 for a 1 kHz
  // loop: against an rtol 1e-10 run of this loop the joint angles stay within 3.5 µrad, the motor currents within
  // 6 mA (peak 37 A) and the joint rates within 5 mrad/s at every sample (docs/performance.md, "A user's loop at
  // 1 kHz"; test SampledPd.LooseToleranceStaysCloseToTightRun); the production rtol 1e-6 is about half as fast.
  sim::CvodeOptions solver = sim::stiffDriveSolver(rtol, 1e-9);
  solver.max_gamma_change = 0.5;  // fewer Newton matrix factorisations at the samples' stops and restarts
  if (fixed_step > 0.0) {
    solver.method = sim::Method::Rosenbrock;
    solver.fixed_step = fixed_step;
    if (adaptive) sim::setAdaptiveJacobian(solver);
  }
  sim::Simulator sim(robot, solver);
  // The robot is only read; the run's inputs live in the simulator's state.
  for (int k = 0; k < n; ++k) robot.setCommandPort(sim.plantState(), k, systems::CommandPort::Voltage);

  // PD gains on the joint angle [V/rad] and on the motor speed reduced to the joint [V·s/rad]; gravity
  // feed-forward through the steady current i = g / (N k_t), i.e. the voltage R i (the back-EMF and the friction
  // are left to the feedback).
  const double Kp = 200.0, Kd = 5.0, dt = 1e-3;
  multibody::Data data(robot.model());
  Eigen::VectorXd V(n), q_ref = q0;
  double worst_after_settling = 0.0;
  const auto wall0 = std::chrono::steady_clock::now();
  while (sim.time() < duration - 1e-9) {
    if (sim.time() >= 0.2 - 1e-9) q_ref = q0.array() + 0.1;
    const auto q = sim.state().head(n);  // joint angles (ideal sensors)
    const Eigen::VectorXd& g = multibody::gravityTorques(robot.model(), data, q);
    for (int k = 0; k < n; ++k) {
      const auto& d = robot.drives()[static_cast<size_t>(k)];
      const double N = d.transmission->ratio();
      V[k] =
          d.motor.R * g[k] / (N * d.motor.kt) + Kp * (q_ref[k] - q[k]) - Kd * robot.motorVelocity(sim.state(), k) / N;
    }
    robot.setCommands(sim.plantState(), V);
    sim.advance(dt);
    if (sim.time() >= 1.7 - 1e-9)
      worst_after_settling = std::max(worst_after_settling, (q_ref - sim.state().head(n)).cwiseAbs().maxCoeff());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const Eigen::VectorXd e = q_ref - sim.state().head(n);
  std::printf("PD voltage control of '%s' at 1 kHz: %.3f s simulated in %.3f s (real-time factor %.1f), %ld restarts\n",
              robot.model().name.c_str(), sim.time(), wall, sim.time() / wall, sim.restarts());
  const sim::SolverStats st = sim.stats();
  if (fixed_step > 0.0) std::printf("fixed-step method, step %g s\n", fixed_step);
  std::printf("solver (rtol %g): %ld steps, %ld RHS evaluations, %ld Jacobians (+%ld reused at restarts), %ld Newton "
              "matrix factorisations, %ld error test failures\n",
              rtol, st.steps, st.rhs_evals, st.jac_evals, st.jac_reused, st.lin_setups, st.error_test_failures);
  std::printf("final error [mrad]:");
  for (int k = 0; k < n; ++k) std::printf(" %.3f", 1e3 * e[k]);
  std::printf("\nlargest error from 1.7 s on: %.3f mrad (bound 5 mrad)\n", 1e3 * worst_after_settling);
  return duration >= 1.7 && worst_after_settling > 5e-3 ? 1 : 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "pd_voltage_ur5: %s\n", e.what());
  return 2;
}
