// `jointsim plot` (report::plotRun): for a short run of every shipped experiment type, the expected figures exist
// and are valid PNGs of the requested size (SVGs with --svg); sweep folders (manifest.csv), the generic
// fallback, atomic output and the errors (missing folder, no CSV, gnuplot not found: InputError, exit 2).
// Needs gnuplot (Debian gnuplot-nox, installed by scripts/install-deps.sh): without it every figure test fails
// with "gnuplot not found; install gnuplot-nox".
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/report/plot.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using jointsim::test::sourcePath;
namespace fs = std::filesystem;

namespace {

/// A fresh folder per test (CTest runs the tests in parallel processes), removed at the end of a test that
/// passed (kept for inspection when it failed).
using Scratch = jointsim::test::TempDir;

/// Runs a shipped experiment file with overrides (kept short) into `dir`.
void runExperiment(const std::string& config, const std::vector<std::string>& overrides, const fs::path& dir) {
  jointsim::experiments::RunOptions options;
  options.output_dir = dir.string();
  options.overrides = overrides;
  const auto report = jointsim::experiments::runExperimentFile(sourcePath("config/experiments/" + config), options);
  ASSERT_EQ(report.status, "ok") << config;
}

/// Width and height of a PNG; fails unless it has the PNG signature and an IHDR chunk first.
::testing::AssertionResult isPng(const std::string& path, int width, int height) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return ::testing::AssertionFailure() << path << ": missing";
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  if (in.gcount() != 24) return ::testing::AssertionFailure() << path << ": shorter than a PNG header";
  const unsigned char signature[8] = {0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A};
  if (!std::equal(signature, signature + 8, b)) return ::testing::AssertionFailure() << path << ": no PNG signature";
  if (std::string(reinterpret_cast<char*>(b + 12), 4) != "IHDR")
    return ::testing::AssertionFailure() << path << ": first chunk is not IHDR";
  auto be32 = [&](int at) {
    return static_cast<int>((std::uint32_t(b[at]) << 24) | (std::uint32_t(b[at + 1]) << 16) |
                            (std::uint32_t(b[at + 2]) << 8) | std::uint32_t(b[at + 3]));
  };
  if (be32(16) != width || be32(20) != height)
    return ::testing::AssertionFailure() << path << ": " << be32(16) << "x" << be32(20) << " pixels, expected " << width
                                         << "x" << height;
  if (fs::file_size(path) < 5000)
    return ::testing::AssertionFailure() << path << ": suspiciously small (empty figure?)";
  return ::testing::AssertionSuccess();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Plots `run_dir` into run_dir/figures and checks exactly the expected figures (PNG) were written.
void expectFigures(const fs::path& run_dir, const std::vector<std::string>& stems,
                   const jointsim::report::PlotOptions& options = {}) {
  const auto written = jointsim::report::plotRun(run_dir.string(), "", options);
  std::vector<std::string> expected;
  for (const auto& s : stems) expected.push_back((run_dir / "figures" / (s + ".png")).string());
  if (options.svg)
    for (const auto& s : stems) expected.push_back((run_dir / "figures" / (s + ".svg")).string());
  EXPECT_EQ(written, expected);
  for (const auto& s : stems)
    EXPECT_TRUE(isPng((run_dir / "figures" / (s + ".png")).string(), options.width, options.height));
  for (const auto& entry : fs::directory_iterator(run_dir / "figures"))
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << "left behind: " << entry.path();
}

using jointsim::test::CliResult;

/// The CLI with `args`, `env` (assignments such as "PATH=... ") in front; output captured by test::runCommand.
CliResult runCli(const std::string& args, const std::string& env = "") {
  return jointsim::test::runCommand(env + std::string(JOINTSIM_CLI_PATH) + " " + args);
}

}  // namespace

// ------------------------------------------------------------------------------------------ one test per type

