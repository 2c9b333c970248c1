// The UR5 digital twin through `jointsim run` (library entry): the excitation run tracks within 0.5°,
// and bad robot/trajectory input is rejected with file, key path or row, writing nothing.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

using namespace jointsim;
using ::testing::HasSubstr;

namespace {
std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Column-wise maximum of |q_set − q| from the CSV.
std::vector<double> maxErrors(const std::string& csv_path, int n) {
  std::ifstream in(csv_path);
  std::string line;
  std::getline(in, line);
  std::vector<double> err(static_cast<size_t>(n), 0.0);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<double> row;
    for (std::string c; std::getline(ss, c, ',');) row.push_back(std::stod(c));
    for (int k = 0; k < n; ++k) {
      const size_t base = 1 + 11 * static_cast<size_t>(k);  // q_set, q, ... (11 columns per joint)
      err[static_cast<size_t>(k)] = std::max(err[static_cast<size_t>(k)], std::abs(row[base] - row[base + 1]));
    }
  }
  return err;
}
}  // namespace

TEST(Tracking, Ur5ExcitationTracksWithinHalfADegree) {
  const test::TempDir tmp;
  const auto dir = tmp / "jointsim_ur5_excitation";
  experiments::RunOptions o;
  o.output_dir = dir.string();
  const auto report = experiments::runExperimentFile(test::sourcePath("config/experiments/ur5_excitation.yaml"), o);
  ASSERT_EQ(report.status, "ok");
  const auto err = maxErrors(report.csv_path, 6);
  for (int k = 0; k < 6; ++k) {
    std::printf("joint %d: max tracking error %.4f deg\n", k + 1, err[static_cast<size_t>(k)] * 180 / M_PI);
    EXPECT_LT(err[static_cast<size_t>(k)] * 180 / M_PI, 0.5) << "joint " << k + 1;
    EXPECT_GT(err[static_cast<size_t>(k)], 0.0);
  }
  EXPECT_THAT(slurp(report.summary_path), HasSubstr("\"max_tracking_error_rad\""));
}

TEST(Tracking, RobotWithDrivesErrors) {
  const test::TempDir tmp;
  const auto& dir = tmp.path();
  const std::string drives = slurp(test::sourcePath("config/robots/ur5_drives.yaml"));
  const auto path = dir / "jointsim_bad_drives.yaml";
  auto expectError = [&](std::string text, const std::string& expected) {
    text.replace(text.find("multibody: ur5.yaml"), 19, "multibody: " + test::sourcePath("config/robots/ur5.yaml"));
    std::ofstream(path) << text;
    try {
      systems::loadRobotWithDrives(path.string());
      ADD_FAILURE() << "no error for " << expected;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path.string()));
      EXPECT_THAT(e.what(), HasSubstr(expected));
    }
  };
  // A drive missing for a joint: drop the last drive (5 lines).
  std::string missing = drives;
  missing.erase(missing.find("  - joint: wrist_3_joint"));
  expectError(missing, "drives: joint 'wrist_3_joint' has no drive");
  // Gains of the wrong sign.
  std::string negative = drives;
  negative.replace(negative.find("P_vel: 1.0"), 10, "P_vel: -1.0");
  expectError(negative, "controller.P_vel: expected a gain >= 0 A·s/rad");
}

