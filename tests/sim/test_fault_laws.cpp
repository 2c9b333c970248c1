// Faults as they happen (systems/faults.hpp): the time laws against their definitions (progress of the linear and
// exponential progressions, the mid-interval parameter schedule, episodes), and each new fault type on one joint of
// the UR5 twin against its definition: rebuilt parameters at given times, the motor torque k_t(t)·i, the measured
// angle in dropout/stuck/spike episodes (also through a whole simulation), the bearing ripple A sin(order·φ).
#include <cmath>
#include <set>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/systems/faults.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;
using systems::Fault;
using systems::FaultType;
using systems::Progression;
using ::testing::HasSubstr;

namespace {

constexpr int kElbow = 2;

Fault fault(FaultType type, double value, double onset = 0.0) {
  Fault f;
  f.type = type;
  f.joint = "elbow_joint";
  f.value = value;
  f.onset = onset;
  return f;
}

Fault ramp(FaultType type, double value, Progression p, double onset, double T, int steps = 100, double rate = 0.0) {
  Fault f = fault(type, value, onset);
  f.progression = p;
  f.ramp_time = T;
  f.steps = steps;
  f.rate = rate;
  return f;
}

systems::RobotSystem twin(const std::vector<Fault>& faults) {
  return systems::loadRobotWithDrives(test::sourcePath("config/robots/ur5_drives_elastic.yaml"), faults);
}

Eigen::VectorXd pose() {
  Eigen::VectorXd q0(6);
  q0 << 0.2, -1.2, 1.0, -0.8, 0.5, 0.1;
  return q0;
}

void holdPose(systems::RobotSystem& sys) {
  const Eigen::VectorXd q0 = pose();
  sys.setSetpoints(
      [q0](double, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd) {
        q = q0;
        qd.setZero();
        qdd.setZero();
      });
  sys.setInitialPositions(q0);
}

double stiffness(const systems::RobotSystem& sys, const sim::PlantState& st) {
  const drive::Transmission* t = sys.drives(st)[kElbow].transmission.get();
  if (auto* b = dynamic_cast<const drive::ElastoBacklash*>(t)) return b->params().stiffness;
  return dynamic_cast<const drive::ElasticGear&>(*t).params().stiffness;
}

}  // namespace

TEST(FaultLaws, ProgressionsFollowTheirDefinitions) {
  const Fault lin = ramp(FaultType::GearStiffnessScale, 0.6, Progression::Linear, 1.0, 2.0);
  EXPECT_EQ(systems::faultProgress(lin, 0.999), 0.0);
  EXPECT_DOUBLE_EQ(systems::faultProgress(lin, 1.5), 0.25);
  EXPECT_DOUBLE_EQ(systems::faultValue(lin, 1.5), 1.0 - 0.4 * 0.25);  // nominal 1 + (s − 1)·p
  EXPECT_EQ(systems::faultValue(lin, 3.0), 0.6);
  EXPECT_EQ(systems::faultValue(lin, 7.0), 0.6);
  // Exponential: p = (e^{λτ} − 1)/(e^{λT} − 1); at τ = T/2 that is 1/(e^{λT/2} + 1).
  const Fault ex = ramp(FaultType::CoulombFrictionScale, 3.0, Progression::Exponential, 0.0, 2.0, 100, 1.5);
  EXPECT_NEAR(systems::faultProgress(ex, 1.0), 1.0 / (std::exp(1.5) + 1.0), 1e-15);
  EXPECT_NEAR(systems::faultValue(ex, 1.0), 1.0 + 2.0 / (std::exp(1.5) + 1.0), 1e-14);
  // Additive faults start from 0; a step acts in full from its onset.
  const Fault b = ramp(FaultType::BacklashAdd, 1e-3, Progression::Linear, 0.0, 1.0);
  EXPECT_DOUBLE_EQ(systems::faultValue(b, 0.5), 5e-4);
  const Fault step = fault(FaultType::TorqueConstantScale, 0.7, 0.3);
  EXPECT_EQ(systems::faultValue(step, 0.2999), 1.0);
  EXPECT_EQ(systems::faultValue(step, 0.3), 0.7);
}