TEST(Plot, PassiveRobotJointsAndEnergy) {
  const Scratch dir("passive");
  runExperiment("ur5_fall.yaml", {"duration=0.1"}, dir);
  expectFigures(dir, {"ur5_fall_joints", "ur5_fall_energy"});
}

TEST(Plot, TrackingErrorTorquesAnglesCurrents) {
  const Scratch dir("tracking");
  runExperiment("ur5_excitation.yaml", {"duration=0.1"}, dir);
  expectFigures(dir, {"ur5_excitation_tracking_error", "ur5_excitation_torques", "ur5_excitation_joint_angles",
                      "ur5_excitation_currents"});
  // The script says what is drawn: the error q_set - q per joint, the inverse-dynamics reference.
  jointsim::report::PlotOptions options;
  options.keep_script = true;
  const auto written = jointsim::report::plotRun(dir.string(), (dir / "kept").string(), options);
  ASSERT_EQ(written.back(), (dir / "kept" / "ur5_excitation_plots.gp").string());
  const std::string script = slurp(written.back());
  EXPECT_THAT(script, HasSubstr("set ylabel 'q_set − q ["));
  EXPECT_THAT(script, HasSubstr("title 'inverse dynamics (reference)'"));
  EXPECT_THAT(script, HasSubstr("set xlabel 'time [s]'"));
}

TEST(Plot, ClampingCurvesPerAxisAndClamp) {
  const Scratch dir("clamping");
  runExperiment("irb140_clamping.yaml", {"duration=0.3"}, dir);
  expectFigures(dir, {"irb140_clamping_clamping_curves", "irb140_clamping_axis_torques", "irb140_clamping_clamp"});
  jointsim::report::PlotOptions options;
  options.keep_script = true;
  const std::string script = slurp(jointsim::report::plotRun(dir.string(), (dir / "kept").string(), options).back());
  EXPECT_THAT(script, HasSubstr("set multiplot layout 2,3"));  // six axes
  EXPECT_THAT(script, HasSubstr("set xlabel 'motor angle [rad]'"));
  EXPECT_THAT(script, HasSubstr("set ylabel 'torque [N·m]'"));
}

TEST(Plot, JointRigClampingCurve) {
  const Scratch dir("rig_clamped");
  runExperiment("kr300_joint1_clamping.yaml", {"duration=2"}, dir);
  expectFigures(dir, {"kr300_joint1_clamping_signals", "kr300_joint1_clamping_clamping_curve"});
}

TEST(Plot, JointRigFrictionMap) {
  const Scratch dir("rig_friction");
  runExperiment("lugre_friction_map.yaml", {"duration=1"}, dir);
  expectFigures(dir, {"lugre_friction_map_signals", "lugre_friction_map_friction_map"});
}

TEST(Plot, JointRigWithMotorElectricsAsSvgToo) {
  const Scratch dir("rig_swg");
  runExperiment("ur5_swg_joint_velocity.yaml", {"duration=0.3"}, dir);
  jointsim::report::PlotOptions options;
  options.svg = true;
  options.width = 900;
  options.height = 600;
  expectFigures(dir, {"ur5_swg_joint_velocity_signals", "ur5_swg_joint_velocity_friction_map"}, options);
  const std::string svg = slurp(dir / "figures" / "ur5_swg_joint_velocity_signals.svg");
  EXPECT_THAT(svg, HasSubstr("<svg"));
  EXPECT_THAT(svg, HasSubstr("width=\"900\""));
  EXPECT_THAT(svg, HasSubstr("</svg>"));
}

TEST(Plot, DriveChainInertiasAndElements) {
  const Scratch dir("drive_chain");
  runExperiment("msl_friction.yaml", {"duration=0.6"}, dir);
  expectFigures(dir, {"msl_friction_inertias", "msl_friction_elements"});
}

