// Hostile input at the command line: every reproducer of the hostile-input probe (names that would run code
// in gnuplot or leave the output folder, parser bombs, unbounded output grids and runs, messages that echo
// control bytes or megabytes, outputs that were not a transaction, signals) as the user met it. Each test
// states the defect it guards against.
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.hpp"

namespace fs = std::filesystem;
using jointsim::test::sourcePath;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

using Result = jointsim::test::CliResult;
using jointsim::test::TempDir;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Runs the CLI with `args` in the working directory `cwd` (its output captured outside `cwd`).
Result run(const std::string& args, const fs::path& cwd) {
  return jointsim::test::runCommand("cd " + jointsim::test::shellQuote(cwd.string()) + " && " + JOINTSIM_CLI_PATH +
                                    " " + args);
}

/// Files (not folders) below `dir`, relative, sorted.
std::vector<std::string> filesBelow(const fs::path& dir) {
  std::vector<std::string> out;
  // Without exceptions: a run under way renames and removes files while we look.
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) out.push_back(fs::relative(it->path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

/// The UR5 falling without actuation (as config/experiments/ur5_fall.yaml) with the experiment block
/// `experiment`, `duration` [s] and `log_rate` [Hz], and `extra` YAML appended.
std::string fallExperiment(const std::string& experiment, const std::string& extra = "",
                           const std::string& duration = "0.05", const std::string& log_rate = "500") {
  return "experiment: " + experiment + "\nrobot: " + sourcePath("config/robots/ur5.yaml") +
         "\ninitial_state: {q: [0, -1.2, 0.8, -0.5, 0.7, 0], qd: [0.3, 0, 0, 0, 0, 0]}\n"
         "duration: " +
         duration + "\nlog_rate: " + log_rate + "\nsolver: {method: adams, rtol: 1.0e-8, atol: 1.0e-10}\n" + extra;
}

/// The message of a bad input: one line on stderr.
void expectOneLine(const Result& r) {
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const char c : r.err.substr(0, r.err.size() - 1))
    EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << "control byte " << int(c) << " in " << r.err;
}

}  // namespace

// ---------------------------------------------------------------------------------------------- names

// Was: an experiment named "pw\nsystem(\"touch X\")\n#" ran, and `jointsim plot` then executed the system()
// call in gnuplot.
TEST(HostileNames, ExperimentNameThatWouldRunCodeIsRejected) {
  const TempDir tmp("codeexec");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: \"pw\\nsystem(\\\"touch X\\\")\\n#\", type: passive_robot}"));
  const Result r = run("run e.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("e.yaml:1: experiment.name"));
  expectOneLine(r);
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "X"));
}

