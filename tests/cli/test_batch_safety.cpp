// `jointsim batch`, `validate` and `--dataset` under hostile conditions (issue 26): a full disk, a data set aimed at
// a run's log, two batches into one folder, deleted logs on resume, manifest fields that need CSV quoting, temporary
// files left by a killed process, inputs that would take unbounded memory or time, and signals outside run loops.
// Each case ends with a clear error (exit status, the cause in one line, nothing half-written) or correct results.
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/experiments/batch.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using jointsim::test::runCli;
using jointsim::test::runCommand;
using jointsim::test::shellQuote;
using jointsim::test::TempDir;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kCli = JOINTSIM_CLI_PATH;

// "ulimit -v 1000000; " (1 GB of address space for the command), except under AddressSanitizer, whose shadow memory
// reserves terabytes of address space (the CLI could not start); there the bound is the test's time limit.
#if defined(__SANITIZE_ADDRESS__)
const std::string kMemoryLimit;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
const std::string kMemoryLimit;
#else
const std::string kMemoryLimit = "ulimit -v 1000000; ";
#endif
#else
const std::string kMemoryLimit = "ulimit -v 1000000; ";
#endif

// A sweep of two short runs of the MSL backlash experiment (each about 0.4 MB of log), `extra` appended.
fs::path writeSweep(const fs::path& dir, const std::string& runs = "runs: [{name: a}, {name: b}]\n") {
  const fs::path p = dir / "sweep.yaml";
  std::ofstream(p) << "sweep:\n  name: s\n  experiment: "
                   << jointsim::test::sourcePath("config/experiments/msl_backlash.yaml") << "\n"
                   << runs;
  return p;
}

// An RFC 4180 parser (independent of the writer): records of fields.
std::vector<std::vector<std::string>> parseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> records;
  std::vector<std::string> record;
  std::string field;
  bool quoted = false, any = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
      any = true;
    } else if (c == ',') {
      record.push_back(field);
      field.clear();
    } else if (c == '\n') {
      record.push_back(field);
      records.push_back(record);
      record.clear();
      field.clear();
      any = false;
    } else {
      field += c;
      any = true;
    }
  }
  EXPECT_FALSE(quoted) << "an unterminated quoted field";
  if (any || !record.empty()) ADD_FAILURE() << "the last record has no line end";
  return records;
}

int countTemporaries(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    n += e.path().filename().string().find(".tmp.") != std::string::npos;
  return n;
}

}  // namespace

// A full disk while the data set is written (simulated by a file-size limit, with SIGXFSZ ignored as a shell may
// have it): the system's reason, exit 1, neither the data set nor its temporary file left. It used to end in
// SIGSEGV (HDF5 closing the failed file at exit).
TEST(BatchSafety, ADataSetOnAFullDiskFailsWithTheReasonAndLeavesNothing) {
  const TempDir tmp("fulldisk");
  const fs::path sweep = writeSweep(tmp.path()), out = tmp.path() / "out", set = tmp.path() / "set.h5";
  ASSERT_EQ(runCli("batch " + sweep.string() + " -o " + out.string()).status, 0);
  const auto r = runCommand("trap '' XFSZ; ulimit -f 40; exec " + kCli + " batch " + sweep.string() + " -o " +
                            out.string() + " --collect --dataset " + set.string());
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("data set " + set.string()));
  EXPECT_THAT(r.err, HasSubstr("File too large"));  // EFBIG: the limit's errno (a full disk gives ENOSPC)
  EXPECT_FALSE(fs::exists(set));
  EXPECT_EQ(countTemporaries(tmp.path()), 0);
  // Without the limit, the same command writes it.
  const auto ok = runCli("batch " + sweep.string() + " -o " + out.string() + " --collect --dataset " + set.string());
  EXPECT_EQ(ok.status, 0) << ok.err;
  EXPECT_EQ(slurp(set).substr(0, 4), "\x89HDF");
}

