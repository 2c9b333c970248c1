// `jointsim batch`: a fault-injection sweep of the UR5 twin with every fault type finishes with a complete
// manifest; a batch killed midway resumes and runs only what is missing; two shards cover the sweep
// exactly once; a failing run is recorded without stopping the others; bad sweep files exit 2.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/io/csv_reader.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

using Result = jointsim::test::CliResult;
using jointsim::test::TempDir;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Result run(const std::string& args) { return jointsim::test::runCli(args); }

// A sweep of the UR5 twin (elastic gears) over `duration` simulated seconds: one nominal run and four runs
// per fault type (24 faulty runs), plus `extra` YAML appended to the runs list.
fs::path writeSweep(const fs::path& dir, double duration, const std::string& extra = "") {
  const fs::path p = dir / "sweep.yaml";
  std::ofstream(p)
      << "sweep:\n  name: test_sweep\n  experiment: "
      << jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml")
      << "\n  set: {robot: ../robots/ur5_drives_elastic.yaml, duration: " << duration << ", log_rate: 50}\n"
      << "runs:\n  - name: nominal\n"
      << extra
      << "faults:\n"
         "  - {type: gear_stiffness_scale,   joints: [shoulder_lift_joint, elbow_joint], values: [0.8, 0.6]}\n"
         "  - {type: backlash_add,           joints: [shoulder_lift_joint, elbow_joint], values: [2.9e-4, 1.0e-3]}\n"
         "  - {type: coulomb_friction_scale, joints: [shoulder_pan_joint, shoulder_lift_joint], values: [1.5, 2.0]}\n"
         "  - {type: sigma0_scale,           joints: [shoulder_pan_joint, elbow_joint], values: [0.5, 2.0]}\n"
         "  - {type: torque_constant_scale,  joints: [shoulder_lift_joint, wrist_1_joint], values: [0.9, 0.8]}\n"
         "  - {type: sensor_bias,            joints: [shoulder_pan_joint, wrist_2_joint], values: [1.0e-3, -1.0e-3]}\n";
  return p;
}

// Manifest rows: run -> status (header checked).
std::map<std::string, std::string> manifest(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,overrides,jointsim_version,git_commit,"
                  "started_utc,inputs,fault_type,fault_joint,fault_severity,fault_onset_s,design,seed");
  std::map<std::string, std::string> rows;
  while (std::getline(in, line)) {
    const size_t a = line.find(','), b = line.find(',', a + 1);
    rows[line.substr(0, a)] = line.substr(a + 1, b - a - 1);
  }
  return rows;
}

int okSummaries(const fs::path& out) {
  int n = 0;
  if (!fs::exists(out)) return 0;
  for (const auto& e : fs::directory_iterator(out))
    if (e.is_directory() && slurp(e.path() / "summary.json").find("\"status\": \"ok\"") != std::string::npos) ++n;
  return n;
}

}  // namespace