// Was: an experiment named ".." wrote into the working directory; a sweep run named ".." deleted *.csv and
// summary.json in the parent of -o DIR and wrote its run there.
TEST(HostileNames, DotDotNamesNeverLeaveTheOutputFolder) {
  const TempDir tmp("dotdot");
  const fs::path& dir = tmp.path();
  write(dir / "keep.csv", "precious\n");
  write(dir / "summary.json", "{\"precious\": true}\n");
  write(dir / "e.yaml", fallExperiment("{name: .., type: passive_robot}"));
  Result r = run("run e.yaml -o sub/out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("experiment.name"));
  write(dir / "ok.yaml", fallExperiment("{name: fall, type: passive_robot}"));
  write(dir / "sweep.yaml", "sweep: {name: s, experiment: ok.yaml}\nruns: [{name: ..}]\n");
  r = run("batch sweep.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("sweep.yaml:2"));
  write(dir / "sweep2.yaml", "sweep: {name: .., experiment: ok.yaml}\nruns: [{name: a}]\n");
  r = run("batch sweep2.yaml", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(slurp(dir / "keep.csv"), "precious\n");
  EXPECT_EQ(slurp(dir / "summary.json"), "{\"precious\": true}\n");
  EXPECT_EQ(filesBelow(dir),
            (std::vector<std::string>{"e.yaml", "keep.csv", "ok.yaml", "summary.json", "sweep.yaml", "sweep2.yaml"}));
}

// Was: a hand-edited summary's "experiment" steered plot output outside the figures folder, and a name with
// newlines reached gnuplot as commands; a column name of the CSV could do the same through titles.
TEST(HostilePlot, SummaryAndColumnNamesCannotSteerOutputsOrRunCode) {
  const TempDir tmp("plot");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: fall, type: passive_robot}"));
  ASSERT_EQ(run("run e.yaml -o run", dir).status, 0);
  const std::string summary = slurp(dir / "run" / "summary.json");
  auto withExperiment = [&](const std::string& name) {
    std::string s = summary;
    const std::string key = "\"experiment\": \"fall\"";
    s.replace(s.find(key), key.size(), "\"experiment\": \"" + name + "\"");
    write(dir / "run" / "summary.json", s);
  };
  for (const std::string& name : {std::string("../../evil"), std::string("x\\nsystem('touch X')\\n#"),
                                  std::string("/tmp/evil")}) {  // tmp-path-ok: hostile input, never written
    withExperiment(name);
    const Result r = run("plot run", dir);
    EXPECT_EQ(r.status, 2) << name << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("summary.json: experiment"));
    expectOneLine(r);
  }
  // Titles from the CSV header: quotes, carriage returns, form feeds and gnuplot syntax stay text.
  write(dir / "run" / "summary.json", summary);
  std::string csv = slurp(dir / "run" / "fall.csv");
  const std::string col = "q_shoulder_pan_joint[rad]";
  csv.replace(csv.find(col), col.size(), "\"q_x');system('touch X');print('\rsystem(\"\"touch X\"\")\x0c[rad]\"");
  write(dir / "run" / "fall.csv", csv);
  const Result r = run("plot run", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "X"));
  EXPECT_FALSE(fs::exists(dir / "run" / "X"));
  for (const auto& f : filesBelow(dir)) EXPECT_TRUE(f.rfind("run/", 0) == 0 || f == "e.yaml") << "plot wrote " << f;
}

// ---------------------------------------------------------------------------------------------- parsers

// Was: a URDF of deeply nested elements overflowed the stack in the XML parser (segfault).
TEST(HostileParsers, DeeplyNestedUrdfIsAnInputError) {
  const TempDir tmp("urdf");
  const fs::path& dir = tmp.path();
  std::string xml = "<robot name='r'>";
  for (int i = 0; i < 200000; ++i) xml += "<a>";
  write(dir / "deep.urdf", xml);
  const Result r = run("dynamics --robot deep.urdf --q 0", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("deep.urdf:1: elements nested deeper than 100 levels"));
  expectOneLine(r);
  // A chain of more links than any robot has: an input error too (not a deep recursion).
  std::string chain = "<robot name='r'><link name='l0'/>";
  for (int i = 1; i <= 5000; ++i)
    chain += "<link name='l" + std::to_string(i) + "'/><joint name='j" + std::to_string(i) +
             "' type='revolute'><parent link='l" + std::to_string(i - 1) + "'/><child link='l" + std::to_string(i) +
             "'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>";
  write(dir / "chain.urdf", chain + "</robot>");
  const Result c = run("dynamics --robot chain.urdf --q 0", dir);
  EXPECT_EQ(c.status, 2) << c.err;
  EXPECT_THAT(c.err, HasSubstr("at most 1000 links"));
}

// Was: a deeply nested value in a summary.json overflowed the stack when plot copied the summary
// (segfault). The folder is a real run's, with a value a million levels deep put into its parameters.
TEST(HostileParsers, DeeplyNestedSummaryIsAnInputError) {
  const TempDir tmp("deepjson");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: fall, type: passive_robot}"));
  ASSERT_EQ(run("run e.yaml -o run", dir).status, 0);
  std::string summary = slurp(dir / "run" / "summary.json");
  const size_t at = summary.find("\"parameters\": {");
  ASSERT_NE(at, std::string::npos);
  summary.insert(at + 15, "\"deep\": " + std::string(1000000, '[') + std::string(1000000, ']') + ", ");
  write(dir / "run" / "summary.json", summary);
  const Result r = run("plot run -o figures", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("summary.json: JSON nested deeper than 64 levels"));
  expectOneLine(r);
  EXPECT_FALSE(fs::exists(dir / "figures"));
  // Still an input error, not a crash, when the whole file is one deep array.
  write(dir / "run" / "summary.json", std::string(1000000, '[') + std::string(1000000, ']'));
  EXPECT_EQ(run("plot run -o figures", dir).status, 2);
}