TEST(FaultLaws, TheScheduleHoldsEachIntervalsMidpointValue) {
  const Fault f = ramp(FaultType::GearStiffnessScale, 0.5, Progression::Exponential, 0.5, 1.0, 10, 3.0);
  const double dt = 0.1;
  double worst = 0.0;
  for (int k = 0; k < 10; ++k) {
    const double mid = systems::faultValue(f, 0.5 + 1.0 * (k + 0.5) / 10);
    for (double frac : {0.0, 0.3, 0.999}) {
      const double t = frac == 0.0 ? 0.5 + 1.0 * k / 10 : 0.5 + (k + frac) * dt;  // t_k as the events compute it
      EXPECT_DOUBLE_EQ(systems::scheduledFaultValue(f, t), mid) << "t = " << t;
      worst = std::max(worst, std::abs(systems::scheduledFaultValue(f, t) - systems::faultValue(f, t)));
    }
  }
  // At most the law's change over one step (the last interval changes most: exponential wear accelerates).
  EXPECT_LE(worst, std::abs(systems::faultValue(f, 1.5) - systems::faultValue(f, 1.4)));
  EXPECT_GT(worst, 0.3 * std::abs(systems::faultValue(f, 1.5) - systems::faultValue(f, 1.4)));
  EXPECT_EQ(systems::scheduledFaultValue(f, 1.5), 0.5);
  EXPECT_EQ(systems::scheduledFaultValue(f, 0.4), 1.0);
  // Events: the onset and each step's end, inside (0, t_end).
  const std::vector<double> e = systems::faultEvents(f, 10.0);
  ASSERT_EQ(e.size(), 11u);
  EXPECT_EQ(e.front(), 0.5);
  EXPECT_DOUBLE_EQ(e.back(), 1.5);
  EXPECT_EQ(systems::faultEvents(f, 1.0).size(), 5u);  // 0.5, 0.6, ..., 0.9
}

TEST(FaultLaws, EpisodesStartEveryPeriodAndLastTheirLength) {
  Fault d = fault(FaultType::SensorDropout, 0.01, 0.3);
  d.period = 0.2;
  d.count = 3;
  long k = -1;
  EXPECT_FALSE(systems::faultEpisode(d, 0.2999));
  EXPECT_TRUE(systems::faultEpisode(d, 0.3, &k));
  EXPECT_EQ(k, 0);
  EXPECT_TRUE(systems::faultEpisode(d, 0.509, &k));
  EXPECT_EQ(k, 1);
  EXPECT_FALSE(systems::faultEpisode(d, 0.511));
  EXPECT_TRUE(systems::faultEpisode(d, 0.705));
  EXPECT_FALSE(systems::faultEpisode(d, 0.905));  // count 3: no fourth episode
  EXPECT_THAT(systems::faultEvents(d, 10.0), ::testing::ElementsAre(0.3, 0.31, 0.5, 0.51, 0.7, 0.71));
  Fault s = fault(FaultType::SensorSpike, 0.01, 0.0);
  s.period = 0.1;
  s.width = 0.002;                                      // count 0: every period until the end
  EXPECT_EQ(systems::faultEvents(s, 1.0).size(), 19u);  // 0 is not an event: 9 starts and 10 ends
  EXPECT_TRUE(systems::faultEpisode(s, 0.9015));
  EXPECT_FALSE(systems::faultEpisode(s, 0.9025));
}