TEST(CliBatch, FaultSweepWithEveryFaultTypeCompletesItsManifest) {
  const TempDir tmp("all");
  const fs::path& dir = tmp.path();
  const Result r = run("batch " + writeSweep(dir, 0.3).string() + " -j 2 -o " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  const auto rows = manifest(dir / "out" / "manifest.csv");
  ASSERT_EQ(rows.size(), 25u);
  std::set<std::string> types;
  for (const auto& [name, status] : rows) {
    EXPECT_EQ(status, "ok") << name;
    EXPECT_TRUE(fs::exists(dir / "out" / name / "ur5_excitation.csv")) << name;
    types.insert(name.substr(0, name.find('-')));
  }
  for (const char* t : {"gear_stiffness_scale", "backlash_add", "coulomb_friction_scale", "sigma0_scale",
                        "torque_constant_scale", "sensor_bias", "nominal"})
    EXPECT_TRUE(types.count(t)) << t;
  EXPECT_THAT(slurp(dir / "out" / "manifest.csv"), HasSubstr("fault backlash_add@elbow_joint=0.001"));
  // Label columns at the end of each line: fault_type, fault_joint, fault_severity, fault_onset_s, design, seed.
  const std::string text = slurp(dir / "out" / "manifest.csv");
  EXPECT_THAT(text.substr(0, text.find('\n')),
              ::testing::EndsWith(",inputs,fault_type,fault_joint,fault_severity,fault_onset_s,design,seed"));
  auto lineOf = [&](const std::string& run) {
    const auto at = text.find("\n" + run + ",");
    return text.substr(at + 1, text.find('\n', at + 1) - at - 1);
  };
  EXPECT_THAT(lineOf("backlash_add-elbow_joint-0.001"), ::testing::EndsWith(",backlash_add,elbow_joint,0.001,0,,"));
  EXPECT_THAT(lineOf("nominal"), ::testing::EndsWith("\",,,,,,"));
  // Faults change the run: the faulty logs differ from the nominal one.
  EXPECT_NE(slurp(dir / "out" / "nominal" / "ur5_excitation.csv"),
            slurp(dir / "out" / "backlash_add-elbow_joint-0.001" / "ur5_excitation.csv"));
}

TEST(CliBatch, KilledMidwayResumesOnlyTheMissingRuns) {
  const TempDir tmp("resume");
  const fs::path& dir = tmp.path();
  const fs::path out = dir / "out";
  const std::string args = "batch " + writeSweep(dir, 1.0).string() + " -j 1 -o " + out.string();
  // Start the batch in its own process group, wait until a few runs have finished, kill the whole group.
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::setpgid(0, 0);
    const std::string cmd = std::string(JOINTSIM_CLI_PATH) + " " + args + " >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  ::setpgid(pid, pid);
  const auto t0 = std::chrono::steady_clock::now();
  while (okSummaries(out) < 4 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(-pid, SIGKILL);
  int st = 0;
  ::waitpid(pid, &st, 0);
  const int done_before = okSummaries(out);
  ASSERT_GE(done_before, 4);
  ASSERT_LT(done_before, 25) << "the batch finished before it could be killed";
  std::map<std::string, fs::file_time_type> stamps;
  for (const auto& e : fs::directory_iterator(out))
    if (fs::exists(e.path() / "summary.json"))
      stamps[e.path().filename()] = fs::last_write_time(e.path() / "summary.json");
  // The interrupted manifest is consistent: every run is listed.
  EXPECT_EQ(manifest(out / "manifest.csv").size(), 25u);

  const Result r = run(args);
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr(std::to_string(25 - done_before) + " ok"));
  EXPECT_THAT(r.out, HasSubstr(std::to_string(done_before) + " skipped"));
  for (const auto& [name, status] : manifest(out / "manifest.csv")) EXPECT_EQ(status, "ok") << name;
  for (const auto& [name, t] : stamps) {  // finished runs were not run again
    if (slurp(out / name / "summary.json").find("\"status\": \"ok\"") != std::string::npos) {
      EXPECT_EQ(fs::last_write_time(out / name / "summary.json"), t) << name;
    }
  }
}

TEST(CliBatch, TwoShardsCoverTheSweepExactlyOnce) {
  const TempDir tmp("shards");
  const fs::path& dir = tmp.path();
  const fs::path sweep = writeSweep(dir, 0.2), out = dir / "out";
  const Result a = run("batch " + sweep.string() + " --shard 0/2 -o " + out.string());
  ASSERT_EQ(a.status, 0) << a.err;
  const auto m0 = manifest(out / "manifest.shard-0-of-2.csv");
  const Result b = run("batch " + sweep.string() + " --shard 1/2 -o " + out.string());
  ASSERT_EQ(b.status, 0) << b.err;
  const auto m1 = manifest(out / "manifest.shard-1-of-2.csv");
  EXPECT_EQ(m0.size(), 13u);
  EXPECT_EQ(m1.size(), 12u);
  for (const auto& [name, s] : m0) EXPECT_FALSE(m1.count(name)) << name << " ran in both shards";
  EXPECT_THAT(b.out, HasSubstr("0 skipped"));  // shard 1 did not re-run shard 0's runs
  const Result c = run("batch " + sweep.string() + " --collect -o " + out.string());
  ASSERT_EQ(c.status, 0) << c.err;
  const auto all = manifest(out / "manifest.csv");
  EXPECT_EQ(all.size(), 25u);
  for (const auto& [name, status] : all) EXPECT_EQ(status, "ok") << name;
  EXPECT_EQ(run("batch " + sweep.string() + " --shard 2/2").status, 2);
  EXPECT_EQ(run("batch " + sweep.string() + " --shard x").status, 2);
}

TEST(CliBatch, FailingRunIsRecordedAndTheOthersFinish) {
  const TempDir tmp("failing");
  const fs::path& dir = tmp.path();
  const std::string extra =
      "  - {name: bad_key, set: {no_such_key: 1}}\n"
      "  - {name: swg_backlash, set: {robot: ../robots/ur5_drives.yaml}, faults: [{type: backlash_add, joint: elbow_joint, value: 0.001}]}\n";
  const Result r = run("batch " + writeSweep(dir, 0.2, extra).string() + " -j 2 -o " + (dir / "out").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.err, HasSubstr("2 run(s) failed"));
  const auto rows = manifest(dir / "out" / "manifest.csv");
  ASSERT_EQ(rows.size(), 27u);
  EXPECT_EQ(rows.at("bad_key"), "error");
  EXPECT_EQ(rows.at("swg_backlash"), "error");
  EXPECT_THAT(slurp(dir / "out" / "swg_backlash" / "run.log"), HasSubstr("strain_wave_gear"));
  int ok = 0;
  for (const auto& [name, status] : rows) ok += status == "ok";
  EXPECT_EQ(ok, 25);
  // Collected from the folders (as after the shards of a job array), the runs that ended before writing a summary
  // are still errors, not pending.
  const Result c = run("batch " + (dir / "sweep.yaml").string() + " --collect -o " + (dir / "out").string());
  EXPECT_EQ(c.status, 1);
  const auto collected = manifest(dir / "out" / "manifest.csv");
  EXPECT_EQ(collected.at("bad_key"), "error");
  EXPECT_EQ(collected.at("swg_backlash"), "error");
}

TEST(CliBatch, BadSweepFilesExitTwoWithFileAndLine) {
  const TempDir tmp("bad");
  const fs::path& dir = tmp.path();
  struct Case {
    std::string text, expected;
  };
  const std::string head =
      "sweep:\n  name: s\n  experiment: " + jointsim::test::sourcePath("config/experiments/ur5_fall.yaml") + "\n";
  const std::vector<Case> cases{
      {head + "runs:\n  - name: a\n  - name: a\n", "duplicate run name 'a'"},
      {head + "faults:\n  - {type: gear_wear, joints: [j], values: [1]}\n", "unknown fault 'gear_wear'"},
      {head + "grid:\n  duration: []\n", "at least one value"},
      {head, "the sweep has no runs"},
      {"sweep:\n  name: s\n  experiment: nowhere.yaml\nruns: [{name: a}]\n", "no such file"},
      {head + "runs:\n  - {name: a, sets: {duration: 1}}\n", "did you mean 'set'"},
      // Severities out of their type's range and bad time laws fail the sweep before any run.
      {head + "faults:\n  - {type: gear_stiffness_scale, joints: [j], values: [0.8, -0.5]}\n", "> 0 and <= 100"},
      {head + "faults:\n  - {type: backlash_add, joints: [j], values: [2.0]}\n", "<= 0.5 rad"},
      {head + "runs:\n  - {name: a, faults: [{type: sensor_spike, joint: j, value: 9}]}\n", "within ±π rad"},
      {head + "faults:\n  - {type: coulomb_friction_scale, joints: [j], values: [2], progression: cubic}\n",
       "step, linear or exponential"},
      {head + "faults:\n  - {type: coulomb_friction_scale, joints: [j], values: [2], progression: linear}\n",
       "ramp_time"},
      {head + "faults:\n  - {type: sensor_dropout, joints: [j], values: [0.5], period: 0.1}\n",
       "longer than the period"},
      // Counts are reported as written (a clamp once turned 10^9 into "1000000" and -5 into "-1").
      {head + "faults:\n  - {type: coulomb_friction_scale, joints: [j], values: [2], progression: linear, "
              "ramp_time: 1, steps: 1000000000}\n",
       "expected 1 to 100000 parameter updates, got 1000000000"},
      {head + "faults:\n  - {type: coulomb_friction_scale, joints: [j], values: [2], progression: linear, "
              "ramp_time: 1, steps: -5}\n",
       "expected 1 to 100000 parameter updates, got -5"},
      {head + "faults:\n  - {type: sensor_dropout, joints: [j], values: [0.01], period: 0.1, count: -5}\n", "got -5"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const fs::path p = dir / ("bad" + std::to_string(i) + ".yaml");
    std::ofstream(p) << cases[i].text;
    const Result r = run("batch " + p.string() + " -o " + (dir / "out").string());
    EXPECT_EQ(r.status, 2) << cases[i].expected << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(cases[i].expected));
    EXPECT_THAT(r.err, HasSubstr(p.filename().string() + ":"));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "manifest.csv"));
  // Bad command lines: a shard beyond the count, a data set in a folder that does not exist, a data set of a shard.
  const fs::path good = writeSweep(dir, 0.1);
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {" --shard 3/2", "0 <= I < N"},
           {" --dataset " + (dir / "missing" / "d.h5").string(), "does not exist"},
           {" --shard 0/2 --dataset " + (dir / "d.h5").string(), "needs the whole sweep"}}) {
    const Result r = run("batch " + good.string() + " -o " + (dir / "out").string() + args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(expected));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));  // nothing ran
  EXPECT_FALSE(fs::exists(dir / "d.h5"));
}