// Was: a 1.5 KB alias bomb in experiment.description expanded without bound while the summary was written
// (the CSV committed, no summary ever).
TEST(HostileParsers, AliasBombIsRejectedBeforeAnythingIsWritten) {
  const TempDir tmp("bomb");
  const fs::path& dir = tmp.path();
  std::string v = "&a0 \"lol\"";
  for (int i = 1; i < 10; ++i) {
    std::string next = "&a" + std::to_string(i) + " [" + v;
    for (int k = 0; k < 9; ++k) next += ", *a" + std::to_string(i - 1);
    v = next + "]";
  }
  write(dir / "e.yaml", fallExperiment("{name: bomb, type: passive_robot, description: " + v + "}"));
  const Result r = run("run e.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("expands to more than 200000 values"));
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// Was: a non-scalar YAML key ended in "internal error" with exit status 1 and no file named.
TEST(HostileParsers, NonScalarKeyIsAnInputErrorWithFileAndLine) {
  const TempDir tmp("key");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: k, type: passive_robot}", "? [a, b]\n: 1\n"));
  const Result r = run("run e.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("e.yaml:7"));
  EXPECT_THAT(r.err, HasSubstr("got a key that is a list"));
  expectOneLine(r);
}

// ---------------------------------------------------------------------------------------------- budgets

// Was: duration × log_rate overflowed a static_cast<long> (log_rate 1e300: "ok" with a one-row CSV;
// log_rate 1e12: 382 MB in 30 s with no bound).
TEST(HostileBudgets, OutputGridBeyondTheRowLimitIsAnInputError) {
  const TempDir tmp("rows");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: rows, type: passive_robot}"));
  for (const char* rate : {"1e300", "1e12", "3e8"}) {
    const Result r = run("run e.yaml -o out --set log_rate=" + std::string(rate), dir);
    EXPECT_EQ(r.status, 2) << rate << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("e.yaml: simulate: the output grid has"));
    EXPECT_THAT(r.err, HasSubstr("limits.log_rows"));
    EXPECT_FALSE(fs::exists(dir / "out")) << rate;
  }
  // The limit is the user's to raise or lower.
  write(dir / "small.yaml", fallExperiment("{name: rows, type: passive_robot}", "limits: {log_rows: 10}\n"));
  const Result r = run("run small.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("more than the limit of 10 rows"));
}

// Was: huge gains or initial speeds made CVODE crawl for minutes with no work or time limit.
TEST(HostileBudgets, RunsStopAtTheirStepOrWallTimeBudgetWithAFailedSummary) {
  const TempDir tmp("budget");
  const fs::path& dir = tmp.path();
  // A violent spin (1e4 rad/s) for a long time: far more steps than the budget allows.
  write(dir / "e.yaml",
        "experiment: {name: spin, type: passive_robot}\nrobot: " + sourcePath("config/robots/ur5.yaml") +
            "\ninitial_state: {q: [0, -1.2, 0.8, -0.5, 0.7, 0], qd: [1.0e4, 1.0e4, 1.0e4, 0, 0, 0]}\n"
            "duration: 1000\nlog_rate: 10\nlimits: {steps: 3000}\n"
            "solver: {method: adams, max_num_steps: 1000000000}\n");
  for (const std::string& extra : {std::string(), std::string(" --max-steps 0 --max-wall-time 0.5")}) {
    const auto t0 = std::chrono::steady_clock::now();
    const Result r = run("run e.yaml -o out" + extra, dir);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_LT(wall, 60.0);
    EXPECT_THAT(r.err,
                HasSubstr(extra.empty() ? "more than 3000 solver steps (limits.steps) at t = " : "limits.wall_time"));
    const std::string s = slurp(dir / "out" / "summary.json");
    EXPECT_THAT(s, HasSubstr("\"status\": \"failed\""));
    EXPECT_THAT(s, Not(HasSubstr("\"wall_time_s\": 0,")));
    EXPECT_THAT(s, Not(HasSubstr("\"steps\": 0,")));
    EXPECT_EQ(filesBelow(dir / "out"), std::vector<std::string>{"summary.json"});
  }
}

// ---------------------------------------------------------------------------------------------- messages
// Was (found by fuzz_sweep): a sweep whose experiment path has a component longer than a file name may be
// made std::filesystem throw from the library (ENAMETOOLONG): no file and no key in the message, and an
// exception that is not a jointsim error for a C++ caller. Now the key is named.
TEST(HostileMessages, OverlongPathComponentNamesTheKey) {
  const TempDir tmp("longname");
  const fs::path& dir = tmp.path();
  write(dir / "sweep.yaml", "sweep: {name: s, experiment: " + std::string(300, 'x') + ".yaml}\nruns: [{name: a}]\n");
  Result r = run("batch sweep.yaml -o out", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("sweep.yaml:1"));
  EXPECT_THAT(r.err, HasSubstr("no such file"));
  expectOneLine(r);
  r = run("plot " + std::string(300, 'y'), dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("no such run folder"));
  expectOneLine(r);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// Was: control bytes echoed across several lines; a 10 MB bad line echoed whole; an infinite trajectory, an
// over-long path ended in "internal error".
TEST(HostileMessages, OneLineEscapedCutAndNamingTheFile) {
  const TempDir tmp("messages");
  const fs::path& dir = tmp.path();
  write(dir / "ctl.yaml", fallExperiment("{name: m, type: passive_robot}", "", "0.05", "\"1\\e[31mred\\a\""));
  Result r = run("run ctl.yaml", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("ctl.yaml:"));
  EXPECT_THAT(r.err, HasSubstr("\\x1b[31mred\\x07"));
  expectOneLine(r);

  write(dir / "big.yaml", fallExperiment("{name: m, type: passive_robot}", "", "0.05", std::string(10000000, 'x')));
  r = run("run big.yaml", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_LT(r.err.size(), 2200u);
  EXPECT_THAT(r.err, HasSubstr("big.yaml:"));
  EXPECT_THAT(r.err, HasSubstr("bytes cut"));
  expectOneLine(r);

  write(dir / "traj.yaml",
        "experiment: {name: t, type: tracking}\nrobot: " + sourcePath("config/robots/ur5_drives.yaml") +
            "\ntrajectory:\n  type: point_to_point\n  start: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0]\n"
            "  segments:\n    - {target: [1.0e308, -1.2, 1.7, -2.07, -1.5708, 0.6], velocity: 1.0e-300, "
            "acceleration: 1.4}\n");
  r = run("run traj.yaml", dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("traj.yaml:4: trajectory: point_to_point segment 0"));
  expectOneLine(r);

  write(dir / "ok.yaml", fallExperiment("{name: m, type: passive_robot}"));
  const std::string long_name(5000, 'a');
  for (const std::string& args : {"run ok.yaml -o " + long_name, "plot " + long_name}) {
    r = run(args, dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr(args[0] == 'r' ? "File name too long" : "no such run folder"));
    EXPECT_THAT(r.err, Not(HasSubstr("internal error")));
    expectOneLine(r);
  }
}

// Was: Ceres dumped its own log ("WARNING: Logging before InitGoogleLogging()", "Covariance matrix is near
// rank deficient ...") before jointsim's message when a fit was not identifiable.
TEST(HostileMessages, UnidentifiableFitPrintsOnlyItsOwnMessage) {
  const TempDir tmp("ceres");
  const fs::path& dir = tmp.path();
  const Result r = run("identify clamping " + sourcePath("tests/golden/kr300_joint1_clamping.csv") +
                           " --fix-backlash 0.01 --fit-viscous --fit-damping -o fit.yaml",
                       dir);
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_THAT(r.err, ::testing::StartsWith("jointsim: cannot identify: clamping fit: the parameters"));
  expectOneLine(r);
  EXPECT_FALSE(fs::exists(dir / "fit.yaml"));
}

// ---------------------------------------------------------------------------------------------- outputs

// Was: a failed run into the folder of an earlier good run left the old CSV beside a "failed" summary (and
// plot drew it, exit 0).
TEST(HostileOutputs, FailedRunLeavesOnlyItsFailedSummary) {
  const TempDir tmp("stale");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: fall, type: passive_robot}"));
  ASSERT_EQ(run("run e.yaml -o out", dir).status, 0);
  ASSERT_TRUE(fs::exists(dir / "out" / "fall.csv"));
  write(dir / "out" / "fall.csv.tmp.12345", "left by a killed run\n");
  const Result r = run("run e.yaml -o out --max-steps 5", dir);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(filesBelow(dir / "out"), std::vector<std::string>{"summary.json"});
  EXPECT_THAT(slurp(dir / "out" / "summary.json"), HasSubstr("\"status\": \"failed\""));
  const Result p = run("plot out", dir);
  EXPECT_EQ(p.status, 2) << p.err;
  EXPECT_THAT(p.err, HasSubstr("the run failed"));
}

// Was (found by fuzz_experiment): a description with bytes that are not UTF-8 made the summary's JSON writer
// throw after the CSV was written: "internal error", exit 1, no summary.
TEST(HostileOutputs, DescriptionThatIsNotUtf8IsWrittenWithReplacementCharacters) {
  const TempDir tmp("utf8");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: fall, type: passive_robot, description: \"bad \xff\xfe bytes\"}"));
  const Result r = run("run e.yaml -o out", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  const std::string s = slurp(dir / "out" / "summary.json");
  EXPECT_THAT(s, HasSubstr("\"status\": \"ok\""));
  EXPECT_THAT(s, HasSubstr("bad \xEF\xBF\xBD\xEF\xBF\xBD bytes"));  // U+FFFD per bad byte
  EXPECT_EQ(filesBelow(dir / "out"), (std::vector<std::string>{"fall.csv", "summary.json"}));
}

// Was: clamping curves were written after an "ok" summary; a joint named "j6/x" made the run exit 1 with an
// "ok" summary and 5 of 6 curves.
TEST(HostileOutputs, ClampingCurveOfAJointWithASlashInItsName) {
  const TempDir tmp("slash");
  const fs::path& dir = tmp.path();
  std::string robot = slurp(sourcePath("config/robots/irb140.yaml"));
  std::string experiment = slurp(sourcePath("config/experiments/irb140_clamping.yaml"));
  for (std::string* s : {&robot, &experiment})
    for (size_t at; (at = s->find("joint6")) != std::string::npos;) s->replace(at, 6, "j6/x");
  experiment.replace(experiment.find("../robots/irb140.yaml"), 21, "irb.yaml");
  write(dir / "irb.yaml", robot);
  write(dir / "e.yaml", experiment);
  const Result r = run("run e.yaml -o out --set duration=0.3", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  const auto files = filesBelow(dir / "out");
  EXPECT_EQ(files.size(), 8u);
  EXPECT_TRUE(std::count(files.begin(), files.end(), "irb140_clamping_j6_x_curve.csv"))
      << ::testing::PrintToString(files);
  EXPECT_THAT(slurp(dir / "out" / "summary.json"), HasSubstr("irb140_clamping_j6_x_curve.csv"));
}

// ---------------------------------------------------------------------------------------------- signals

namespace {

/// Starts the CLI with `args` in `cwd` (output to files there) and returns its pid.
pid_t start(const std::vector<std::string>& args, const fs::path& cwd) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(cwd.c_str()) != 0) _exit(127);
    if (!std::freopen(".cli.out", "w", stdout) || !std::freopen(".cli.err", "w", stderr)) _exit(127);
    std::vector<char*> argv{const_cast<char*>(JOINTSIM_CLI_PATH)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(JOINTSIM_CLI_PATH, argv.data());
    _exit(127);
  }
  return pid;
}

int waitExit(pid_t pid) {
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/// Waits until `ready` holds (or 120 s pass).
template <class F>
bool waitFor(F ready) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!ready()) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(120)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

bool hasTemporary(const fs::path& dir) {
  for (const auto& f : filesBelow(dir))
    if (f.find(".tmp.") != std::string::npos) return true;
  return false;
}

}  // namespace

