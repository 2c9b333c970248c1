// Faults on a joint rig's drive (named `rig`): the KR300 joint-1 clamping rig of [KR300Thesis] with a worn gear and
// added backlash, checked against the elasto-backlash law at the clamping curve's turning points.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/faults.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

const std::string kRig = test::sourcePath("config/experiments/kr300_joint1_clamping.yaml");

// Transmission torque over (|φ| − b/2) at the largest motor angle φ (the output is clamped at 0, the model is on the
// motor side with ratio 1, so φ is the deflection; the triangle input is slow, so the damper is idle there).
double stiffnessAtTheTurningPoint(const std::vector<systems::Fault>& faults, double backlash) {
  auto e = experiments::loadExperiment(kRig, {"duration=20"}, faults);
  const auto r = experiments::runInMemory(*e);
  const Eigen::VectorXd phi = r.log["motor_angle"], tau = r.log["transmission_torque_in"];
  Eigen::Index k = 0;
  phi.cwiseAbs().maxCoeff(&k);
  return std::abs(tau[k]) / (std::abs(phi[k]) - backlash / 2);
}

systems::Fault fault(systems::FaultType type, double value, const std::string& joint = "rig") {
  systems::Fault f;
  f.type = type;
  f.joint = joint;
  f.value = value;
  return f;
}

}  // namespace

TEST(RigFaults, WornGearAndAddedBacklashOnTheKr300ClampingRig) {
  // Table 6.1: c = 25.7 N·m/rad, b = 0.0102 rad.
  EXPECT_NEAR(stiffnessAtTheTurningPoint({}, 0.0102), 25.7, 0.01 * 25.7);
  EXPECT_NEAR(stiffnessAtTheTurningPoint({fault(systems::FaultType::GearStiffnessScale, 0.5)}, 0.0102), 12.85,
              0.01 * 12.85);
  EXPECT_NEAR(stiffnessAtTheTurningPoint({fault(systems::FaultType::BacklashAdd, 0.05)}, 0.0602), 25.7, 0.01 * 25.7);
}

TEST(RigFaults, FaultsTheRigCannotTakeAreRefusedWithTheReason) {
  auto refused = [](const systems::Fault& f, const std::string& why) {
    try {
      experiments::loadExperiment(kRig, {}, {f});
      ADD_FAILURE() << "expected an InputError for " << systems::describe(f);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused(fault(systems::FaultType::GearStiffnessScale, 0.5, "joint1"), "called 'rig'");
  refused(fault(systems::FaultType::SensorBias, 0.01), "sensors and controllers");
  refused(fault(systems::FaultType::TorqueConstantScale, 0.5), "electrics");  // a torque-driven rig has no k_t
  systems::Fault later = fault(systems::FaultType::GearStiffnessScale, 0.5);
  later.onset = 1.0;
  refused(later, "time law");
}

// The RobotR3 one-axis model (its drive named `axis`): a worn gear halves the spring c in the load's equation of motion
// J_L q̈ = −N (c φ_rel + d w_rel), checked on the right-hand side at a state in motion; a demagnetised motor (k × 0.8)
// needs 1/0.8 of the current for the same motor torque.
TEST(AxisFaults, RobotR3AxisSpringAndTorqueConstantThroughTheFaults) {
  const std::string path = test::sourcePath("config/experiments/robotr3_one_axis.yaml");
  auto nominal = experiments::loadExperiment(path, {"stop_time=0.4"});
  auto worn = experiments::loadExperiment(path, {"stop_time=0.4"},
                                          {fault(systems::FaultType::GearStiffnessScale, 0.5, "axis")});
  sim::Simulator s(worn->plant(), worn->simulateOptions().solver);
  s.advanceTo(0.3);
  const Eigen::VectorXd y = s.state();
  Eigen::VectorXd ydot(y.size());
  worn->plant().derivatives(s.plantState(), 0.3, y, ydot);
  const double N = 210.0, c = 8.0 * 0.5, d = 0.01, J_L = 19.5;  // robotr3_one_axis.yaml
  ASSERT_GT(std::abs(y[2]), 1e-4);                              // the spring is loaded
  EXPECT_NEAR(ydot[1], -N * (c * y[2] + d * y[3]) / J_L, 1e-12 * N * 8.0 / J_L);
  // The torque constant: the same motion needs 1/0.8 of the current (the current is k-independent otherwise).
  auto weak = experiments::loadExperiment(path, {"stop_time=0.4"},
                                          {fault(systems::FaultType::TorqueConstantScale, 0.8, "axis")});
  const auto a = experiments::runInMemory(*nominal), b = experiments::runInMemory(*weak);
  const double ia = a.log["axis.motor.La.i"].cwiseAbs().maxCoeff(), ib = b.log["axis.motor.La.i"].cwiseAbs().maxCoeff();
  EXPECT_NEAR(ib / ia, 1.0 / 0.8, 0.02);
  try {
    experiments::loadExperiment(path, {}, {fault(systems::FaultType::GearStiffnessScale, 0.5, "r1")});
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("called 'axis'"), std::string::npos) << e.what();
  }
}

// A drive chain's element named by its name: a shaft of 2 kg·m² driven by 10 N·m against a bearing of 2 N·m slides
// with (10 − 2)/2 = 4 rad/s²; coulomb_friction_scale 2 on the bearing makes it (10 − 4)/2 = 3 rad/s² (closed form);
// a spring's stiffness is refused on a bearing, naming what it lacks.
TEST(ChainFaults, BearingFrictionScaledAgainstTheClosedForm) {
  const test::TempDir dir;
  const std::string path = (dir / "chain.yaml").string();
  std::ofstream(path) << R"(experiment: {name: chain, type: drive_chain}
inertias: [{name: shaft, J: 2.0}]
elements:
  - {name: motor, type: torque, on: shaft, profile: {type: constant, value: 10}}
  - {name: bearing, type: bearing_friction, from: ground, to: shaft, tau_pos: [[0, 2.0]], peak: 1}
duration: 1.0
log_rate: 10
)";
  auto speed = [&](const std::vector<systems::Fault>& faults) {
    auto e = experiments::loadExperiment(path, {}, faults);
    const auto r = experiments::runInMemory(*e);
    return r.log["shaft.w"][r.log.values.rows() - 1];
  };
  EXPECT_NEAR(speed({}), 4.0, 1e-6);
  EXPECT_NEAR(speed({fault(systems::FaultType::CoulombFrictionScale, 2.0, "bearing")}), 3.0, 1e-6);
  try {
    speed({fault(systems::FaultType::GearStiffnessScale, 0.5, "bearing")});
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no stiffness parameter"), std::string::npos) << e.what();
  }
}