TEST(FaultLaws, BadTimeLawsAndSeveritiesAreRejected) {
  auto message = [](const Fault& f) {
    try {
      systems::checkFault(f);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message(fault(FaultType::GearStiffnessScale, 0.0)), HasSubstr("> 0 and <= 100"));
  EXPECT_THAT(message(fault(FaultType::GearStiffnessScale, 250.0)), HasSubstr("> 0 and <= 100"));
  EXPECT_THAT(message(fault(FaultType::BacklashAdd, 1.0)), HasSubstr("<= 0.5 rad"));
  EXPECT_THAT(message(fault(FaultType::SensorSpike, 4.0)), HasSubstr("±π"));
  EXPECT_THAT(message(fault(FaultType::SensorDropout, 0.0)), HasSubstr("episode length"));
  EXPECT_THAT(message(fault(FaultType::BearingRipple, -1.0)), HasSubstr(">= 0 N·m"));
  EXPECT_THAT(message(fault(FaultType::SensorBias, 1e-3, -1.0)), HasSubstr("onset"));
  EXPECT_THAT(message(ramp(FaultType::GearStiffnessScale, 0.5, Progression::Linear, 0.0, 0.0)), HasSubstr("ramp_time"));
  EXPECT_THAT(message(ramp(FaultType::GearStiffnessScale, 0.5, Progression::Exponential, 0.0, 1.0)), HasSubstr("rate"));
  EXPECT_THAT(message(ramp(FaultType::GearStiffnessScale, 0.5, Progression::Linear, 0.0, 1.0, 0)), HasSubstr("steps"));
  EXPECT_THAT(message(ramp(FaultType::SensorStuck, 0.1, Progression::Linear, 0.0, 1.0)), HasSubstr("no progression"));
  Fault long_episode = fault(FaultType::SensorStuck, 0.3);
  long_episode.period = 0.2;
  EXPECT_THAT(message(long_episode), HasSubstr("longer than the period"));
  EXPECT_EQ(message(ramp(FaultType::Sigma0Scale, 2.0, Progression::Linear, 0.1, 1.0)), "accepted");
}

TEST(FaultLaws, ProgressiveParametersAreRebuiltOnTheirSchedule) {
  const Fault k = ramp(FaultType::GearStiffnessScale, 0.5, Progression::Linear, 0.2, 0.5, 50);
  const Fault c = ramp(FaultType::CoulombFrictionScale, 3.0, Progression::Exponential, 0.2, 0.5, 50, 4.0);
  const Fault b = ramp(FaultType::BacklashAdd, 1e-3, Progression::Linear, 0.0, 1.0, 20);
  systems::RobotSystem nominal = twin({});
  const double k0 = stiffness(nominal, *nominal.makeState());
  const double fc0 = dynamic_cast<const drive::LuGreUr5Friction&>(*nominal.drives()[kElbow].friction).params().f_c;
  systems::RobotSystem sys = twin({k, c, b});
  holdPose(sys);
  const Eigen::VectorXd y = sys.initialState();
  const auto st = sys.makeState();
  for (double t : {0.0, 0.1, 0.2, 0.33, 0.5, 0.69, 0.7, 0.95}) {
    sys.start(*st, t, y);  // the faults' state at t, as at a (re)start
    EXPECT_DOUBLE_EQ(stiffness(sys, *st), k0 * systems::scheduledFaultValue(k, t)) << t;
    EXPECT_DOUBLE_EQ(dynamic_cast<const drive::LuGreUr5Friction&>(*sys.drives(*st)[kElbow].friction).params().f_c,
                     fc0 * systems::scheduledFaultValue(c, t))
        << t;
    // An elastic gear with growing backlash is an elasto-backlash gear of the same stiffness from the start.
    const auto& eb = dynamic_cast<const drive::ElastoBacklash&>(*sys.drives(*st)[kElbow].transmission).params();
    int step = 0;  // t_k = T·k/steps <= t < t_k+1
    while (step + 1 < 20 && 1.0 * (step + 1) / 20 <= t) ++step;
    EXPECT_DOUBLE_EQ(eb.backlash, 1e-3 * (step + 0.5) / 20) << t;
  }
  // Through a run: an event at every step of the three schedules, the final values at the end.
  std::set<double> instants;
  for (const Fault& f : {k, c, b})
    for (double e : systems::faultEvents(f, 1.0)) instants.insert(e);
  const auto run = sys.makeState();
  const auto o = sim::SimulateOptions::atRate(1.0, 100, sim::CvodeOptions{});
  const sim::SimulationResult r = sim::simulate(sys, *run, o, [](const Eigen::VectorXd&) {});
  // Instants closer than the simulator's time resolution of events (1e-12 s relative: 0.3 of one schedule and
  // 0.30000000000000004 of another) are one event.
  long distinct = 0;
  double last = -1.0;
  for (double e : instants) {
    if (e - last > 1e-12 * std::max(1.0, e)) ++distinct;
    last = e;
  }
  EXPECT_GE(r.events, distinct);
  EXPECT_GE(distinct, 55);
  EXPECT_GE(instants.size(), 60u);
  EXPECT_DOUBLE_EQ(stiffness(sys, *run), 0.5 * k0);
  EXPECT_DOUBLE_EQ(dynamic_cast<const drive::LuGreUr5Friction&>(*sys.drives(*run)[kElbow].friction).params().f_c,
                   3.0 * fc0);
}

TEST(FaultLaws, TorqueConstantLossScalesTheMotorTorque) {
  systems::RobotSystem sys = twin({ramp(FaultType::TorqueConstantScale, 0.6, Progression::Linear, 0.0, 1.0, 4)});
  holdPose(sys);
  Eigen::VectorXd y = sys.initialState();
  const int i_state = sys.layout(kElbow).current;
  y[i_state] = 2.5;  // [A]
  const double kt0 = twin({}).drives()[kElbow].motor.kt;
  const auto st = sys.makeState();
  for (double t : {0.1, 0.4, 0.6, 0.9, 1.2}) {
    sys.start(*st, t, y);
    const double s = systems::scheduledFaultValue(sys.faults()[0], t);
    EXPECT_NEAR(sys.driveSignals(*st, t, y).tau_motor[kElbow], kt0 * s * 2.5, 1e-12) << t;  // τ_M = k_t(t) i
    EXPECT_DOUBLE_EQ(sys.drives(*st)[kElbow].motor.ke, twin({}).drives()[kElbow].motor.ke * s);
  }
}

TEST(FaultLaws, SensorEpisodesChangeTheMeasuredAngleAsDefined) {
  Fault drop = fault(FaultType::SensorDropout, 0.01, 0.3);
  drop.period = 0.2;
  Fault spike = fault(FaultType::SensorSpike, 0.02, 0.35);
  spike.width = 0.01;
  Fault stuck = fault(FaultType::SensorStuck, 0.1, 0.6);
  systems::RobotSystem sys = twin({drop, spike, stuck, fault(FaultType::SensorBias, 1e-3)});
  holdPose(sys);
  const Eigen::VectorXd y = sys.initialState();
  const double q = y[kElbow];
  const auto st = sys.makeState();
  sys.start(*st, 0.0, y);
  EXPECT_DOUBLE_EQ(sys.driveSignals(*st, 0.2, y).q_fb[kElbow], q + 1e-3);           // biased, no episode
  EXPECT_EQ(sys.driveSignals(*st, 0.305, y).q_fb[kElbow], 0.0);                     // dropout: reads 0 rad
  EXPECT_DOUBLE_EQ(sys.driveSignals(*st, 0.355, y).q_fb[kElbow], q + 1e-3 + 0.02);  // spike: + A
  EXPECT_DOUBLE_EQ(sys.driveSignals(*st, 0.365, y).q_fb[kElbow], q + 1e-3);         // after the spike's width
  // Stuck: the reading at the episode's start is held while the joint moves on.
  Eigen::VectorXd moved = y;
  moved[kElbow] += 0.05;
  sys.updateModes(*st, 0.6, y, {});  // the time event at the episode's start
  EXPECT_DOUBLE_EQ(sys.driveSignals(*st, 0.65, moved).q_fb[kElbow], q + 1e-3);
  EXPECT_DOUBLE_EQ(sys.driveSignals(*st, 0.71, moved).q_fb[kElbow], q + 0.05 + 1e-3);
  // Through a run at 1 kHz: the logged q_fb is 0 in every dropout episode and the biased angle elsewhere.
  systems::RobotSystem run = twin({drop, fault(FaultType::SensorBias, 1e-3)});
  holdPose(run);
  const int col_q = test::rowIndex(run, "q_elbow_joint"), col_fb = test::rowIndex(run, "q_fb_elbow_joint");
  int in_episode = 0;
  sim::simulate(run, sim::SimulateOptions::atRate(1.0, 1000, sim::CvodeOptions{}), [&](const Eigen::VectorXd& row) {
    if (systems::faultEpisode(drop, row[0])) {
      ++in_episode;
      EXPECT_EQ(row[col_fb], 0.0) << row[0];
    } else {
      EXPECT_DOUBLE_EQ(row[col_fb], row[col_q] + 1e-3) << row[0];
    }
  });
  EXPECT_EQ(in_episode, 4 * 10);  // episodes at 0.3, 0.5, 0.7, 0.9, 10 samples of 1 ms each
  // Sampled control at 20 kHz: the controller's held reading is 0 rad once a sample fell in the episode.
  systems::RobotSystem sampled = twin({drop});
  holdPose(sampled);
  sampled.setSampledControl(20000.0, 1);
  int checked = 0;
  sim::simulate(sampled, sim::SimulateOptions::atRate(0.6, 1000, sim::CvodeOptions{}), [&](const Eigen::VectorXd& row) {
    if (systems::faultEpisode(drop, row[0] - 1e-4)) {
      ++checked;
      EXPECT_EQ(row[col_fb], 0.0) << row[0];
    }
  });
  EXPECT_GE(checked, 2 * 9);
}

TEST(FaultLaws, BearingRippleAddsASineOfTheShaftAngle) {
  Fault r = ramp(FaultType::BearingRipple, 2.0, Progression::Linear, 0.0, 1.0, 4);
  r.order = 7.0;
  systems::RobotSystem with = twin({r});
  systems::RobotSystem without = twin({});
  holdPose(with);
  holdPose(without);
  Eigen::VectorXd y = with.initialState();
  const auto st = with.makeState(), st0 = without.makeState();
  for (double phi : {0.3, 1.1, -2.0}) {
    y[kElbow] = phi;
    for (double t : {0.1, 0.6, 1.5}) {
      with.start(*st, t, y);
      const double A = systems::scheduledFaultValue(r, t);  // the amplitude's schedule [N·m]
      const double extra =
          with.driveSignals(*st, t, y).tau_friction[kElbow] - without.driveSignals(*st0, t, y).tau_friction[kElbow];
      EXPECT_NEAR(extra, A * std::sin(7.0 * phi), 1e-12) << "t = " << t << ", φ = " << phi;
    }
  }
}

TEST(FaultLaws, AnExponentialLawWithAVanishingRateIsItsLinearLimit) {
  // (e^{λτ} − 1)/(e^{λT} − 1) → τ/T as λ → 0; at the smallest double λ both expm1 underflow to 0 (0/0 before).
  for (const double rate : {5e-324, 1e-300, 1e-15}) {
    const Fault f = ramp(FaultType::GearStiffnessScale, 0.5, Progression::Exponential, 0.0, 2.0, 100, rate);
    for (const double t : {0.0, 0.5, 1.0, 1.5}) EXPECT_NEAR(systems::faultProgress(f, t), t / 2.0, 1e-12) << rate;
  }
  // The description (part of a batch run's fingerprint) tells nearby rates apart.
  const Fault a = ramp(FaultType::GearStiffnessScale, 0.5, Progression::Exponential, 0.0, 2.0, 100, 1e-7);
  const Fault b = ramp(FaultType::GearStiffnessScale, 0.5, Progression::Exponential, 0.0, 2.0, 100, 5e-7);
  EXPECT_NE(systems::describe(a), systems::describe(b));
  EXPECT_THAT(systems::describe(a), HasSubstr("at rate 1e-07 1/s"));
}