// Was: SIGINT/SIGTERM left a 6 MB *.csv.tmp.<pid> and no summary.
TEST(HostileSignals, InterruptedRunLeavesAnInterruptedSummaryAndNoTemporaryFile) {
  const TempDir tmp("signal");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: long, type: passive_robot}", "", "10000"));
  for (const auto& [sig, code] : std::vector<std::pair<int, int>>{{SIGINT, 130}, {SIGTERM, 143}}) {
    const pid_t pid = start({"run", "e.yaml", "-o", "out"}, dir);
    ASSERT_TRUE(waitFor([&] { return hasTemporary(dir / "out"); })) << "the run never started writing";
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ::kill(pid, sig);
    EXPECT_EQ(waitExit(pid), code) << slurp(dir / ".cli.err");
    EXPECT_THAT(slurp(dir / ".cli.err"), HasSubstr("interrupted"));
    EXPECT_EQ(filesBelow(dir / "out"), std::vector<std::string>{"summary.json"});
    const std::string s = slurp(dir / "out" / "summary.json");
    EXPECT_THAT(s, HasSubstr("\"status\": \"interrupted\""));
    EXPECT_THAT(s, Not(HasSubstr("\"sim_time_s\": 0,")));
  }
}

// An interrupted batch stops launching runs, leaves no temporary file, and its resume gives results
// byte-identical to an uninterrupted batch.
TEST(HostileSignals, InterruptedBatchResumesToIdenticalResults) {
  const TempDir tmp("batchsignal");
  const fs::path& dir = tmp.path();
  write(dir / "e.yaml", fallExperiment("{name: fall, type: passive_robot}", "", "30", "200"));
  std::string sweep = "sweep: {name: s, experiment: e.yaml}\nruns:\n  - name: a\n";
  for (const auto& [name, qd] : {std::pair{"b", "0.5"}, {"c", "0.7"}, {"d", "0.9"}})
    sweep += "  - name: " + std::string(name) + "\n    set:\n      \"initial_state.qd[0]\": " + qd + "\n";
  write(dir / "sweep.yaml", sweep);
  auto okRuns = [&](const fs::path& out) {
    int n = 0;
    for (const char* r : {"a", "b", "c", "d"})
      n += slurp(out / r / "summary.json").find("\"status\": \"ok\"") != std::string::npos;
    return n;
  };
  const pid_t pid = start({"batch", "sweep.yaml", "-j", "1", "-o", "interrupted"}, dir);
  // Interrupt while a run is under way (after the first has finished), so one run ends "interrupted".
  ASSERT_TRUE(waitFor([&] {
    if (okRuns(dir / "interrupted") < 1) return false;
    for (const char* r : {"b", "c", "d"})
      if (hasTemporary(dir / "interrupted" / r)) return true;
    return false;
  }));
  ::kill(pid, SIGINT);
  EXPECT_EQ(waitExit(pid), 130) << slurp(dir / ".cli.err");
  const int done = okRuns(dir / "interrupted");
  ASSERT_LT(done, 4) << "the batch finished before it could be interrupted";
  EXPECT_FALSE(hasTemporary(dir / "interrupted"));
  EXPECT_THAT(slurp(dir / "interrupted" / "manifest.csv"), HasSubstr(",interrupted,"));

  const Result resumed = run("batch sweep.yaml -j 1 -o interrupted", dir);
  EXPECT_EQ(resumed.status, 0) << resumed.err;
  EXPECT_THAT(resumed.out, HasSubstr(std::to_string(done) + " skipped"));
  const Result whole = run("batch sweep.yaml -j 2 -o whole", dir);
  EXPECT_EQ(whole.status, 0) << whole.err;
  for (const char* r : {"a", "b", "c", "d"}) {
    const std::string a = slurp(dir / "interrupted" / r / "fall.csv"), b = slurp(dir / "whole" / r / "fall.csv");
    EXPECT_GT(a.size(), 100000u) << r;
    EXPECT_TRUE(a == b) << "run " << r << " differs after the resume";
  }
  EXPECT_FALSE(hasTemporary(dir / "interrupted"));
}