TEST(Plot, RobotR3AxisSignalsAndEnergy) {
  const Scratch dir("r3_axis");
  runExperiment("robotr3_one_axis.yaml", {"stop_time=0.3"}, dir);
  expectFigures(dir, {"robotr3_one_axis_axis", "robotr3_one_axis_energy"});
}

TEST(Plot, RobotR3FullJointsAndDrives) {
  const Scratch dir("r3_full");
  runExperiment("robotr3_full_robot.yaml", {"stop_time=0.2"}, dir);
  expectFigures(dir, {"robotr3_full_robot_joints", "robotr3_full_robot_drives"});
}

TEST(Plot, UnknownTypeGetsEveryColumnInPagesOfSix) {
  const Scratch dir("generic");
  {
    std::ofstream csv(dir / "mystery.csv");
    csv << "time[s],a[m],b[rad],c[N],d[-],e[V],f[A],g[J]\n";
    for (int i = 0; i <= 100; ++i) {
      const double t = 0.01 * i;
      csv << t << "," << t * t << "," << std::sin(10 * t) << "," << 3 * t << ",1," << -t << ",0.5," << t << "\n";
    }
    std::ofstream(dir / "summary.json") << "{\n  \"experiment\": \"mystery\",\n  \"type\": \"something_new\",\n"
                                           "  \"status\": \"ok\",\n  \"parameters\": {\"type\": \"joint_rig\"}\n}\n";
  }
  expectFigures(dir, {"mystery_columns_1", "mystery_columns_2"});
}

// ------------------------------------------------------------------------------------------ sweeps

TEST(Plot, SweepBarsAndOverlay) {
  const Scratch dir("sweep");
  runExperiment("ur5_fall.yaml", {"duration=0.1"}, dir / "fall_a");
  runExperiment("ur5_fall.yaml", {"duration=0.1", "initial_state.qd[0]=1"}, dir / "fall_b");
  std::ofstream(dir / "manifest.csv") << "run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,overrides\n"
                                      << "fall_a,ok,0.02,0.1,5,fall_a,\"duration=0.1\"\n"
                                      << "fall_b,ok,0.01,0.1,10," << (dir / "fall_b").string()
                                      << ",\"duration=0.1,initial_state.qd[0]=1\"\n"
                                      << "fall_c,failed,0.005,0.01,2,fall_c,\"solver.rtol=1\"\n";
  expectFigures(dir, {"sweep_runs", "sweep_overlay"});
  jointsim::report::PlotOptions options;
  options.keep_script = true;
  const std::string script = slurp(jointsim::report::plotRun(dir.string(), (dir / "kept").string(), options).back());
  EXPECT_THAT(script, HasSubstr("title 'fall_a'"));
  EXPECT_THAT(script, HasSubstr("title 'fall_b'"));
  EXPECT_THAT(script, HasSubstr("title 'status failed'"));
}

TEST(Plot, SweepOfDifferentExperimentsHasNoOverlay) {
  const Scratch dir("sweep_mixed");
  runExperiment("ur5_fall.yaml", {"duration=0.1"}, dir / "one");
  runExperiment("msl_backlash.yaml", {"duration=0.1"}, dir / "two");
  std::ofstream(dir / "manifest.csv") << "run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,overrides\n"
                                      << "one,ok,0.02,0.1,5,one,\"\"\nsecond,ok,0.01,0.1,10,two,\"\"\n";
  expectFigures(dir, {"sweep_runs"});
}

TEST(Plot, BadManifestIsInputError) {
  const Scratch dir("sweep_bad");
  std::ofstream(dir / "manifest.csv") << "run,status\nx,ok\n";
  EXPECT_THROW(jointsim::report::plotRun(dir.string()), jointsim::InputError);
}

// ------------------------------------------------------------------------------------------ errors

