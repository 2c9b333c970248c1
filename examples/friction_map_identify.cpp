// A friction map identified from a simulated rig, measured the way a test bench does it: a user loop steps the
// velocity reference of the rig's PI speed controller (its command port) through plateaus, averages the motor
// torque over the second half of each plateau (at constant speed it balances the friction), and fits the static
// map of [Hauschild2003, eq. 4.6] per direction. The rig's friction is LuGre with the parameters of
// [Hauschild2003, Table 4.3]; exits 1 when α0, α1 or α2 of either direction is more than 3 % off (the test suite
// runs it).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <jointsim/jointsim.hpp>

using namespace jointsim;

int main() try {
  drive::LuGreParams truth;  // the defaults are [Hauschild2003, Table 4.3]
  systems::JointRigSetup s;
  s.name = "friction_bench";
  s.rotor_inertia = 1e-3;
  s.transmission = std::make_shared<drive::RigidGear>(1.0);
  s.friction = std::make_shared<drive::LuGreFriction>(truth);
  s.friction_side = systems::Side::Output;
  s.load_inertia = 3.41;  // kg·m²
  s.input = systems::RigInput::VelocityPI;
  s.pi = {200.0, 4000.0, 60.0, false, systems::Side::Output};  // kp, ki, limit 60 N·m, torque output, output speed
  s.solver.rtol = 1e-8;
  s.solver.atol = 1e-10;
  systems::JointRig rig(s);
  sim::Simulator sim(rig, s.solver);
  const int iv = sim.signalIndex("output_velocity"), iq = sim.signalIndex("motor_torque");

  std::vector<double> v, tau;
  const auto wall0 = std::chrono::steady_clock::now();
  const int n = 16;
  for (int dir : {1, -1})
    for (int k = n - 1; k >= 0; --k) {
      const double w = 5e-3 * std::pow(0.6 / 5e-3, static_cast<double>(k) / (n - 1));  // rad/s
      // Long enough for the bristles (σ0) and the PI loop to settle at this speed.
      const double plateau = std::max(3.0, 10.0 * 9.4 / (truth.sigma0 * w));
      rig.setCommand(sim.plantState(), dir * w);
      const double t0 = sim.time();
      double sum_v = 0, sum_tau = 0;
      int count = 0;
      while (sim.time() < t0 + plateau - 1e-9) {
        sim.advance(0.25);
        if (sim.time() >= t0 + 0.5 * plateau) {
          sum_v += sim.signals()[iv];
          sum_tau += sim.signals()[iq];
          ++count;
        }
      }
      v.push_back(sum_v / count);
      tau.push_back(sum_tau / count);
    }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const identify::FrictionFit fit = identify::fitFrictionMap(v, tau);

  bool ok = true;
  auto row = [&ok](const char* name, double est, double t) {
    const double rel = est / t - 1.0;
    std::printf("  %-7s %.5g (truth %.5g, %+.2f %%)\n", name, est, t, 100 * rel);
    return ok = ok && std::abs(rel) <= 0.03;
  };
  for (const auto& [d, t] : {std::pair{&fit.positive, truth.positive}, std::pair{&fit.negative, truth.negative}}) {
    std::printf("%s direction (%d plateaus):\n", d->direction.c_str(), d->points);
    row("alpha0", d->alpha0.value, t.alpha0);
    row("alpha1", d->alpha1.value, t.alpha1);
    row("alpha2", d->alpha2.value, t.alpha2);
    std::printf("  v_s     %.4g rad/s (truth %.4g)\n", d->v_s.value, t.v_s);
  }
  std::printf("%.0f s of bench time simulated in %.2f s\n", sim.time(), wall);
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "friction_map_identify: %s\n", e.what());
  return 2;
}
