// The command-line contract: `jointsim dynamics` JSON output against the library, exit status 2 with a
// one-line message for bad input, `jointsim run` outputs.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using ::testing::MatchesRegex;
using jointsim::test::sourcePath;

namespace {
using Result = jointsim::test::CliResult;
using jointsim::test::runCli;
using jointsim::test::TempDir;

// Extracts the numbers of the JSON array following "key": (flattening nested arrays).
std::vector<double> jsonNumbers(const std::string& json, const std::string& key) {
  const size_t start = json.find("\"" + key + "\":");
  if (start == std::string::npos) return {};
  size_t i = json.find('[', start), depth = 0;
  std::vector<double> out;
  std::string token;
  for (; i < json.size(); ++i) {
    const char c = json[i];
    if (c == '[') ++depth;
    if (c == ']' || c == ',') {
      if (!token.empty()) out.push_back(std::stod(token));
      token.clear();
      if (c == ']' && --depth == 0) break;
    } else if (c != '[' && c != ' ') {
      token += c;
    }
  }
  return out;
}

std::string oneLine(const std::string& s) { return s.substr(0, s.find('\n')); }
}  // namespace

TEST(CliDynamics, JsonMatchesLibrary) {
  const std::string robot = sourcePath("config/robots/ur5.yaml");
  const Result r =
      runCli("dynamics --robot " + robot +
             " --q 0.1,-1.0,0.5,0.2,0.3,0.4 --qd 1,2,3,-1,-2,-3 --qdd 0.5,0.5,0.5,0.5,0.5,0.5 --tau 1,2,3,4,5,6");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << "one JSON object on one line";
  using namespace jointsim::multibody;
  const Model model = loadRobot(robot);
  Data data(model);
  Eigen::VectorXd q(6), qd(6), qdd = Eigen::VectorXd::Constant(6, 0.5), tau(6);
  q << 0.1, -1.0, 0.5, 0.2, 0.3, 0.4;
  qd << 1, 2, 3, -1, -2, -3;
  tau << 1, 2, 3, 4, 5, 6;
  auto near = [](const std::vector<double>& got, const Eigen::MatrixXd& want) {
    Eigen::MatrixXd w = want.transpose();  // rows printed in order
    ASSERT_EQ(got.size(), static_cast<size_t>(w.size()));
    for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], w.data()[i]) << "17 significant digits round-trip";
  };
  near(jsonNumbers(r.out, "tau"), rnea(model, data, q, qd, qdd));
  near(jsonNumbers(r.out, "M"), crba(model, data, q));
  near(jsonNumbers(r.out, "g"), gravityTorques(model, data, q));
  near(jsonNumbers(r.out, "qdd"), aba(model, data, q, qd, tau));
  forwardKinematics(model, data, q);
  near(jsonNumbers(r.out, "tcp"), data.oMf[static_cast<size_t>(model.frameIndex(model.tip_frame))].homogeneous());
}

TEST(CliDynamics, QddOnlyWithTauAndNamedFrame) {
  const Result r =
      runCli("dynamics --robot " + sourcePath("config/robots/ur5.urdf") + " --q 0,0,0,0,0,0 --frame base_link");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("\"qdd\"")));
  EXPECT_EQ(jsonNumbers(r.out, "tcp"), std::vector<double>({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}));
}

TEST(CliDynamics, WrongNumberOfValues) {
  const Result r = runCli("dynamics --robot " + sourcePath("config/robots/ur5.yaml") + " --q 0,0,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(oneLine(r.err), HasSubstr("--q: expected 6 comma-separated values"));
  EXPECT_TRUE(r.out.empty());
}

TEST(CliDynamics, BadNumberUnknownFrameBadFiles) {
  const std::string ur5 = sourcePath("config/robots/ur5.yaml");
  Result r = runCli("dynamics --robot " + ur5 + " --q 0,0,x,0,0,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("--q: expected comma-separated numbers, got 'x'"));
  r = runCli("dynamics --robot " + ur5 + " --q 0,0,0,0,0,0 --frame nowhere");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown frame 'nowhere'"));
  const TempDir tmp_dir;
  const auto tmp = tmp_dir / "jointsim_bad_robot.yaml";
  std::ofstream(tmp) << "name: r\nconvention: tree\nlinks: []\njoints: []\nextra: 1\n";
  r = runCli("dynamics --robot " + tmp.string() + " --q 0");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr(tmp.string() + ":5: extra: unknown key 'extra'"));
  const auto bad_urdf = tmp_dir / "jointsim_bad.urdf";
  std::ofstream(bad_urdf) << "<robot name='r'><link name='a'>";
  r = runCli("dynamics --robot " + bad_urdf.string() + " --q 0");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr(bad_urdf.string() + ": not a valid URDF"));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one-line error: " << r.err;
}