TEST(Tracking, TrajectoryBeyondLimitsAndBadSetpointCsvExitTwoAndWriteNothing) {
  const test::TempDir tmp;
  const auto& dir = tmp.path();
  const std::string robot = test::sourcePath("config/robots/ur5_drives.yaml");
  auto run = [&](const std::string& trajectory) {
    const auto cfg = dir / "exp.yaml";
    std::ofstream(cfg) << "experiment: {name: bad, type: tracking}\nrobot: " << robot << "\ntrajectory:\n"
                       << trajectory;
    const auto out = dir / "out";
    const std::string cmd = std::string(JOINTSIM_CLI_PATH) + " run " + cfg.string() + " -o " + out.string() + " 2>" +
                            (dir / "err").string();
    const int rc = std::system(cmd.c_str());
    EXPECT_FALSE(std::filesystem::exists(out / "bad.csv"));
    EXPECT_FALSE(std::filesystem::exists(out / "summary.json"));
    return std::make_pair(WEXITSTATUS(rc), slurp(dir / "err"));
  };
  // Beyond the ±2π joint limits of ur5.yaml.
  auto [rc1, err1] =
      run("  type: point_to_point\n  start: [0, -1.5, 1.5, -1.5, -1.5, 0]\n"
          "  segments:\n    - {target: [0, -1.5, 1.5, -1.5, -1.5, 7.0], velocity: 3.0, acceleration: 8.0}\n");
  EXPECT_EQ(rc1, 2);
  EXPECT_THAT(err1, HasSubstr("exp.yaml:4: trajectory: trajectory leaves the limits of joint wrist_3_joint at t = "));
  // Set-point CSV with a gap and with non-monotonic time.
  std::ofstream(dir / "gap.csv") << "t,q1,q2,q3,q4,q5,q6\n0,0,-1.5,1.5,-1.5,-1.5,0\n0.008,0,-1.5,1.5,-1.5,-1.5,0\n"
                                    "0.016,0,-1.5,1.5,-1.5,-1.5,0\n0.5,0,-1.5,1.5,-1.5,-1.5,0\n";
  auto [rc2, err2] = run("  type: csv\n  file: gap.csv\n");
  EXPECT_EQ(rc2, 2);
  EXPECT_THAT(err2, HasSubstr("gap.csv:5: time step"));
  EXPECT_THAT(err2, HasSubstr("(a gap)"));
  std::ofstream(dir / "back.csv") << "t,q1,q2,q3,q4,q5,q6\n0,0,-1.5,1.5,-1.5,-1.5,0\n0.008,0,-1.5,1.5,-1.5,-1.5,0\n"
                                     "0.004,0,-1.5,1.5,-1.5,-1.5,0\n";
  auto [rc3, err3] = run("  type: csv\n  file: back.csv\n");
  EXPECT_EQ(rc3, 2);
  EXPECT_THAT(err3, HasSubstr("back.csv:4: time 0.004 s is not after"));
}

TEST(Tracking, SampledControlWithNoisySensorsIsReproducibleBySeed) {
  // Sample-and-hold control at 20 kHz with quantised, noisy sensors: the same seed gives the same run
  // bit for bit, another seed a different one, and the arm still tracks.
  const test::TempDir tmp;
  const auto& dir = tmp.path();
  std::string drives = slurp(test::sourcePath("config/robots/ur5_drives.yaml"));
  drives.replace(drives.find("multibody: ur5.yaml"), 19, "multibody: " + test::sourcePath("config/robots/ur5.yaml"));
  for (size_t at = drives.find("    controller:"); at != std::string::npos;
       at = drives.find("    controller:", at + 200))
    drives.insert(
        at,
        "    sensors: {motor_quantum: 4.79e-5, joint_quantum: 3.83e-4, current_noise: 0.01, current_quantum: 0.001}\n");
  std::ofstream(dir / "drives.yaml") << drives;
  std::string exp = slurp(test::sourcePath("config/experiments/ur5_excitation.yaml"));
  exp.replace(exp.find("robot: ../robots/ur5_drives.yaml"), 32, "robot: drives.yaml\ncontrol: {rate: 20000, seed: 7}");
  std::ofstream(dir / "exp.yaml") << exp;
  auto run = [&](const std::string& out, std::vector<std::string> overrides) {
    experiments::RunOptions o;
    o.output_dir = (dir / out).string();
    o.overrides = std::move(overrides);
    o.overrides.push_back("duration=0.01");
    o.overrides.push_back("log_rate=2000");
    return experiments::runExperimentFile((dir / "exp.yaml").string(), o);
  };
  const auto a = run("a", {}), b = run("b", {}), c = run("c", {"control.seed=8"});
  const std::string csv_a = slurp(a.csv_path), csv_b = slurp(b.csv_path), csv_c = slurp(c.csv_path);
  EXPECT_EQ(csv_a, csv_b) << "same seed, same run";
  EXPECT_NE(csv_a, csv_c) << "the noise depends on the seed";
  for (double e : maxErrors(a.csv_path, 6)) EXPECT_LT(e * 180 / M_PI, 0.5);
  EXPECT_THAT(slurp(a.summary_path), HasSubstr("\"control_rate_hz\": 20000"));
}

