// The shipped replay of a measured UR5 log (config/experiments/ur5_measured_replay.yaml): the twin starts on the
// measured first positions and follows the real robot's measured joint positions (an independent measurement),
// and its predicted motor currents correlate with the measured ones.
#include <cmath>

#include <gtest/gtest.h>

#include "jointsim/experiments/experiment.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/report/agreement.hpp"
#include "test_util.hpp"

using namespace jointsim;

TEST(MeasuredLogReplay, TheTwinFollowsTheRealRobotsMeasuredMotion) {
  const std::string dir = std::string(JOINTSIM_SOURCE_DIR) + "/config/";
  // The first 6 s: a rest, then moves of every joint at up to 1.05 rad/s.
  auto e = experiments::loadExperiment(dir + "experiments/ur5_measured_replay.yaml", {"duration=6"});
  const auto result = experiments::runInMemory(*e);
  const auto& log = result.log;
  const io::CsvTable meas = io::readCsv(dir + "logs/ur5_kufieta2013_mov6_first30s.csv");
  const char* joints[] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                          "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  for (int j = 0; j < 6; ++j) {
    const int q = log.column(std::string("q_") + joints[j] + "[rad]");
    const int qa = meas.require("q_actual_" + std::to_string(j + 1), "measured position");
    const int qt = meas.require("q_target_" + std::to_string(j + 1), "commanded position");
    EXPECT_EQ(log.values(0, q), meas.data(0, qa)) << joints[j];  // starts on the measured first position
    // Replayed relative to the twin (the default for logs): its reference starts there too.
    const int q_set = log.column(std::string("q_set_") + joints[j] + "[rad]");
    EXPECT_NEAR(log.values(0, q_set), meas.data(0, qa), 1e-12) << joints[j];
    double worst = 0.0, real = 0.0;
    for (Eigen::Index r = 0; r < log.values.rows(); ++r) {
      const double t = log.values(r, 0);
      const auto k = static_cast<Eigen::Index>(std::lround(t / 0.008));  // the log's samples (log_rate 125 Hz)
      ASSERT_NEAR(meas.data(k, 0), t, 1e-9);
      worst = std::max(worst, std::abs(log.values(r, q) - meas.data(k, qa)));
      real = std::max(real, std::abs(meas.data(k, qt) - meas.data(k, qa)));
    }
    // The twin is as far from the real robot's measured positions as the real robot is from its own target
    // (7.8e-3 rad on the wrist 3, 1e-4 … 4e-4 rad on the others over these 6 s), within 1e-3 rad.
    EXPECT_LT(worst, real + 1e-3) << joints[j];
  }
}

TEST(MeasuredLogReplay, AbsoluteReplayOnRequestHoldsTheLoggedPositions) {
  const std::string dir = std::string(JOINTSIM_SOURCE_DIR) + "/config/";
  const io::CsvTable meas = io::readCsv(dir + "logs/ur5_kufieta2013_mov6_first30s.csv");
  auto run = [&](bool relative) {
    std::vector<std::string> over = {"duration=5"};
    if (!relative) over.push_back("+relative_replay=false");
    auto e = experiments::loadExperiment(dir + "experiments/ur5_measured_replay.yaml", over);
    return experiments::runInMemory(*e).log;
  };
  const auto abs = run(false), rel = run(true);
  const char* joints[] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                          "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  double differ = 0.0;
  for (int j = 0; j < 5; ++j) {  // (the wrist 3 moves at 5 s)
    const std::string name = std::string("q_set_") + joints[j] + "[rad]";
    const int qt = meas.require("q_target_" + std::to_string(j + 1), "commanded position");
    const int v = meas.require("qd_target_" + std::to_string(j + 1), "commanded velocity");
    // At 5 s joints 1-5 rest (until about 6 s): the absolute replay holds the logged position of the rest's last
    // sample (where the next move starts); the relative one holds the twin where it stopped.
    Eigen::Index m = static_cast<Eigen::Index>(std::lround(5.0 / 0.008));
    while (std::abs(meas.data(m + 1, v)) <= 1e-4) ++m;
    const Eigen::Index last = abs.values.rows() - 1;
    EXPECT_NEAR(abs.values(last, abs.column(name)), meas.data(m, qt), 1e-9) << joints[j];
    differ = std::max(differ, std::abs(rel.values(last, rel.column(name)) - meas.data(m, qt)));
  }
  EXPECT_GT(differ, 1e-5);
}

TEST(MeasuredLogReplay, TheCalibratedTwinIsCloserToTheMeasuredCurrentsThanTheMakersModel) {
  // The acceptance figure of the calibration (docs/replay.md): the shipped replay with the shipped calibrated drives,
  // RMS current error in % of each joint's measured range over the whole log, against the robot maker's own model
  // (its i_target against i_actual of the same samples: 8.7, 4.9, 6.3, 21.5, 10.0, 14.8 %).
  const std::string dir = std::string(JOINTSIM_SOURCE_DIR) + "/config/";
  auto e = experiments::loadExperiment(dir + "experiments/ur5_measured_replay.yaml",
                                       {"robot=" + dir + "robots/ur5_drives_measured.yaml"});
  const auto result = experiments::runInMemory(*e);
  const io::CsvTable meas = io::readCsv(dir + "logs/ur5_kufieta2013_mov6_first30s.csv");
  io::CsvTable run;
  run.path = "replay";
  run.header = result.log.columns;
  run.data = result.log.values;
  for (Eigen::Index r = 0; r < run.data.rows(); ++r) run.lines.push_back(static_cast<int>(r) + 2);
  const std::vector<std::string> joints = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                           "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  const auto twin = report::agreement(run, meas, report::SignalPair::expand("current_{joint}=i_actual_{j}", joints));
  const auto maker = report::agreement(meas, meas, report::SignalPair::expand("i_target_{j}=i_actual_{j}", joints));
  for (size_t j = 0; j < 6; ++j) {
    EXPECT_LT(twin.pairs[j].rms_percent, maker.pairs[j].rms_percent) << joints[j];
    EXPECT_GT(twin.pairs[j].correlation, 0.75) << joints[j];
  }
}
