// Fault injection: each fault type changes exactly the parameter it names (checked on the rebuilt
// components), faults that do not apply are rejected, and in closed loop a joint-angle sensor bias shifts
// the held posture by minus the bias while a weakened motor needs proportionally more current.
#include <cmath>
#include <memory>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;
using systems::Fault;
using systems::FaultType;
using ::testing::HasSubstr;

namespace {
systems::DriveSpec elasticDrive() {
  systems::DriveSpec d;
  d.joint = "j";
  drive::ElasticGearParams p;
  p.ratio = 101;
  p.stiffness = 1.4e5;
  p.damping = 60;
  p.side = drive::ComplianceSide::Output;
  d.transmission = std::make_shared<drive::ElasticGear>(p);
  drive::LuGreUr5Params f;
  f.f_c = 4.0;
  f.f_v = 2.0;
  f.k_q = 1.0;
  d.friction = std::make_shared<drive::LuGreUr5Friction>(f);
  d.motor = drive::DcMotorParams::ur5(2);
  return d;
}

// The UR5 twin (elastic gears) holding `q0` for 1.5 s with the given faults; returns the final state's
// joint angles and motor currents.
std::pair<Eigen::VectorXd, Eigen::VectorXd> hold(const std::vector<Fault>& faults) {
  systems::RobotSystem sys =
      systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives_elastic.yaml"), faults);
  Eigen::VectorXd q0(6);
  q0 << 0.2, -1.2, 1.0, -0.8, 0.5, 0.1;
  sys.setSetpoints(
      [q0](double, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd) {
        q = q0;
        qd.setZero();
        qdd.setZero();
      });
  sim::CvodeOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  o.max_order = 2;
  const auto st = sys.makeState();
  sim::CvodeIntegrator integ(
      sys.stateSize(),
      [&](double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
        sys.derivatives(*st, t, y, yd);
      },
      o);
  Eigen::VectorXd y = sys.initialState(q0);
  sys.start(*st, 0.0, y);
  integ.initialize(0.0, y);
  integ.advance(1.5, y);
  const auto& s = sys.driveSignals(*st, 1.5, y);
  return {y.head(6), s.current};
}
}  // namespace

TEST(Faults, EachTypeChangesTheParameterItNames) {
  systems::DriveSpec d = elasticDrive();
  systems::applyFault(d, {FaultType::GearStiffnessScale, "j", 0.8});
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::ElasticGear&>(*d.transmission).params().stiffness, 0.8 * 1.4e5);
  systems::applyFault(d, {FaultType::BacklashAdd, "j", 1e-3});
  const auto& eb = dynamic_cast<const drive::ElastoBacklash&>(*d.transmission).params();
  EXPECT_DOUBLE_EQ(eb.backlash, 1e-3);
  EXPECT_DOUBLE_EQ(eb.stiffness, 0.8 * 1.4e5);
  EXPECT_EQ(eb.side, drive::ComplianceSide::Output);
  EXPECT_DOUBLE_EQ(eb.ratio, 101);
  systems::applyFault(d, {FaultType::BacklashAdd, "j", 5e-4});
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::ElastoBacklash&>(*d.transmission).params().backlash, 1.5e-3);
  systems::applyFault(d, {FaultType::CoulombFrictionScale, "j", 1.5});
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::LuGreUr5Friction&>(*d.friction).params().f_c, 6.0);
  const double s0 = dynamic_cast<const drive::LuGreUr5Friction&>(*d.friction).params().sigma0;
  systems::applyFault(d, {FaultType::Sigma0Scale, "j", 2.0});
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::LuGreUr5Friction&>(*d.friction).params().sigma0, 2.0 * s0);
  const double kt = d.motor.kt, ke = d.motor.ke;
  systems::applyFault(d, {FaultType::TorqueConstantScale, "j", 0.9});
  EXPECT_DOUBLE_EQ(d.motor.kt, 0.9 * kt);
  EXPECT_DOUBLE_EQ(d.motor.ke, 0.9 * ke);
  d.controller.type = control::ControllerType::VoltageCascade;
  systems::applyFault(d, {FaultType::SensorBias, "j", -2e-3});
  EXPECT_DOUBLE_EQ(d.sensors.joint_bias, -2e-3);

  // The strain-wave gear scales all five stiffnesses; table friction scales its torques.
  systems::DriveSpec w;
  w.joint = "w";
  w.transmission = std::make_shared<drive::StrainWaveGear>(drive::StrainWaveGearParams{});
  systems::applyFault(w, {FaultType::GearStiffnessScale, "w", 0.5});
  const auto& sp = dynamic_cast<const drive::StrainWaveGear&>(*w.transmission).params();
  const drive::StrainWaveGearParams ref;
  EXPECT_DOUBLE_EQ(sp.K_m, 0.5 * ref.K_m);
  EXPECT_DOUBLE_EQ(sp.K_WG, 0.5 * ref.K_WG);
  EXPECT_DOUBLE_EQ(sp.K_CS, 0.5 * ref.K_CS);
  drive::TableFrictionParams tp;
  tp.tau_pos = {{{0.0, 1.0}}, {{1.0, 2.0}}};
  w.friction = std::make_shared<drive::TableFriction>(tp);
  systems::applyFault(w, {FaultType::CoulombFrictionScale, "w", 3.0});
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::TableFriction&>(*w.friction).params().tau_pos[1][1], 6.0);
}