TEST(Plot, MissingFolderOrCsvIsInputError) {
  const Scratch dir("errors");
  try {
    jointsim::report::plotRun((dir / "nowhere").string());
    FAIL() << "expected InputError";
  } catch (const jointsim::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no such run folder"));
  }
  try {  // neither a run nor a sweep
    jointsim::report::plotRun(dir.string());
    FAIL() << "expected InputError";
  } catch (const jointsim::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("neither a run folder"));
  }
  // A failed run: summary.json without a CSV.
  std::ofstream(dir / "summary.json") << "{\"experiment\": \"boom\", \"type\": \"joint_rig\", \"status\": \"failed\", "
                                         "\"reason\": \"CV_CONV_FAILURE at t = 0.1 s\"}";
  try {
    jointsim::report::plotRun(dir.string());
    FAIL() << "expected InputError";
  } catch (const jointsim::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no CSV log to plot"));
    EXPECT_THAT(e.what(), HasSubstr("CV_CONV_FAILURE"));
  }
  EXPECT_FALSE(fs::exists(dir / "figures")) << "nothing written on bad input";
}

TEST(Plot, GnuplotNotFoundIsInputError) {
  const Scratch dir("nognuplot");
  runExperiment("ur5_fall.yaml", {"duration=0.05"}, dir);
  jointsim::report::PlotOptions options;
  options.gnuplot = (dir / "no-such-gnuplot").string();
  try {
    jointsim::report::plotRun(dir.string(), "", options);
    FAIL() << "expected InputError";
  } catch (const jointsim::InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("gnuplot not found; install gnuplot-nox (scripts/install-deps.sh)"));
  }
  EXPECT_NO_THROW(jointsim::report::findGnuplot()) << "gnuplot-nox is needed by `jointsim plot` and these tests";
}

TEST(Plot, GnuplotFailureIsReportedAndLeavesNoFigure) {
  const Scratch dir("gnuplot_fails");
  runExperiment("ur5_fall.yaml", {"duration=0.05"}, dir);
  const fs::path fake = dir / "fake-gnuplot";
  std::ofstream(fake) << "#!/bin/sh\necho 'line 3: something went wrong' >&2\nexit 1\n";
  fs::permissions(fake, fs::perms::owner_all);
  jointsim::report::PlotOptions options;
  options.gnuplot = fake.string();
  try {
    jointsim::report::plotRun(dir.string(), "", options);
    FAIL() << "expected Error";
  } catch (const jointsim::InputError&) {
    FAIL() << "a gnuplot failure is not bad input";
  } catch (const jointsim::Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("failed with exit status 1"));
    EXPECT_THAT(e.what(), HasSubstr("line 3: something went wrong"));
  }
  ASSERT_TRUE(fs::is_directory(dir / "figures"));
  EXPECT_TRUE(fs::is_empty(dir / "figures")) << "no figure, temporary file or script left behind";
}

// ------------------------------------------------------------------------------------------ command line

TEST(PlotCli, WritesFiguresAndListsThem) {
  const Scratch dir("cli");
  runExperiment("ur5_fall.yaml", {"duration=0.1"}, dir / "run");
  const CliResult r = runCli("plot " + (dir / "run").string() + " -o " + (dir / "figs").string() + " --svg");
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_THAT(r.out, HasSubstr((dir / "figs" / "ur5_fall_joints.png").string()));
  EXPECT_THAT(r.out, HasSubstr((dir / "figs" / "ur5_fall_energy.svg").string()));
  EXPECT_TRUE(isPng((dir / "figs" / "ur5_fall_energy.png").string(), 1400, 900));
}

TEST(PlotCli, BadInputExitsWithStatus2) {
  const Scratch dir("cli_errors");
  CliResult r = runCli("plot " + (dir / "nowhere").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("no such run folder"));
  runExperiment("ur5_fall.yaml", {"duration=0.05"}, dir / "run");
  r = runCli("plot " + (dir / "run").string(), "PATH=" + (dir / "empty").string() + " ");
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("gnuplot not found; install gnuplot-nox (scripts/install-deps.sh)"));
}
