// `jointsim validate` and `--set +key.path=value`: a file is checked completely without a run (every run of a
// sweep loaded with its settings); `+` adds a key the file lacks, which the loader then checks as if written.
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.hpp"

using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {
using Result = jointsim::test::CliResult;
Result run(const std::string& args) { return jointsim::test::runCli(args); }
const std::string kRoot = JOINTSIM_SOURCE_DIR;
}  // namespace

TEST(CliValidate, ExperimentAndSweepFilesAreCheckedWithoutRunning) {
  Result r = run("validate " + kRoot + "/config/experiments/ur5_excitation.yaml");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("valid tracking experiment 'ur5_excitation': 96 states, 72 signals, 10 s"));
  EXPECT_THAT(r.out, HasSubstr("config/robots/ur5_drives.yaml"));
  EXPECT_THAT(r.out, HasSubstr("config/robots/ur5.yaml"));
  r = run("validate " + kRoot + "/config/sweeps/ur5_faults.yaml");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("valid sweep 'ur5_faults': 25 runs of a tracking experiment"));
  EXPECT_THAT(r.out, HasSubstr("config/robots/ur5_drives_elastic.yaml"));  // the sweep's common override
}

TEST(CliValidate, AProblemInOneRunOfASweepIsFoundAndNamed) {
  const jointsim::test::TempDir tmp;
  const fs::path dir = tmp.path();
  // backlash_add does not apply to the strain-wave gears of ur5_drives.yaml: only the second run is wrong.
  std::ofstream(dir / "sweep.yaml") << "sweep:\n  name: s\n  experiment: " << kRoot
                                    << "/config/experiments/ur5_excitation.yaml\n"
                                       "runs:\n  - name: nominal\n"
                                       "faults:\n  - {type: backlash_add, joints: [elbow_joint], values: [1.0e-3]}\n";
  const Result r = run("validate " + (dir / "sweep.yaml").string());
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_THAT(r.err, HasSubstr("run '"));
  EXPECT_THAT(r.err, HasSubstr("backlash_add"));
  EXPECT_TRUE(fs::exists(dir / "sweep.yaml"));
  size_t entries = 0;
  for (auto it = fs::directory_iterator(dir); it != fs::directory_iterator(); ++it) ++entries;
  EXPECT_EQ(entries, 1u) << "nothing written";
}

TEST(CliSetAdd, PlusAddsAKeyTheFileLacksAndTheLoaderChecksIt) {
  const std::string fall = kRoot + "/config/experiments/ur5_fall.yaml";
  const jointsim::test::TempDir tmp;
  const fs::path out = tmp / "jointsim_set_add";
  // ur5_fall.yaml has no solver block.
  Result r = run("run " + fall + " --set duration=0.05 --set solver.max_step=0.001 -o " + out.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("the file has no key 'solver.max_step' (to add it, override +solver.max_step=0.001)"));
  r = run("run " + fall + " --set duration=0.05 --set +solver.max_step=0.001 -o " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string text = jointsim::test::readText(out / "summary.json");
  EXPECT_THAT(text, HasSubstr("\"max_step\": 0.001"));
  // Steps of at most 1 ms: at least 50 for 0.05 s.
  const auto at = text.find("\"steps\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GE(std::stol(text.substr(at + 9)), 50);
  r = run("validate " + fall + " --set +solver.bogus=1");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown key 'bogus'"));
  r = run("validate " + kRoot + "/config/experiments/ur5_excitation.yaml --set +trajectory.offset[9]=1");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("list entries cannot be added"));
  r = run("validate " + fall + " --set +duration=0.5");  // an existing key: replaced as without '+'
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr(", 0.5 s"));
}