// The manifest and a run's summary on a full disk: the reason, not a silently cut file.
TEST(BatchSafety, AManifestOnAFullDiskIsReportedWithTheReason) {
  const TempDir tmp("fullmanifest");
  std::string runs = "runs:\n";
  for (int i = 0; i < 400; ++i)  // a manifest of about 60 KB
    runs += "  - {name: r" + std::to_string(i) + ", set: {experiment.description: " + std::string(100, 'x') + "}}\n";
  const fs::path sweep = writeSweep(tmp.path(), runs), out = tmp.path() / "out";
  const auto r = runCommand("trap '' XFSZ; ulimit -f 20; exec " + kCli + " batch " + sweep.string() + " -o " +
                            out.string() + " --collect");
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("manifest.csv: writing failed: File too large"));
  EXPECT_FALSE(fs::exists(out / "manifest.csv"));
  EXPECT_EQ(countTemporaries(out), 0);
}

// --dataset aimed at a run's own log, at a file that is not a data set, into a folder where nothing can be created,
// or with a name that leaves no room for the temporary name: refused before any run, exit 2.
TEST(BatchSafety, ADataSetPathThatCannotWorkIsRefusedBeforeAnyRun) {
  const TempDir tmp("datasetpath");
  const fs::path sweep = writeSweep(tmp.path()), out = tmp.path() / "out";
  ASSERT_EQ(runCli("batch " + sweep.string() + " -o " + out.string()).status, 0);
  const fs::path log = out / "a" / "msl_backlash.csv";
  const std::string before = slurp(log);
  ASSERT_FALSE(before.empty());
  auto r = runCli("batch " + sweep.string() + " -o " + out.string() + " --dataset " + log.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("is not an HDF5 file; refusing to replace it"));
  EXPECT_EQ(slurp(log), before);
  r = runCli("batch " + sweep.string() + " -o " + out.string() + " --dataset " + (out / "a" / "set.h5").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("inside the folder of run 'a'"));
  // 251 bytes: the name fits the 255-byte limit, NAME.tmp.PID does not; no run is started (fresh output folder).
  const fs::path fresh = tmp.path() / "fresh";
  r = runCli("batch " + sweep.string() + " -o " + fresh.string() + " --dataset " +
             (tmp.path() / (std::string(248, 'd') + ".h5")).string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("a file name of 251 bytes is too long"));
  EXPECT_FALSE(fs::exists(fresh));
  // A folder that is a file's name.
  r = runCli("batch " + sweep.string() + " -o " + fresh.string() + " --dataset " + (log / "set.h5").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(fresh));
  // Nowhere to create a file: /proc is read-only for everyone (root included).
  if (fs::is_directory("/proc/self")) {
    r = runCli("batch " + sweep.string() + " -o " + fresh.string() + " --dataset /proc/self/set.h5");
    EXPECT_EQ(r.status, 2);
    EXPECT_THAT(r.err, HasSubstr("cannot create a file in folder '/proc/self'"));
    EXPECT_FALSE(fs::exists(fresh));
  }
}

