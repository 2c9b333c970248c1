// Golden regression tests (docs/regression.md): each case of tests/golden/cases.txt runs its shortened
// experiment with `jointsim run` and compares the log with the committed decimated reference
// tests/golden/<name>.csv using `jointsim compare` and the case's tolerances. The reference's times are a
// subset of the log's (every EVERY-th row), so compare matches them sample by sample without interpolation.
// Regenerate the references with: bash scripts/regenerate-golden.sh build/jointsim
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/report/compare.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using jointsim::test::sourcePath;

namespace {

struct GoldenCase {
  std::string name, config;
  int every = 1;
  std::string rtol, atol;
  std::vector<std::string> overrides;
};

/// Names the case in test listings (CTest shows "GetParam() = NAME" instead of the object's bytes).
void PrintTo(const GoldenCase& c, std::ostream* os) { *os << c.name; }

std::vector<GoldenCase> readCases() {
  std::ifstream in(sourcePath("tests/golden/cases.txt"));
  std::vector<GoldenCase> cases;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    GoldenCase c;
    if (!(ss >> c.name) || c.name[0] == '#') continue;
    ss >> c.config >> c.every >> c.rtol >> c.atol;
    for (std::string o; ss >> o;) c.overrides.push_back(o);
    cases.push_back(c);
  }
  return cases;
}

GoldenCase findCase(const std::string& name) {
  for (const auto& c : readCases())
    if (c.name == name) return c;
  throw std::runtime_error("no golden case " + name + " in tests/golden/cases.txt");
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

using Result = jointsim::test::CliResult;
using jointsim::test::runCli;
/// A scratch directory of this test alone (CTest runs the tests in parallel processes).
using Scratch = jointsim::test::TempDir;

/// Runs the case's experiment (plus `extra` overrides) into `dir`; returns the log path ("" on failure).
std::string runCase(const GoldenCase& c, const std::filesystem::path& dir, const std::vector<std::string>& extra = {}) {
  std::string args = "run " + sourcePath(c.config) + " -o " + (dir / "out").string();
  for (const auto& o : c.overrides) args += " --set " + o;
  for (const auto& o : extra) args += " --set " + o;
  const Result r = runCli(args);
  EXPECT_EQ(r.status, 0) << "jointsim " << args << "\n" << r.out << r.err;
  const size_t at = r.out.find("log:");
  if (r.status != 0 || at == std::string::npos) return {};
  std::istringstream ss(r.out.substr(at + 4));
  std::string log;
  ss >> log;
  return log;
}

Result compareWithGolden(const GoldenCase& c, const std::string& log) {
  return runCli("compare " + sourcePath("tests/golden/" + c.name + ".csv") + " " + log + " --rtol " + c.rtol +
                " --atol " + c.atol);
}

class GoldenCaseTest : public ::testing::TestWithParam<GoldenCase> {};

}  // namespace

TEST_P(GoldenCaseTest, Matches) {
  const GoldenCase& c = GetParam();
  const Scratch dir(c.name);
  const std::string log = runCase(c, dir);
  ASSERT_FALSE(log.empty());
  const Result r = compareWithGolden(c, log);
  EXPECT_EQ(r.status, 0) << "the log of " << c.name << " differs from tests/golden/" << c.name
                         << ".csv (if the change is intended: bash scripts/regenerate-golden.sh)\n"
                         << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("(0 with B interpolated)")) << "the reference must lie on the log's time grid";
}

INSTANTIATE_TEST_SUITE_P(Golden, GoldenCaseTest, ::testing::ValuesIn(readCases()),
                         [](const ::testing::TestParamInfo<GoldenCase>& info) { return info.param.name; });

