// A clamping experiment built in code and its curve identified, without any file: the clamped joint rig of
// [KR300Thesis] (motor with rotor inertia, elasto-backlash gear, Coulomb friction on the motor shaft, output
// clamped) is driven by a torque triangle; its (motor angle, motor torque) curve goes to the identification of
// stiffness, backlash and friction ([KR300Thesis, Algorithm II] + Ceres). Exits 1 when an identified value is
// more than 3 % from the simulated truth (the test suite runs it).
#include <cmath>
#include <cstdio>
#include <memory>

#include <jointsim/jointsim.hpp>

using namespace jointsim;

int main() try {
  const double c = 25.7, b = 0.0102, F = 1.91;  // N·m/rad, rad, N·m (motor side, [KR300Thesis, Table 6.1])

  systems::JointRigSetup rig;
  rig.name = "clamping_in_code";
  rig.rotor_inertia = 0.01;  // kg·m²
  drive::ElastoBacklashParams eb;
  eb.stiffness = c;
  eb.backlash = b;
  eb.damping = 0.5;  // N·m·s/rad
  rig.transmission = std::make_shared<drive::ElastoBacklash>(eb);
  drive::TableFrictionParams fp;
  fp.tau_pos = {{{0.0, F}}, {{1.0, F}}};
  fp.peak = 1.0;
  rig.friction = std::make_shared<drive::TableFriction>(fp);
  rig.clamped = true;
  rig.input = systems::RigInput::MotorTorque;
  rig.profile = control::Profile::triangle(5.0, 40.0, 0.5);  // ±5 N·m about 0.5 N·m, period 40 s
  rig.duration = 200.0;                                      // 10 half-cycles
  rig.log_rate = 50.0;
  systems::JointRig plant(rig);
  const sim::SignalTable log = sim::simulateTable(plant, plant.simulateOptions());

  identify::ClampingData data;
  data.source = "in memory";
  data.time = log["time"];
  data.angle = log["motor_angle"];
  data.torque = log["motor_torque"];
  const identify::ClampingFitResult fit = identify::identifyClamping(data);

  auto report = [](const char* name, const identify::FittedParameter& p, double truth, const char* unit) {
    const double rel = p.value / truth - 1.0;
    std::printf("%-10s %.5g %s (truth %.5g, %+.2f %%, std error %.2g)\n", name, p.value, unit, truth, 100 * rel,
                p.std_error);
    return std::abs(rel) <= 0.03;
  };
  bool ok = report("stiffness", fit.stiffness, c, "N*m/rad");
  ok = report("backlash", fit.backlash, b, "rad") && ok;
  ok = report("friction", fit.friction, F, "N*m") && ok;
  std::printf("%ld samples, RMS residual %.3g N*m\n", static_cast<long>(data.time.size()), fit.rms_residual);
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "clamping_identify: %s\n", e.what());
  return 2;
}