// Two batches into one folder: the second is refused at once (exit 2, the reason and what to do) while the first
// finishes with all its runs ok and a manifest that agrees with its data set. They used to delete each other's files.
TEST(BatchSafety, ASecondBatchIntoTheSameFolderIsRefusedAndTheFirstFinishes) {
  const TempDir tmp("twobatches");
  const fs::path dir = tmp.path(), out = dir / "out";
  std::ofstream(dir / "slow.yaml") << "sweep:\n  name: slow\n  experiment: "
                                   << jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml")
                                   << "\n  set: {duration: 1.0, log_rate: 50}\nruns: [{name: a}, {name: b}]\n";
  const std::string first = kCli + " batch " + (dir / "slow.yaml").string() + " -o " + out.string() + " --dataset " +
                            (dir / "set.h5").string() + " >" + shellQuote((dir / "first.out").string()) + " 2>&1";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", first.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // The first holds the lock once its manifest exists.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!fs::exists(out / "manifest.csv") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const auto second = runCli("batch " + (dir / "slow.yaml").string() + " -o " + out.string());
  const auto collect = runCli("batch " + (dir / "slow.yaml").string() + " -o " + out.string() + " --collect");
  const auto shard = runCli("batch " + (dir / "slow.yaml").string() + " -o " + out.string() + " --shard 1/2");
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir / "first.out");
  for (const auto* r : {&second, &collect, &shard}) {
    EXPECT_EQ(r->status, 2) << r->out << r->err;
    EXPECT_THAT(r->err, HasSubstr("another jointsim batch is writing into this folder"));
  }
  EXPECT_THAT(slurp(dir / "first.out"), HasSubstr("2 ok"));
  const auto rows = parseCsv(slurp(out / "manifest.csv"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1][1], "ok");
  EXPECT_EQ(rows[2][1], "ok");
  EXPECT_EQ(countTemporaries(dir), 0);
  // Once it has ended, the folder is free again: everything is already done.
  const auto again = runCli("batch " + (dir / "slow.yaml").string() + " -o " + out.string());
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_THAT(again.out, HasSubstr("2 skipped"));
}

// Resume reuses a run only while its outputs are there as written: a deleted or emptied log runs it again (it used
// to count as done, and the data set then held the run without data). Temporary files of a killed process are
// removed.
TEST(BatchSafety, ResumeRunsAgainARunWhoseLogWasDeletedOrEmptied) {
  const TempDir tmp("resumelogs");
  const fs::path sweep = writeSweep(tmp.path(), "runs: [{name: a}, {name: b}, {name: c}]\n"), out = tmp.path() / "out";
  ASSERT_EQ(runCli("batch " + sweep.string() + " -o " + out.string()).status, 0);
  const std::string log_c = slurp(out / "c" / "msl_backlash.csv");
  fs::remove(out / "a" / "msl_backlash.csv");
  std::ofstream(out / "b" / "msl_backlash.csv", std::ios::trunc);
  std::ofstream(out / "manifest.csv.tmp.999999") << "left by a kill -9";
  std::ofstream(out / "c" / "msl_backlash.csv.tmp.999999") << "left by a kill -9";
  const auto r =
      runCli("batch " + sweep.string() + " -o " + out.string() + " --dataset " + (tmp.path() / "set.h5").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 ok"));
  EXPECT_THAT(r.out, HasSubstr("1 skipped"));
  EXPECT_THAT(r.out, HasSubstr("3 with logs"));
  EXPECT_EQ(slurp(out / "a" / "msl_backlash.csv"), log_c);  // the same experiment: the same log
  EXPECT_EQ(slurp(out / "b" / "msl_backlash.csv"), log_c);
  EXPECT_EQ(countTemporaries(out), 0);
}

// Manifest fields are RFC 4180 CSV: a fault joint with a comma and a line break (a run in error) keeps every record
// at 17 fields. It used to give records of 14 and 5 fields under the 17-field header.
TEST(BatchSafety, ManifestFieldsAreQuotedAsCsv) {
  const TempDir tmp("quoting");
  const fs::path dir = tmp.path(), out = dir / "out";
  std::ofstream(dir / "q.yaml") << "sweep:\n  name: q\n  experiment: "
                                << jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml")
                                << "\n  set: {duration: 0.01}\nruns:\n  - {name: nominal}\n"
                                   "  - name: odd\n    set: {experiment.description: \"a \\\"quoted\\\",\\nvalue\"}\n"
                                   "    faults: [{type: sensor_bias, joint: \"a,b\\nc\", value: 0.1}]\n";
  const auto r = runCli("batch " + (dir / "q.yaml").string() + " -o " + out.string());
  EXPECT_EQ(r.status, 1) << r.err;  // the odd run is in error (no such joint)
  const auto rows = parseCsv(slurp(out / "manifest.csv"));
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) EXPECT_EQ(row.size(), 17u);
  EXPECT_EQ(rows[2][0], "odd");
  EXPECT_EQ(rows[2][1], "error");
  EXPECT_EQ(rows[2][12], "a,b\nc");  // fault_joint
  EXPECT_THAT(rows[2][6], HasSubstr("experiment.description=a \"quoted\",\nvalue"));
}