TEST(CliBatch, ResumeReusesOnlyRunsWhoseSettingsAreUnchanged) {
  const TempDir tmp("settings");
  const fs::path& dir = tmp.path();
  const fs::path out = dir / "out";
  auto write = [&](const std::string& durations, int log_rate) {
    std::ofstream(dir / "grid.yaml") << "sweep:\n  name: g\n  experiment: "
                                     << jointsim::test::sourcePath("config/experiments/ur5_fall.yaml")
                                     << "\n  set: {log_rate: " << log_rate << "}\ngrid:\n  duration: [" << durations
                                     << "]\n";
    return run("batch " + (dir / "grid.yaml").string() + " -o " + out.string());
  };
  Result r = write("0.2, 0.3", 50);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 ok"));
  // A new grid value: only the new run executes; runs are named by their values.
  r = write("0.1, 0.2, 0.3", 50);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("1 ok"));
  EXPECT_THAT(r.out, HasSubstr("2 skipped"));
  const auto rows = manifest(out / "manifest.csv");
  EXPECT_TRUE(rows.count("grid-duration_0.1") && rows.count("grid-duration_0.2") && rows.count("grid-duration_0.3"));
  // Changed common settings: every run executes again.
  r = write("0.1, 0.2, 0.3", 100);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("3 ok"));
  EXPECT_THAT(r.out, HasSubstr("0 skipped"));
  EXPECT_THAT(slurp(out / "grid-duration_0.1" / "summary.json"), HasSubstr("\"log_rate\": 100"));
}