TEST(Golden, CasesCoverEveryExperimentTypeAndReferencesAreSmall) {
  const std::vector<GoldenCase> cases = readCases();
  ASSERT_GE(cases.size(), 7u);
  std::set<std::string> types;
  std::uintmax_t bytes = 0;
  for (const auto& c : cases) {
    const std::string yaml = slurp(sourcePath(c.config));
    const size_t at = yaml.find("type:");
    ASSERT_NE(at, std::string::npos) << c.config;
    std::istringstream ss(yaml.substr(at + 5));
    std::string type;
    ss >> type;
    types.insert(type);
    const std::string ref = sourcePath("tests/golden/" + c.name + ".csv");
    ASSERT_TRUE(std::filesystem::exists(ref)) << ref << " (bash scripts/regenerate-golden.sh)";
    bytes += std::filesystem::file_size(ref);
  }
  for (const char* t :
       {"passive_robot", "joint_rig", "tracking", "drive_chain", "robotr3_axis", "robotr3_full", "clamping"})
    EXPECT_EQ(types.count(t), 1u) << "no golden case of type " << t;
  EXPECT_LT(bytes, 1000000u) << "keep tests/golden/ small: decimate more";
}

// Acceptance: a 1 % change of a stiffness parameter makes the comparison fail and names the columns that
// moved, while the unchanged rerun (GoldenCaseTest.Matches/kr300_joint1_clamping) passes.
TEST(Golden, CatchesOnePercentStiffnessChangeOnKr300ClampingRig) {
  const GoldenCase c = findCase("kr300_joint1_clamping");
  const Scratch dir("kr300_stiffness");
  const std::string log = runCase(c, dir, {"transmission.stiffness=25.957"});  // 25.7 N·m/rad + 1 %
  ASSERT_FALSE(log.empty());
  const Result r = compareWithGolden(c, log);
  EXPECT_EQ(r.status, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("columns differ beyond tolerance"));
  EXPECT_THAT(r.err, HasSubstr("motor_angle[rad]"));
  EXPECT_THAT(r.out, ::testing::ContainsRegex("motor_angle\\[rad\\] .* FAIL"));
  // With margin: the deflection changes by about 1 % of the motor angle, ~100 × the tolerance.
  jointsim::report::CompareOptions o;
  o.rtol = std::stod(c.rtol);
  o.atol = std::stod(c.atol);
  const auto result = jointsim::report::compareCsvFiles(sourcePath("tests/golden/" + c.name + ".csv"), log, o);
  for (const auto& col : result.columns) {
    if (col.name == "motor_angle[rad]") {
      EXPECT_GT(col.max_deviation, 20.0 * col.tolerance);
    }
  }
  // Columns that the stiffness cannot move (the clamped output) stay within tolerance.
  EXPECT_THAT(r.out, ::testing::ContainsRegex("output_angle\\[rad\\] .* ok"));
}

TEST(Golden, CatchesOnePercentStiffnessChangeOnIrb140Clamping) {
  const GoldenCase c = findCase("irb140_clamping");
  const Scratch dir("irb140_stiffness");
  const std::string log = runCase(c, dir, {"axes[1].c=8.282"});  // joint 2: 8.2 N·m/rad + 1 %
  ASSERT_FALSE(log.empty());
  const Result r = compareWithGolden(c, log);
  EXPECT_EQ(r.status, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("joint2.deflection[rad]"));
  EXPECT_THAT(r.out, ::testing::ContainsRegex("joint2\\.motor_angle\\[rad\\] .* FAIL"));
}

TEST(Golden, CompareExitStatus2ForUnreadableOrIncompatibleFiles) {
  const Scratch dir("incompatible");
  const std::string ref = sourcePath("tests/golden/kr300_joint1_clamping.csv");
  Result r = runCli("compare " + ref + " " + (dir / "missing.csv").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("missing.csv"));
  r = runCli("compare " + ref + " " + sourcePath("tests/golden/ur5_fall.csv"));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("incompatible"));
  r = runCli("compare " + ref + " " + ref + " --columns motor_angle,friction_torque");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("all 2 columns within tolerance"));
}