// Inputs that would take unbounded memory: an intermittent fault with a 1e-9 s period over a 10 s run (10^10
// episodes) is refused by validate and by batch's run, within a 1 GB address-space limit and in seconds.
TEST(BatchSafety, AnIntermittentFaultWithATinyPeriodIsRefusedWithinBoundedMemory) {
  const TempDir tmp("dropout");
  const fs::path dir = tmp.path();
  std::ofstream(dir / "d.yaml") << "sweep:\n  name: d\n  experiment: "
                                << jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml")
                                << "\nruns:\n  - name: tiny\n    faults: [{type: sensor_dropout, joint: elbow_joint, "
                                   "value: 1e-10, period: 1e-9}]\n";
  const auto t0 = std::chrono::steady_clock::now();
  auto r = runCommand(kMemoryLimit + "exec " + kCli + " validate " + (dir / "d.yaml").string());
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("time events"));
  EXPECT_THAT(r.err, HasSubstr("run 'tiny'"));
  r = runCommand(kMemoryLimit + "exec " + kCli + " batch " + (dir / "d.yaml").string() + " -o " +
                 (dir / "out").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(slurp(dir / "out" / "tiny" / "run.log"), HasSubstr("time events"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 60.0);
}

// validate makes the checks run makes: a log grid beyond limits.log_rows is refused by both (validate passed it).
TEST(BatchSafety, ValidateRefusesWhatRunRefuses) {
  const std::string exp = jointsim::test::sourcePath("config/experiments/ur5_fall.yaml");
  const auto v = runCli("validate " + exp + " --set log_rate=1e7 --set duration=2");
  EXPECT_EQ(v.status, 2) << v.out;
  EXPECT_THAT(v.err, HasSubstr("limits.log_rows"));
  const TempDir tmp("validaterun");
  const auto r = runCli("run " + exp + " --set log_rate=1e7 --set duration=2 -o " + tmp.path().string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("limits.log_rows"));
}

// SIGINT during validate of a large sweep: it stops at once with exit 130 (it used to ignore SIGINT for minutes).
TEST(BatchSafety, ValidateOfALargeSweepStopsOnSigint) {
  const TempDir tmp("validatesigint");
  const fs::path dir = tmp.path();
  std::ofstream(dir / "big.yaml") << "sweep:\n  name: big\n  experiment: "
                                  << jointsim::test::sourcePath("config/experiments/ur5_fall.yaml")
                                  << "\nsample:\n  design: monte_carlo\n  runs: 100000\n  seed: 1\n  parameters:\n"
                                     "    duration: {distribution: uniform, low: 0.1, high: 0.2}\n";
  const auto t0 = std::chrono::steady_clock::now();
  const auto r =
      runCommand("exec timeout --preserve-status -s INT 2 " + kCli + " validate " + (dir / "big.yaml").string());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.status, 130) << r.err;
  EXPECT_THAT(r.err, HasSubstr("validate interrupted"));
  EXPECT_LT(wall, 20.0);
}