// ---------------------------------------------------------------------------------------------- joint limits

// Was: joint limits were informative only — a torque-free swing of the UR5 took the elbow far past its ±π
// limit without a word. Now the default (warn) reports it, and `stop` holds the joints at their end stops.
TEST(HostileJointLimits, SwingPastTheElbowLimitIsReportedOrStopped) {
  const TempDir tmp("limits");
  const fs::path& dir = tmp.path();
  write(dir / "swing.yaml",
        "experiment: {name: swing, type: passive_robot}\nrobot: " + sourcePath("config/robots/ur5.urdf") +
            "\ninitial_state: {q: [0, -1.5708, 0.3, 0, 0, 0]}\njoint_limits: warn\n"
            "duration: 3\nlog_rate: 500\nsolver: {method: bdf, rtol: 1.0e-8, atol: 1.0e-10}\n");
  auto elbowRange = [&](const fs::path& csv) {
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    double lo = 0, hi = 0;
    while (std::getline(in, line)) {
      std::stringstream ss(line);
      std::string cell;
      for (int c = 0; c <= 3 && std::getline(ss, cell, ','); ++c)
        if (c == 3) lo = std::min(lo, std::stod(cell)), hi = std::max(hi, std::stod(cell));
    }
    return std::pair{lo, hi};
  };
  Result r = run("run swing.yaml -o warn", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("warning: joint elbow_joint left its range [-3.1416, 3.1416] rad at t = 0.514 s"));
  const auto [lo, hi] = elbowRange(dir / "warn" / "swing.csv");
  EXPECT_LT(lo, -8.5);  // the swing of the probe
  std::string s = slurp(dir / "warn" / "summary.json");
  EXPECT_THAT(s, HasSubstr("\"mode\": \"warn\""));
  EXPECT_THAT(s, HasSubstr("\"joint\": \"elbow_joint\""));

  r = run("run swing.yaml -o stop --set joint_limits=stop", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, Not(HasSubstr("warning")));
  const auto [lo_stop, hi_stop] = elbowRange(dir / "stop" / "swing.csv");
  EXPECT_GT(lo_stop, -M_PI - 0.05);
  EXPECT_LT(hi_stop, M_PI + 0.05);
  EXPECT_GT(hi_stop, M_PI) << "the elbow reaches its stop";
  s = slurp(dir / "stop" / "summary.json");
  EXPECT_THAT(s, HasSubstr("\"mode\": \"stop\""));
  EXPECT_THAT(slurp(dir / "stop" / "swing.csv").substr(0, 2000), HasSubstr("end_stop_torque_elbow_joint[N·m]"));

  r = run("run swing.yaml -o ignore --set joint_limits=ignore", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, Not(HasSubstr("warning")));
  EXPECT_THAT(slurp(dir / "ignore" / "summary.json"), Not(HasSubstr("\"violations\"")));
  EXPECT_EQ(slurp(dir / "ignore" / "swing.csv"), slurp(dir / "warn" / "swing.csv")) << "warn only watches";

  write(dir / "bad.yaml",
        "experiment: {name: swing, type: passive_robot}\nrobot: " + sourcePath("config/robots/ur5.urdf") +
            "\njoint_limits: {mode: stop, damping: -1}\nduration: 1\n");
  r = run("run bad.yaml", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("bad.yaml:3: joint_limits.damping: expected a finite damping >= 0 N·m·s/rad"));
}
