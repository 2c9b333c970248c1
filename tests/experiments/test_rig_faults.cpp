// Faults on a joint rig's drive (named `rig`): the KR300 joint-1 clamping rig of [KR300Thesis] with a worn gear and
// added backlash, checked against the elasto-backlash law at the clamping curve's turning points.
#include <cmath>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
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
