// `jointsim run` on joint-rig files: every class of bad input gives exit status 2, a message naming the
// file, the line and the key path, and no output files; a solver failure gives exit status 1 and a
// "failed" summary without a CSV.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.hpp"

using ::testing::HasSubstr;

namespace {
using Result = jointsim::test::CliResult;
using jointsim::test::TempDir;

Result run(const std::string& args) { return jointsim::test::runCli(args); }

const char* kGood = R"(experiment: {name: rig, type: joint_rig}
rotor_inertia: 0.01
transmission: {type: elasto_backlash, stiffness: 25.7, backlash: 0.0102, damping: 0.5}
friction:
  side: motor
  model: {type: table, tau_pos: [[0, 1.91], [1, 1.91]]}
load: {clamped: true}
input: {type: torque, profile: {type: triangle, amplitude: 5.0, period: 4.0}}
duration: 4.0
log_rate: 50
)";
}  // namespace

TEST(CliRig, GoodFileRuns) {
  const TempDir tmp;
  const auto dir = tmp / "jointsim_rig_good";
  const auto cfg = tmp / "jointsim_rig_good.yaml";
  std::ofstream(cfg) << kGood;
  const Result r = run("run " + cfg.string() + " -o " + dir.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "rig.csv"));
}

TEST(CliRig, BadInputExitTwoWithFileLineKeyPathAndNoOutput) {
  struct Case {
    std::string from, to, extra_args, expected;
  };
  const std::vector<Case> cases = {
      {"load: {clamped: true}", "load: {clamped: true, mass: 3}", "", ":7: load.mass: unknown key 'mass'"},
      {"stiffness: 25.7", "stiffness: stiff", "",
       ":3: transmission.stiffness: expected a stiffness in N·m/rad, got 'stiff'"},
      {"backlash: 0.0102, ", "", "", ":3: transmission: missing required key 'backlash'"},
      {"stiffness: 25.7", "stiffness: -25.7", "",
       ":3: transmission.stiffness: expected a finite value > 0 N·m/rad, got -25.7"},
      {"rotor_inertia: 0.01", "rotor_inertia: -0.01", "",
       ":2: rotor_inertia: expected a rotor inertia > 0 kg·m², got '-0.01'"},
      {"{type: triangle, amplitude: 5.0, period: 4.0}", "{type: csv, file: /nonexistent/torque.csv}", "",
       ":8: input.profile: /nonexistent/torque.csv: cannot open CSV file for reading"},
      {"", "", "--set load.inertia=2", "has no key 'load.inertia'"},
      {"", "", "--set transmission.stiffness=abc",
       "transmission.stiffness: expected a stiffness in N·m/rad, got 'abc'"},
  };
  const TempDir tmp;
  const auto cfg = tmp / "jointsim_rig_bad.yaml";
  for (const Case& c : cases) {
    const auto dir = tmp / "jointsim_rig_bad_out";
    std::filesystem::remove_all(dir);
    std::string text = kGood;
    if (!c.from.empty()) {
      const size_t at = text.find(c.from);
      ASSERT_NE(at, std::string::npos) << c.from;
      text.replace(at, c.from.size(), c.to);
    }
    std::ofstream(cfg) << text;
    const Result r = run("run " + cfg.string() + " -o " + dir.string() + " " + c.extra_args);
    EXPECT_EQ(r.status, 2) << c.expected << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.expected));
    if (c.extra_args.empty()) {
      EXPECT_THAT(r.err, HasSubstr(cfg.string()));
    }
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "rig.csv")) << c.expected;
    EXPECT_FALSE(std::filesystem::exists(dir / "summary.json")) << c.expected;
  }
}

TEST(CliRig, SolverFailureLeavesFailedSummary) {
  const TempDir tmp;
  const auto dir = tmp / "jointsim_rig_fail";
  const auto cfg = tmp / "jointsim_rig_fail.yaml";
  std::ofstream(cfg) << kGood << "solver: {rtol: 1.0e-12, atol: 1.0e-14, max_num_steps: 3}\n";
  const Result r = run("run " + cfg.string() + " -o " + dir.string());
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("joint rig 'rig'"));
  EXPECT_THAT(r.err, HasSubstr("at t = "));
  EXPECT_FALSE(std::filesystem::exists(dir / "rig.csv"));
  std::ifstream in(dir / "summary.json");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_THAT(ss.str(), HasSubstr("\"status\": \"failed\""));
  EXPECT_THAT(ss.str(), HasSubstr("\"reason\": \"joint rig 'rig': more than max_num_steps = 3 solver steps in one "
                                  "output interval (CV_TOO_MUCH_WORK) at t = "));
}
