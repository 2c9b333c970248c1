// A user's computed-torque controller around the UR5 digital twin at 1 kHz on the motor-torque command port (the
// drives' cascades and motor electrics bypassed: the command is the electromagnetic torque at each rotor). The law
// inverts the rigid model the user knows — the multibody's RNEA plus each rotor's inertia through its gear ratio:
//
//   q̈_c = q̈_r + K_d (q̇_r − q̇) + K_p (q_r − q) + K_i ∫(q_r − q) dt,
//   τ_m,k = τ_k(q, q̇, q̈_c) / N_k + J_M,k N_k q̈_c,k   (the rotor term for compliant gears only)
//
// with τ = RNEA(q, q̇, q̈_c) = M(q) q̈_c + C(q, q̇) q̇ + g(q) [Siciliano2009, §8.5.2] — and leaves to the feedback
// what the twin has and the law does not: the strain-wave gears' compliance and losses and the LuGre friction (the
// integral term holds against the friction). The
// angles are the joints' (output encoders); the rate is the motor's reduced to the joint (motor encoder), collocated
// with the torque as in pd_voltage_ur5. The reference moves every joint by 0.1 rad with a quintic blend from 0.2 s
// to 0.7 s.
//
//   computed_torque_ur5 [ROBOT_WITH_DRIVES.yaml] [DURATION_S] [RTOL] [FIXED_STEP_S]
//
// FIXED_STEP_S > 0: the fixed-step method (solver method rosenbrock) with that step instead of BDF at RTOL.
//
// Prints the tracking error and the real-time factor of the loop; exits 1 when a joint is further than 5 mrad from
// its reference during the move or after it (the test suite runs it).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include <jointsim/jointsim.hpp>

using namespace jointsim;

namespace {
/// Quintic blend s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ over [t0, t1] and its first two time derivatives [1, 1/s, 1/s²].
void blend(double t, double t0, double t1, double& s, double& sd, double& sdd) {
  const double T = t1 - t0, tau = std::clamp((t - t0) / T, 0.0, 1.0);
  s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
  sd = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / T;
  sdd = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (T * T);
}
}  // namespace

int main(int argc, char** argv) try {
  const std::string robot_file = argc > 1 ? argv[1] : "config/robots/ur5_drives.yaml";
  const double duration = argc > 2 ? std::stod(argv[2]) : 1.5;
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

  sim::CvodeOptions solver = sim::stiffDriveSolver(rtol, 1e-9);
  solver.max_gamma_change = 0.5;
  if (fixed_step > 0.0) {
    solver.method = sim::Method::Rosenbrock;
    solver.fixed_step = fixed_step;
    if (adaptive) sim::setAdaptiveJacobian(solver);
  }
  sim::Simulator sim(robot, solver);
  for (int k = 0; k < n; ++k) robot.setCommandPort(sim.plantState(), k, systems::CommandPort::MotorTorque);

  // Gains of the error dynamics e⃛ + K_d ë + K_p ė + K_i e = 0 with a triple pole at −ω, ω = 40 rad/s (well below the
  // 1 kHz sampling and the gears' modes).
  const double w = 40.0, Kd = 3.0 * w, Kp = 3.0 * w * w, Ki = w * w * w, dt = 1e-3, t0 = 0.2, t1 = 0.7;
  multibody::Data data(robot.model());
  Eigen::VectorXd tau_m(n), qr(n), qdr(n), qddr(n), qd(n), qdd_c(n), e_int = Eigen::VectorXd::Zero(n);
  double worst = 0.0, worst_moving = 0.0;
  const auto wall0 = std::chrono::steady_clock::now();
  while (sim.time() < duration - 1e-9) {
    double s, sd, sdd;
    blend(sim.time(), t0, t1, s, sd, sdd);
    qr = q0.array() + 0.1 * s;
    qdr.setConstant(0.1 * sd);
    qddr.setConstant(0.1 * sdd);
    const auto q = sim.state().head(n);
    for (int k = 0; k < n; ++k)
      qd[k] = robot.motorVelocity(sim.state(), k) / robot.drives()[static_cast<size_t>(k)].transmission->ratio();
    qdd_c = qddr + Kd * (qdr - qd) + Kp * (qr - q) + Ki * e_int;
    e_int += dt * (qr - q);
    const Eigen::VectorXd& tau = multibody::rnea(robot.model(), data, q, qd, qdd_c);
    for (int k = 0; k < n; ++k) {
      const auto& d = robot.drives()[static_cast<size_t>(k)];
      const double N = d.transmission->ratio();
      // (A rigid gear merges the rotor into the joint: the model's armature N² J_M, inside RNEA's τ, already has it.)
      tau_m[k] = tau[k] / N + (robot.layout(k).rigid ? 0.0 : d.motor.J_M * N * qdd_c[k]);
    }
    robot.setCommands(sim.plantState(), tau_m);
    sim.advance(dt);
    blend(sim.time(), t0, t1, s, sd, sdd);
    const double err = (q0.array() + 0.1 * s - sim.state().head(n).array()).abs().maxCoeff();
    worst = std::max(worst, err);
    if (sim.time() <= t1 + 1e-9) worst_moving = std::max(worst_moving, err);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf(
      "computed-torque control of '%s' at 1 kHz on the motor-torque port: %.3f s simulated in %.3f s (real-time "
      "factor %.1f)\n",
      robot.model().name.c_str(), sim.time(), wall, sim.time() / wall);
  const sim::SolverStats st = sim.stats();
  if (fixed_step > 0.0)
    std::printf("fixed-step method, step %g s (%ld shortened, %ld retaken)\n", fixed_step, st.split_steps,
                st.retaken_steps);
  std::printf("solver (rtol %g): %ld steps, %ld RHS evaluations, %ld Jacobians, %ld error test failures\n", rtol,
              st.steps, st.rhs_evals, st.jac_evals, st.error_test_failures);
  std::printf("largest tracking error: %.3f mrad during the move, %.3f mrad overall (bound 5 mrad)\n",
              1e3 * worst_moving, 1e3 * worst);
  return worst > 5e-3 ? 1 : 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "computed_torque_ur5: %s\n", e.what());
  return 2;
}