TEST(Faults, InapplicableOrOutOfRangeFaultsAreInputErrors) {
  systems::DriveSpec w;
  w.joint = "w";
  w.transmission = std::make_shared<drive::StrainWaveGear>(drive::StrainWaveGearParams{});
  try {
    systems::applyFault(w, {FaultType::BacklashAdd, "w", 1e-3});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("backlash_add@w=0.001"));
    EXPECT_THAT(e.what(), HasSubstr("strain_wave_gear"));
  }
  w.friction = std::make_shared<drive::CoulombViscousFriction>(drive::CoulombViscousParams{});
  EXPECT_THROW(systems::applyFault(w, {FaultType::Sigma0Scale, "w", 2.0}), InputError);
  EXPECT_THROW(systems::applyFault(w, {FaultType::GearStiffnessScale, "w", -1.0}), InputError);
  EXPECT_THROW(systems::applyFault(w, {FaultType::BacklashAdd, "w", -1e-3}), InputError);
  std::vector<systems::DriveSpec> drives{w};
  EXPECT_THROW(systems::applyFaults(drives, {{FaultType::SensorBias, "nope", 1e-3}}), InputError);
  EXPECT_THROW(systems::faultTypeFromString("gear_wear"), InputError);
  // Faults that would leave the dynamics unchanged are refused rather than silently ignored.
  systems::DriveSpec ppi = elasticDrive();
  ppi.electrics = false;
  ppi.controller.type = control::ControllerType::TorqueCascade;
  EXPECT_THROW(systems::applyFault(ppi, {FaultType::TorqueConstantScale, "j", 0.8}), InputError);
  EXPECT_THROW(systems::applyFault(ppi, {FaultType::SensorBias, "j", 1e-3}), InputError);
  for (const auto& n : systems::faultTypeNames()) EXPECT_EQ(systems::toString(systems::faultTypeFromString(n)), n);
}

// faultApplies (what the FMU offers per drive) says yes exactly where applyFault accepts the fault, for drives with
// every transmission and friction type, with and without electrics and a joint-angle controller.
TEST(Faults, FaultAppliesAgreesWithApplyFaultOnEveryComponentType) {
  std::vector<std::shared_ptr<const drive::Transmission>> gears{
      std::make_shared<drive::RigidGear>(50.0), std::make_shared<drive::ElasticGear>(drive::ElasticGearParams{}),
      std::make_shared<drive::ElastoBacklash>(drive::ElastoBacklashParams{}),
      std::make_shared<drive::StrainWaveGear>(drive::StrainWaveGearParams{}), nullptr};
  drive::LuGreUr5Params u;
  u.f_c = 3.0;
  u.f_v = 1.0;
  u.k_q = 1.0;
  std::vector<std::shared_ptr<const drive::Friction>> frictions{
      std::make_shared<drive::CoulombViscousFriction>(drive::CoulombViscousParams{}),
      std::make_shared<drive::TableFriction>(drive::TableFrictionParams{}),
      std::make_shared<drive::StribeckFriction>(drive::StribeckParams{}),
      std::make_shared<drive::DahlFriction>(drive::DahlParams{}),
      std::make_shared<drive::LuGreFriction>(drive::LuGreParams{}),
      std::make_shared<drive::LuGreUr5Friction>(u),
      nullptr};
  int applied = 0, refused = 0;
  for (const auto& g : gears)
    for (const auto& f : frictions)
      for (const bool electrics : {false, true}) {
        systems::DriveSpec d;
        d.joint = "j";
        d.transmission = g;
        d.friction = f;
        d.electrics = electrics;
        d.controller.type =
            electrics ? control::ControllerType::VoltageCascade : control::ControllerType::TorqueCascade;
        for (const auto& name : systems::faultTypeNames()) {
          Fault fault;
          fault.type = systems::faultTypeFromString(name);
          fault.joint = "j";
          fault.value = fault.type == FaultType::BacklashAdd || fault.type == FaultType::SensorBias ? 1e-3 : 1.1;
          if (fault.type == FaultType::SensorDropout || fault.type == FaultType::SensorStuck) fault.value = 1e-2;
          systems::DriveSpec copy = d;
          bool ok = true;
          try {
            systems::applyFault(copy, fault);
          } catch (const InputError&) {
            ok = false;
          }
          EXPECT_EQ(systems::faultApplies(d, fault.type), ok)
              << name << " on " << (g ? g->type() : "none") << " / " << (f ? f->type() : "none");
          (ok ? applied : refused)++;
        }
      }
  EXPECT_GT(applied, 100);
  EXPECT_GT(refused, 50);
}

TEST(Faults, ClosedLoopSensorBiasShiftsThePostureAndWeakMotorDrawsMoreCurrent) {
  const auto [q_nom, i_nom] = hold({});
  Eigen::VectorXd q0(6);
  q0 << 0.2, -1.2, 1.0, -0.8, 0.5, 0.1;
  EXPECT_LT((q_nom - q0).cwiseAbs().maxCoeff(), 1e-4);  // the integrators remove the gravity droop
  // The position loop drives the *measured* angle q + bias to the set-point: q → q_set − bias.
  const auto [q_b, i_b] = hold({{FaultType::SensorBias, "shoulder_lift_joint", 2e-3}});
  EXPECT_NEAR(q_b[1] - q_nom[1], -2e-3, 1e-4);
  // Holding against gravity with 80 % of the torque constant needs 1/0.8 of the current.
  const auto [q_k, i_k] = hold({{FaultType::TorqueConstantScale, "shoulder_lift_joint", 0.8}});
  EXPECT_NEAR(i_k[1] / i_nom[1], 1.25, 0.01);
  EXPECT_LT(std::abs(q_k[1] - q_nom[1]), 1e-4);
}