TEST(CliBatch, EditedRobotFileRecomputesTheRunsThatReadIt) {
  // Resume compares the content hash of every file a finished run read (summary.json "inputs") with the file
  // now: editing the robot file recomputes the runs; an unrelated edit does not.
  const TempDir tmp("inputs");
  const fs::path& dir = tmp.path();
  const fs::path out = dir / "out";
  fs::create_directories(dir / "experiments");
  fs::create_directories(dir / "robots");
  fs::copy_file(jointsim::test::sourcePath("config/experiments/ur5_fall.yaml"), dir / "experiments" / "ur5_fall.yaml");
  fs::copy_file(jointsim::test::sourcePath("config/robots/ur5.yaml"), dir / "robots" / "ur5.yaml");
  std::ofstream(dir / "grid.yaml") << "sweep:\n  name: g\n  experiment: experiments/ur5_fall.yaml\n"
                                   << "  set: {log_rate: 50}\ngrid:\n  duration: [0.1, 0.2]\n";
  const std::string args = "batch " + (dir / "grid.yaml").string() + " -o " + out.string();
  Result r = run(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 ok"));
  const std::string summary = slurp(out / "grid-duration_0.1" / "summary.json");
  EXPECT_THAT(summary, HasSubstr("robots/ur5.yaml"));
  EXPECT_THAT(summary, HasSubstr("\"hash\": \"xxh3:"));
  EXPECT_THAT(slurp(out / "manifest.csv"), HasSubstr("ur5.yaml=xxh3:"));
  // Unchanged inputs (and an unrelated new file): both runs are reused.
  std::ofstream(dir / "robots" / "unrelated.yaml") << "name: x\n";
  r = run(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 skipped"));
  // The robot file changes (a comment only, but its bytes change): both runs are recomputed.
  std::ofstream(dir / "robots" / "ur5.yaml", std::ios::app) << "# edited\n";
  r = run(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 ok"));
  EXPECT_THAT(r.out, HasSubstr("0 skipped"));
  EXPECT_NE(slurp(out / "grid-duration_0.1" / "summary.json"), summary);
  // And reused again once the results match the edited file.
  r = run(args);
  EXPECT_THAT(r.out, HasSubstr("2 skipped"));
}

// A sampled sweep runs and labels its runs with the design and the seed; the sampled value reaches the run.
TEST(CliBatch, SampledRunsCarryDesignAndSeedAndTheirValues) {
  const TempDir tmp("sampled");
  const fs::path& dir = tmp.path();
  const std::string exp = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/ur5_swg_joint_velocity.yaml";
  std::ofstream(dir / "s.yaml") << "sweep: {name: s, experiment: " << exp << ", set: {duration: 0.05}}\n"
                                << "sample:\n  design: latin_hypercube\n  runs: 3\n  seed: 5\n  parameters:\n"
                                << "    load.inertia: {distribution: uniform, low: 1.0, high: 2.0}\n";
  const Result r = run("batch " + (dir / "s.yaml").string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  const std::string text = slurp(dir / "out" / "manifest.csv");
  for (const char* name : {"sample-0", "sample-1", "sample-2"}) {
    const auto at = text.find(std::string("\n") + name + ",ok,");
    ASSERT_NE(at, std::string::npos) << name << "\n" << text;
    const std::string line = text.substr(at + 1, text.find('\n', at + 1) - at - 1);
    EXPECT_THAT(line, ::testing::EndsWith(",,,,,latin_hypercube,5")) << line;
    // The run's summary holds the sampled inertia given in its overrides.
    const auto o = line.find("load.inertia=");
    ASSERT_NE(o, std::string::npos);
    const double inertia = std::stod(line.substr(o + 13));
    EXPECT_GT(inertia, 1.0);
    EXPECT_LT(inertia, 2.0);
    EXPECT_THAT(slurp(dir / "out" / name / "summary.json"), HasSubstr("\"inertia\": " + line.substr(o + 13, 6)));
  }
}

namespace {

// On a terminal (here the pseudo-terminal of util-linux `script`), the progress line of `jointsim batch` says how
// many runs are done and, once one has finished, about how long the rest will take; not on a pipe or file.
TEST(CliBatch, TheProgressLineOnATerminalGivesTheTimeLeft) {
  if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "util-linux script not installed";
  const TempDir dir;
  const fs::path sweep = dir / "three.yaml";
  std::ofstream(sweep) << "sweep:\n  name: three\n  experiment: "
                       << jointsim::test::sourcePath("config/experiments/ur5_fall.yaml")
                       << "\n  set: {duration: 0.2}\nruns: [{name: a}, {name: b}, {name: c}]\n";
  const std::string batch =
      std::string(JOINTSIM_CLI_PATH) + " batch " + sweep.string() + " -j 1 -o " + (dir / "runs").string();
  const Result tty = jointsim::test::runCommand("script -qec '" + batch + "' /dev/null");
  ASSERT_EQ(tty.status, 0) << tty.out << tty.err;
  EXPECT_THAT(tty.out, HasSubstr("[batch three] 1/3 done (0 failed, 0 skipped)"));
  EXPECT_THAT(tty.out, HasSubstr(" left")) << tty.out;
  EXPECT_THAT(tty.out, HasSubstr("3/3 done"));
  // Not a terminal: no progress line (the runs are skipped as done, so this is quick).
  const Result pipe = run("batch " + sweep.string() + " -j 1 -o " + (dir / "runs").string());
  ASSERT_EQ(pipe.status, 0) << pipe.err;
  EXPECT_THAT(pipe.err, ::testing::Not(HasSubstr("[batch three]")));
}

}  // namespace

namespace {
// One column of a batch run's log.
Eigen::VectorXd logColumn(const fs::path& csv, const std::string& name) {
  const jointsim::io::CsvTable t = jointsim::io::readCsv(csv.string());
  const int c = t.find(name);
  EXPECT_GE(c, 0) << name << " in " << csv;
  return c >= 0 ? Eigen::VectorXd(t.data.col(c)) : Eigen::VectorXd();
}
}  // namespace

// Fault sweeps on the two whole-robot models whose drives are plain parameters (their axes' parameter tables):
// the IRB140 clamping experiment of [Olsson2017] and the MSL RobotR3 FullRobot. Each fault is checked against the
// physics it changes, not only against the nominal log:
// - IRB140 joint 2 (ElastoBacklash c = 8.2 N·m/rad, b = 0.01 rad): at the largest deflection δ (a turning point,
//   the damper idle) the spring torque is c·(|δ| − b/2); gear_stiffness_scale 0.5 halves that c,
//   backlash_add 0.1 rad keeps c with b = 0.11 rad; coulomb_friction_scale 2 doubles every friction table torque,
//   so the largest friction torque doubles (the table is linear in the speed, and the speeds stay alike).
// - RobotR3 axis 2 (op-amp motor, torque k·i): torque_constant_scale 0.5 needs twice the current for the same
//   torque along the same path; axis 1 (type 1, spring c): gear_stiffness_scale 0.5 needs (about) twice the spring
//   deflection for the same torque.
TEST(CliBatch, FaultSweepsOnTheIrb140ClampingAndTheRobotR3FullRobot) {
  const TempDir tmp;
  const fs::path& dir = tmp.path();
  std::ofstream(dir / "irb.yaml") << "sweep:\n  name: irb140_faults\n  experiment: "
                                  << jointsim::test::sourcePath("config/experiments/irb140_clamping.yaml")
                                  << "\n  set: {duration: 1.5, curves: false}\nruns:\n  - name: nominal\nfaults:\n"
                                     "  - {type: gear_stiffness_scale, joints: [joint2], values: [0.5]}\n"
                                     "  - {type: coulomb_friction_scale, joints: [joint2], values: [2.0]}\n"
                                     "  - {type: backlash_add, joints: [joint2], values: [0.1]}\n";
  std::ofstream(dir / "r3.yaml") << "sweep:\n  name: r3_faults\n  experiment: "
                                 << jointsim::test::sourcePath("config/experiments/robotr3_full_robot.yaml")
                                 << "\nruns:\n  - name: nominal\nfaults:\n"
                                    "  - {type: gear_stiffness_scale, joints: [r1], values: [0.5]}\n"
                                    "  - {type: torque_constant_scale, joints: [r2], values: [0.5]}\n";
  for (const char* sweep : {"irb", "r3"}) {
    const Result r =
        run("batch " + (dir / (std::string(sweep) + ".yaml")).string() + " -j 2 -o " + (dir / sweep).string());
    ASSERT_EQ(r.status, 0) << r.out << r.err;
  }
  EXPECT_EQ(manifest(dir / "irb" / "manifest.csv").size(), 4u);
  for (const auto& [name, status] : manifest(dir / "irb" / "manifest.csv")) EXPECT_EQ(status, "ok") << name;
  for (const auto& [name, status] : manifest(dir / "r3" / "manifest.csv")) EXPECT_EQ(status, "ok") << name;

  auto irb = [&](const std::string& run) { return dir / "irb" / run / "irb140_clamping.csv"; };
  // Spring torque over (|δ| − b/2) at the largest deflection [N·m/rad].
  auto stiffness = [&](const std::string& run, double b) {
    const Eigen::VectorXd tau = logColumn(irb(run), "joint2.spring_torque");
    const Eigen::VectorXd defl = logColumn(irb(run), "joint2.deflection");
    Eigen::Index k = 0;
    defl.cwiseAbs().maxCoeff(&k);
    return std::abs(tau[k]) / (std::abs(defl[k]) - b / 2);
  };
  EXPECT_NEAR(stiffness("nominal", 0.01), 8.2, 0.02 * 8.2);
  EXPECT_NEAR(stiffness("gear_stiffness_scale-joint2-0.5", 0.01), 4.1, 0.02 * 4.1);
  EXPECT_NEAR(stiffness("backlash_add-joint2-0.1", 0.11), 8.2, 0.02 * 8.2);
  EXPECT_GT(std::abs(stiffness("backlash_add-joint2-0.1", 0.01) - 8.2), 0.1 * 8.2) << "the backlash changed";
  const double friction = logColumn(irb("nominal"), "joint2.friction_torque").cwiseAbs().maxCoeff();
  const double doubled =
      logColumn(irb("coulomb_friction_scale-joint2-2"), "joint2.friction_torque").cwiseAbs().maxCoeff();
  EXPECT_NEAR(doubled / friction, 2.0, 0.03 * 2.0);

  auto r3 = [&](const std::string& run, const std::string& column) {
    return logColumn(dir / "r3" / run / "robotr3_full_robot.csv", column).cwiseAbs().maxCoeff();
  };
  EXPECT_NEAR(r3("torque_constant_scale-r2-0.5", "axis2.motor.La.i") / r3("nominal", "axis2.motor.La.i"), 2.0,
              0.03 * 2.0);
  const double deflection =
      r3("gear_stiffness_scale-r1-0.5", "axis1.gear.spring.phi_rel") / r3("nominal", "axis1.gear.spring.phi_rel");
  EXPECT_GT(deflection, 1.8);
  EXPECT_LT(deflection, 2.5);

  // A fault these models cannot take is refused with the reason, before anything runs.
  std::ofstream(dir / "bad.yaml") << "sweep:\n  name: bad\n  experiment: "
                                  << jointsim::test::sourcePath("config/experiments/irb140_clamping.yaml")
                                  << "\nfaults:\n  - {type: coulomb_friction_scale, joints: [joint2], values: [2.0], "
                                     "onset: 0.5}\n";
  const Result bad = run("batch " + (dir / "bad.yaml").string() + " -o " + (dir / "bad").string());
  EXPECT_NE(bad.status, 0);
  std::string logs;
  for (const auto& e : fs::directory_iterator(dir / "bad"))
    if (e.is_directory()) logs += slurp(e.path() / "run.log");
  EXPECT_THAT(logs, HasSubstr("clamping axis 'joint2' with a time law")) << bad.out << bad.err;
}