// Every class of bad robot file gives exit status 2 and one line naming the file, line, key path and expectation.
TEST(CliDynamics, BadRobotFilesExitTwoWithOneLine) {
  const std::string good = R"(name: arm
convention: dh_hayati
links:
  - name: link1
    joint: {name: j1, a: 0.5, alpha: 0, d: 0, theta: 0}
    mass: 2.0
    com: [-0.25, 0, 0]
    inertia: [0.01, 0.05, 0.05, 0, 0, 0]
)";
  struct Case {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
      {"    mass: 2.0", "    mass: 2.0\n    colour: red", ":7: links[0].colour: unknown key 'colour'"},
      {"    com: [-0.25, 0, 0]\n", "", ":4: links[0]: missing required key 'com'"},
      {"mass: 2.0", "mass: -2.0", ":6: links[0].mass: mass must be >= 0 kg"},
      {"[0.01, 0.05, 0.05, 0, 0, 0]", "[0.01, 0.05, 0.05, 0, 0, -0.1]", ":8: links[0].inertia: inertia tensor"},
      {"a: 0.5", "a: [0.5]", ":5: links[0].joint.a: expected a length, got a list of 1 items"},
  };
  const TempDir tmp;
  const auto path = tmp / "jointsim_cli_bad_robot.yaml";
  for (const Case& c : cases) {
    std::string text = good;
    text.replace(text.find(c.from), c.from.size(), c.to);
    std::ofstream(path) << text;
    const Result r = runCli("dynamics --robot " + path.string() + " --q 0");
    EXPECT_EQ(r.status, 2) << c.expected;
    EXPECT_THAT(r.err, HasSubstr(path.string() + c.expected));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
}

TEST(CliRun, WritesCsvAndSummary) {
  const TempDir tmp;
  const auto dir = tmp / "jointsim_run_test";
  const Result r = runCli("run " + sourcePath("config/experiments/ur5_fall.yaml") + " -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("real-time factor"));
  // One line says what to look at next, with the command as it was typed.
  EXPECT_THAT(r.out, HasSubstr("next:    read the log (one column per signal, SI units) or draw it: " +
                               std::string(JOINTSIM_CLI_PATH) + " plot " + dir.string() + "\n"));
  std::ifstream csv(dir / "ur5_fall.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_THAT(header, ::testing::StartsWith("time[s],q_shoulder_pan_joint[rad],"));
  size_t rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 1001u);  // 2 s at 500 Hz plus t = 0
  std::ifstream summary(dir / "summary.json");
  std::stringstream ss;
  ss << summary.rdbuf();
  EXPECT_THAT(ss.str(), HasSubstr("\"status\": \"ok\""));
  EXPECT_THAT(ss.str(), HasSubstr("\"real_time_factor\""));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp"))) << "leftover temporary file";
}

TEST(CliRun, BadExperimentFileWritesNothing) {
  const TempDir tmp;
  const auto dir = tmp / "jointsim_run_bad";
  const auto cfg = tmp / "jointsim_bad_experiment.yaml";
  std::ofstream(cfg) << "experiment: {name: x, type: passive_robot}\nrobot: " << sourcePath("config/robots/ur5.yaml")
                     << "\nduration: -1\n";
  const Result r = runCli("run " + cfg.string() + " -o " + dir.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr(cfg.string() + ":3: duration: expected a time > 0 s, got '-1'"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv"));
}

TEST(CliRun, SolverFailureLeavesFailedSummaryAndNoCsv) {
  const TempDir tmp;
  const auto dir = tmp / "jointsim_run_fail";
  const auto cfg = tmp / "jointsim_fail_experiment.yaml";
  // Far too few steps allowed per output interval: CVODE gives up (CV_TOO_MUCH_WORK).
  std::ofstream(cfg) << "experiment: {name: f, type: passive_robot}\nrobot: " << sourcePath("config/robots/ur5.yaml")
                     << "\nduration: 1\nlog_rate: 1\nsolver: {rtol: 1.0e-12, atol: 1.0e-14, max_num_steps: 5}\n";
  const Result r = runCli("run " + cfg.string() + " -o " + dir.string());
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.err, HasSubstr("CV_TOO_MUCH_WORK"));
  EXPECT_FALSE(std::filesystem::exists(dir / "f.csv"));
  std::ifstream summary(dir / "summary.json");
  std::stringstream ss;
  ss << summary.rdbuf();
  EXPECT_THAT(ss.str(), HasSubstr("\"status\": \"failed\""));
  EXPECT_THAT(ss.str(), HasSubstr("\"reason\""));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp"))) << "leftover temporary file";
}