// Absurd but well-formed current-loop gains (P_cur = 1e12 V/A, I_cur = 1e20 V/(A·s)) are refused when the drives file
// is read, naming the drive, the gains and the limit (a run used to crawl for 26–40 s before failing at t = 0.3 ms
// without naming anything); gains just inside the limit run.
TEST(BatchSafety, AbsurdCurrentLoopGainsAreRefusedWhenTheFileIsRead) {
  const TempDir tmp("gains");
  const std::string original = slurp(jointsim::test::sourcePath("config/robots/ur5_drives.yaml"));
  const std::string nominal = "P_cur: 10, I_cur: 10000";
  ASSERT_NE(original.find(nominal), std::string::npos);
  ASSERT_NE(original.find("multibody: ur5.yaml"), std::string::npos);
  auto withGains = [&](const std::string& gains) {
    std::string text = original;
    text.replace(text.find(nominal), nominal.size(), gains);
    text.replace(text.find("multibody: ur5.yaml"), std::string("multibody: ur5.yaml").size(),
                 "multibody: " + jointsim::test::sourcePath("config/robots/ur5.yaml"));
    const fs::path p = tmp.path() / "drives.yaml";
    std::ofstream(p) << text;
    return p;
  };
  const std::string exp = jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml");
  for (const std::string gains : {"P_cur: 1e12, I_cur: 10000", "P_cur: 10, I_cur: 1e20"}) {
    SCOPED_TRACE(gains);
    const fs::path robot = withGains(gains);
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = runCli("validate " + exp + " --set robot=" + robot.string());
    EXPECT_EQ(r.status, 2) << r.out << r.err;
    EXPECT_THAT(r.err, HasSubstr("drive of joint 'shoulder_pan_joint'.controller: P_cur = "));
    EXPECT_THAT(r.err, HasSubstr("beyond 100000000 rad/s"));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
  }
  const fs::path robot = withGains("P_cur: 10, I_cur: 5e12");  // poles 7.8e7 rad/s: inside the limit
  const auto r = runCli("run " + exp + " --set robot=" + robot.string() + " --set duration=0.2 -o " +
                        (tmp.path() / "out").string());
  EXPECT_EQ(r.status, 0) << r.err;
}

// A sweep file of a few hundred bytes cannot ask for unbounded work: runs and override strings are counted before any
// is made (100,000 runs x 500 sampled parameters took 4.4 GB and 21 s before its first error), within 1 GB.
TEST(BatchSafety, HugeSweepsAreRefusedBeforeTheyAreBuilt) {
  const TempDir tmp("hugesweeps");
  const std::string head =
      "sweep:\n  name: h\n  experiment: " + jointsim::test::sourcePath("config/experiments/ur5_fall.yaml") + "\n";
  std::string params;
  for (int i = 0; i < 500; ++i) params += "    p" + std::to_string(i) + ": {distribution: uniform, low: 0, high: 1}\n";
  std::string axes;
  for (int i = 0; i < 8; ++i) axes += "  a" + std::to_string(i) + ": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\n";
  std::string common = "  set: {";
  for (int i = 0; i < 100; ++i) common += std::string(i ? ", " : "") + "k" + std::to_string(i) + ": 1";
  common += "}\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "sample:\n  design: monte_carlo\n  runs: 100000\n  seed: 1\n  parameters:\n" + params,
       "overrides in all"},
      {head + "grid:\n" + axes, "the sweep would have 1e+08 runs"},
      {head + common + "sample:\n  design: latin_hypercube\n  runs: 50000\n  seed: 1\n  parameters:\n" +
           "    duration: {distribution: uniform, low: 0.1, high: 0.2}\n",
       "overrides in all (runs x overrides per run, the common `set` included)"},
      {head + "faults:\n  - {type: sensor_bias, joints: [" +
           [] {
             std::string j;
             for (int i = 0; i < 400; ++i) j += std::string(i ? ", " : "") + "j" + std::to_string(i);
             return j;
           }() +
           "], values: [" +
           [] {
             std::string v;
             for (int i = 0; i < 400; ++i) v += std::string(i ? ", " : "") + std::to_string(i + 1) + "e-3";
             return v;
           }() +
           "]}\n",
       "the sweep would have 160000 runs"},
  };
  for (const auto& [text, expected] : cases) {
    SCOPED_TRACE(expected);
    std::ofstream(tmp.path() / "huge.yaml") << text;
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = runCommand(kMemoryLimit + "exec " + kCli + " validate " + (tmp.path() / "huge.yaml").string());
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr(expected));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
  }
}