// `drives:` of a tracking experiment changes parameters of the robot file's drives by their table keys: the held
// pose's gear deflection follows the changed stiffness as the spring law says (δ = τ/c, output side), the other
// drives are unchanged, and a key, component or joint that does not exist is an error at its file line.
TEST(Tracking, DrivesKeyChangesDriveParametersByTheirTableKeys) {
  const test::TempDir tmp;
  auto write = [&](const std::string& drives) {
    const auto path = tmp / "hold.yaml";
    std::ofstream(path) << "experiment: {name: hold, type: tracking}\n"
                        << "robot: " << test::sourcePath("config/robots/ur5_drives_elastic.yaml") << "\n"
                        << drives << "trajectory:\n  type: point_to_point\n"
                        << "  start: [0, -1.2, 1.0, -1.4, -1.57, 0]\n"
                        << "  segments:\n    - {target: [0, -1.2, 1.0, -1.4, -1.57, 0], velocity: 1, acceleration: 1,"
                        << " dwell: 0.4}\nduration: 0.4\nlog_rate: 100\n";
    return path.string();
  };
  auto deflection = [&](const std::string& drives, double* stiffness) {
    std::shared_ptr<experiments::Experiment> e = experiments::loadExperiment(write(drives));
    const systems::RobotSystem& r = *e->robotSystem();
    const int k = r.model().jointIndex("elbow_joint");
    *stiffness = drive::parameterValue(r.drives()[static_cast<size_t>(k)].transmission->parameters(), "stiffness", "");
    auto sim = experiments::makeSimulator(e);
    sim->advanceTo(0.4);
    const double tau = sim->signal("gear_torque_elbow_joint");
    const Eigen::VectorXd y = sim->state();
    const double delta = y[r.layout(k).motor] / r.layout(k).ratio - y[k];  // output-side deflection [rad]
    return std::make_pair(delta, tau);
  };
  double c0 = 0, c1 = 0;
  const auto [d0, t0] = deflection("", &c0);
  const auto [d1, t1] = deflection("drives:\n  elbow_joint:\n    transmission: {stiffness: 2.0e4}\n", &c1);
  EXPECT_EQ(c0, 1.446e5);  // the robot file's
  EXPECT_EQ(c1, 2.0e4);
  EXPECT_NEAR(d0, t0 / c0, 1e-3 * std::abs(t0 / c0));
  EXPECT_NEAR(d1, t1 / c1, 1e-3 * std::abs(t1 / c1));
  EXPECT_NEAR(t1, t0, 1e-3 * std::abs(t0));  // the same gravity torque held
  EXPECT_GT(std::abs(d1), 5.0 * std::abs(d0));

  // Nested keys of the table (both directions of a LuGre-type set would read positive.alpha0); errors at their line.
  auto error = [&](const std::string& drives) {
    try {
      (void)experiments::loadExperiment(write(drives));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string m = error("drives:\n  elbow_joint:\n    friction: {f_cc: 1.0}\n");
  EXPECT_THAT(m, HasSubstr("hold.yaml:5: drives.elbow_joint.friction.f_cc"));
  EXPECT_THAT(m, HasSubstr("f_c, f_v, k_q"));  // the table's keys
  EXPECT_THAT(error("drives:\n  elbow_joint:\n    transmission: {stiffness: -1}\n"), HasSubstr("(0, inf)"));
  EXPECT_THAT(error("drives:\n  elbo_joint:\n    motor: {R: 1}\n"), HasSubstr("no drive of joint 'elbo_joint'"));
  EXPECT_THAT(error("drives:\n  elbow_joint:\n    gear: {R: 1}\n"), HasSubstr("gear"));
}