// validate checks the runs most likely to fail first (the extremes of each sampled value): in a 100,000-run sweep
// whose few bad runs lie anywhere, the error comes in seconds, not after minutes of loading good runs.
TEST(BatchSafety, ValidateFindsTheBadRunOfALargeSweepFirst) {
  const TempDir tmp("validateorder");
  std::ofstream(tmp.path() / "big.yaml") << "sweep:\n  name: big\n  experiment: "
                                         << jointsim::test::sourcePath("config/experiments/ur5_fall.yaml")
                                         << "\nsample:\n  design: monte_carlo\n  runs: 100000\n  seed: 7\n"
                                            "  parameters:\n    duration: {distribution: normal, mean: 1, std: 0.25}\n";
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = runCli("validate " + (tmp.path() / "big.yaml").string());
  EXPECT_EQ(r.status, 2) << r.err;  // about 3 in 100,000 durations fall below 0
  EXPECT_THAT(r.err, HasSubstr("duration"));
  EXPECT_THAT(r.err, HasSubstr("(from the override --set duration=-"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
}

// An error in a value an override set names the override, not a line of the file that no longer holds it.
TEST(BatchSafety, AnOverrideErrorNamesTheOverride) {
  const std::string exp = jointsim::test::sourcePath("config/experiments/ur5_fall.yaml");
  for (const auto& [set, expected] : std::vector<std::pair<std::string, std::string>>{
           {"+a.b=1", "ur5_fall.yaml: a: unknown key 'a'"},
           {"duration=abc", "ur5_fall.yaml: duration: expected a time in s, got 'abc'"}}) {
    const auto r = runCli("validate " + exp + " --set " + set);
    EXPECT_EQ(r.status, 2);
    EXPECT_THAT(r.err, HasSubstr(expected));
    EXPECT_THAT(r.err, HasSubstr("(from the override --set " + set + ")"));
  }
}

// The resume stamp is unambiguous: an override whose value reads "x; log_rate=50" is not the same settings as a
// real log_rate: 50 (joined by "; ", the two stamps were equal and the stale result was reused).
TEST(BatchSafety, TheResumeStampCannotBeForgedByAValue) {
  const TempDir tmp("stamp");
  const fs::path dir = tmp.path(), out = dir / "out";
  auto sweep = [&](const std::string& set) {
    std::ofstream(dir / "s.yaml") << "sweep:\n  name: s\n  experiment: "
                                  << jointsim::test::sourcePath("config/experiments/ur5_fall.yaml")
                                  << "\n  set: {duration: 0.1}\nruns:\n  - {name: a, set: " << set << "}\n";
    return runCli("batch " + (dir / "s.yaml").string() + " -o " + out.string());
  };
  auto r = sweep("{experiment.description: \"x; log_rate=50\"}");
  ASSERT_EQ(r.status, 0) << r.err;
  r = sweep("{experiment.description: x, log_rate: 50}");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("1 ok, 0 failed or in error, 0 skipped"));
  EXPECT_THAT(slurp(out / "a" / "summary.json"), HasSubstr("\"log_rate\": 50"));
}

// Two `jointsim run` into one folder at once: the second is refused (exit 2) instead of removing the first one's
// outputs, and the first completes.
TEST(BatchSafety, ASecondRunIntoTheSameFolderIsRefused) {
  const TempDir tmp("tworuns");
  const fs::path out = tmp.path() / "out";
  const std::string exp = jointsim::test::sourcePath("config/experiments/ur5_excitation.yaml");
  const std::string first = kCli + " run " + exp + " --set duration=10 -o " + out.string() + " >" +
                            shellQuote((tmp.path() / "first.out").string()) + " 2>&1";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", first.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!fs::exists(out) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // created, then locked at once
  const auto second = runCli("run " + exp + " --set duration=0.1 -o " + out.string());
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(tmp.path() / "first.out");
  EXPECT_EQ(second.status, 2) << second.out << second.err;
  EXPECT_THAT(second.err, HasSubstr("another jointsim run is writing into this folder"));
  EXPECT_THAT(slurp(out / "summary.json"), HasSubstr("\"sim_time_s\": 10"));
}

// SIGTERM while --collect writes the data set: exit 143 and no data set, no temporary file (it used to exit 0).
TEST(BatchSafety, SigtermDuringTheDataSetWriteLeavesNothing) {
  const TempDir tmp("collectterm");
  std::string runs = "runs:\n";
  for (int i = 0; i < 60; ++i) runs += "  - {name: r" + std::to_string(i) + "}\n";
  const fs::path sweep = writeSweep(tmp.path(), runs), out = tmp.path() / "out", set = tmp.path() / "set.h5";
  ASSERT_EQ(runCli("batch " + sweep.string() + " -j 2 -o " + out.string()).status, 0);
  // The write of 60 logs of 2000 rows takes about a second; the signal comes after 0.3 s.
  const auto r = runCommand("exec timeout --preserve-status -s TERM 0.3 " + kCli + " batch " + sweep.string() + " -o " +
                            out.string() + " --collect --dataset " + set.string());
  if (r.status == 0) GTEST_SKIP() << "the data set was written before the signal came (a fast machine)";
  EXPECT_EQ(r.status, 143) << r.out << r.err;
  EXPECT_FALSE(fs::exists(set));
  EXPECT_EQ(countTemporaries(tmp.path()), 0);
}

// The manifest is rewritten at a paced rate, not after every run: a sweep of many quick runs and a large manifest
// (a 100,000-run sweep once managed 176 runs in 30 s, rewriting its 20 MB manifest after each). Through the library
// (experiments::runBatch), which counts its writes; the manifest is complete at the end. Measured: 300 runs, 17 writes.
TEST(BatchSafety, TheManifestIsRewrittenAtAPacedRateNotAfterEveryRun) {
  const TempDir tmp("pacing");
  constexpr int kRuns = 300;
  // Every run is refused by the loader at once (a negative duration); 6 KB of overrides per record (a 1.8 MB manifest).
  const std::string text =
      "sweep:\n  name: pacing\n  experiment: " + jointsim::test::sourcePath("config/experiments/ur5_fall.yaml") +
      "\n  set: {experiment.description: " + std::string(6000, 'x') +
      "}\nsample:\n  design: monte_carlo\n  runs: " + std::to_string(kRuns) +
      "\n  seed: 3\n  parameters:\n    duration: {distribution: uniform, low: -2, high: -1}\n";
  const jointsim::experiments::Sweep sweep =
      jointsim::experiments::loadSweepText(text, (tmp.path() / "pacing.yaml").string());
  jointsim::experiments::BatchOptions o;
  o.output_dir = (tmp.path() / "out").string();
  o.jobs = 2;
  const jointsim::experiments::BatchResult r = jointsim::experiments::runBatch(sweep, o);
  EXPECT_EQ(r.failed, kRuns);
  EXPECT_GE(r.manifest_writes, 2);          // at the start and at the end
  EXPECT_LT(r.manifest_writes, kRuns / 4);  // not once per run
  const std::string manifest = slurp(tmp.path() / "out" / "manifest.csv");
  const auto rows = parseCsv(manifest);
  ASSERT_EQ(rows.size(), static_cast<size_t>(kRuns + 1));
  for (size_t i = 1; i < rows.size(); ++i) EXPECT_EQ(rows[i][1], "error") << rows[i][0];
  std::printf("%d runs, %d manifest writes of %zu bytes\n", kRuns, r.manifest_writes, manifest.size());
}
