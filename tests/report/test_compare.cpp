// report::compareTables / compareCsvFiles (`jointsim compare`): alignment on time, the peak-scaled tolerance,
// column selection and the InputError cases (docs/regression.md).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/report/compare.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using namespace jointsim;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Writes a log with columns time[s], angle[rad], torque[N·m], mode[-] sampled every `dt` over [0, t_end]:
/// angle = 0.5 sin(2π t) (a smooth signal crossing zero), torque = 10 cos(t), mode = sign of the angle.
/// The file is `name` in the folder `dir`.
std::string writeLogIn(const std::filesystem::path& dir, const std::string& name, double dt, double t_end,
                       const std::function<void(double, double&, double&, double&)>& tweak = {}) {
  const std::string path = (dir / name).string();
  std::ofstream out(path);
  out << "time[s],angle[rad],torque[N·m],mode[-]\n";
  const int n = static_cast<int>(std::lround(t_end / dt));
  char buf[256];
  for (int i = 0; i <= n; ++i) {
    const double t = i * dt;
    double angle = 0.5 * std::sin(2.0 * kPi * t), torque = 10.0 * std::cos(t);
    double mode = angle > 0.0 ? 1.0 : (angle < 0.0 ? -1.0 : 0.0);
    if (tweak) tweak(t, angle, torque, mode);
    std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g\n", t, angle, torque, mode);
    out << buf;
  }
  return path;
}

/// The tests' logs go to a folder of the test's own (CTest runs the tests of this file in parallel processes).
class Compare : public ::testing::Test {
 protected:
  const test::TempDir dir_;

  std::string writeLog(const std::string& name, double dt, double t_end,
                       const std::function<void(double, double&, double&, double&)>& tweak = {}) const {
    return writeLogIn(dir_, name, dt, t_end, tweak);
  }
};

const report::ColumnComparison& column(const report::CompareResult& r, const std::string& name) {
  for (const auto& c : r.columns)
    if (c.name == name) return c;
  throw std::runtime_error("no column " + name);
}

}  // namespace

TEST_F(Compare, IdenticalFilesPass) {
  const std::string a = writeLog("same_a.csv", 0.01, 2.0), b = writeLog("same_b.csv", 0.01, 2.0);
  const report::CompareResult r = report::compareCsvFiles(a, b);
  EXPECT_TRUE(r.pass());
  EXPECT_EQ(r.time_column, "time[s]");
  ASSERT_EQ(r.columns.size(), 3u);  // every column except time
  EXPECT_EQ(r.rows_compared, 201);
  EXPECT_EQ(r.rows_interpolated, 0);
  for (const auto& c : r.columns) EXPECT_EQ(c.max_deviation, 0.0) << c.name;
  EXPECT_THAT(report::formatComparison(r), HasSubstr("all 3 columns within tolerance"));
}

TEST_F(Compare, OnePercentChangeOfOneColumnFailsNamingItAndTheTime) {
  const std::string a = writeLog("pct_a.csv", 0.01, 2.0);
  const std::string b =
      writeLog("pct_b.csv", 0.01, 2.0, [](double, double&, double& torque, double&) { torque *= 1.01; });
  report::CompareOptions o;
  o.rtol = 1e-4;
  o.atol = 1e-9;
  const report::CompareResult r = report::compareCsvFiles(a, b, o);
  EXPECT_FALSE(r.pass());
  EXPECT_EQ(r.failed(), 1);
  const auto& c = column(r, "torque[N·m]");
  EXPECT_FALSE(c.pass);
  EXPECT_DOUBLE_EQ(c.time, 0.0);  // |Δ| = 0.1 cos t is largest at t = 0
  EXPECT_NEAR(c.max_deviation, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(c.value_a, 10.0);
  EXPECT_DOUBLE_EQ(c.value_b, 10.1);
  EXPECT_NEAR(c.tolerance, 1e-9 + 1e-4 * 10.1, 1e-12);
  EXPECT_EQ(c.line_a, 2);
  EXPECT_TRUE(column(r, "angle[rad]").pass);
  const std::string text = report::formatComparison(r);
  EXPECT_THAT(text, HasSubstr("1 of 3 columns differ beyond tolerance: torque[N·m]"));
  EXPECT_THAT(report::formatComparison(r, true), ::testing::Not(HasSubstr("angle[rad]")));
}

TEST_F(Compare, PeakScaledToleranceAcceptsSmallErrorsNearZeroCrossings) {
  // An error of 1e-6 × peak everywhere: pointwise relative tests would fail where the sine crosses zero.
  const std::string a = writeLog("zc_a.csv", 0.01, 2.0);
  const std::string b = writeLog("zc_b.csv", 0.01, 2.0, [](double, double& angle, double&, double&) { angle += 5e-7; });
  report::CompareOptions o;
  o.rtol = 1e-5;
  o.atol = 0.0;
  const report::CompareResult r = report::compareCsvFiles(a, b, o);
  EXPECT_TRUE(r.pass()) << report::formatComparison(r);
  EXPECT_NEAR(column(r, "angle[rad]").max_deviation, 5e-7, 1e-15);
}

TEST_F(Compare, InterpolatesSmoothSignalsSampledDifferently) {
  const std::string a = writeLog("interp_a.csv", 0.001, 1.0);
  const std::string b = writeLog("interp_b.csv", 0.0007, 0.9996);  // last sample 0.9996: within one interval
  report::CompareOptions o;
  o.rtol = 1e-4;
  o.columns = {"angle,torque"};  // the sign column jumps at zero crossings: not a smooth signal
  const report::CompareResult r = report::compareCsvFiles(a, b, o);
  EXPECT_TRUE(r.pass()) << report::formatComparison(r);
  EXPECT_GT(r.rows_interpolated, 800);  // all but the common multiples of 1 ms and 0.7 ms
  // Linear interpolation error ≤ h²/8 · max|y''| = 0.0007² / 8 · 0.5 (2π)² ≈ 1.2e-6.
  EXPECT_LT(column(r, "angle[rad]").max_deviation, 1.3e-6);
  EXPECT_GT(column(r, "angle[rad]").max_deviation, 1e-8);
  // A's last row (t = 1) is outside B's range and not compared.
  EXPECT_EQ(r.rows_compared, 1000);
}

TEST_F(Compare, SameGridNeedsNoInterpolationAcrossSteps) {
  // A decimated reference against the full log: every time of A is a sample of B, so the step of the mode
  // column is compared sample by sample (no interpolation across it).
  const std::string full = writeLog("grid_full.csv", 0.001, 1.0);
  const std::string dec = writeLog("grid_dec.csv", 0.01, 1.0);
  const report::CompareResult r = report::compareCsvFiles(dec, full);
  EXPECT_EQ(r.rows_interpolated, 0);
  EXPECT_EQ(r.rows_compared, 101);
  EXPECT_TRUE(r.pass()) << report::formatComparison(r);
}

TEST_F(Compare, DiscreteColumnsFailOnAChangeOfState) {
  const std::string a = writeLog("mode_a.csv", 0.01, 1.0);
  const std::string b = writeLog("mode_b.csv", 0.01, 1.0, [](double t, double&, double&, double& mode) {
    if (std::abs(t - 0.3) < 1e-9) mode = 0.0;
  });
  const report::CompareResult r = report::compareCsvFiles(a, b);
  ASSERT_FALSE(r.pass());
  EXPECT_FALSE(column(r, "mode[-]").pass);
  EXPECT_NEAR(column(r, "mode[-]").time, 0.3, 1e-12);
}

TEST_F(Compare, TimeToleranceAcceptsShiftedEvents) {
  // B's mode switches 5 ms late: fails at the same time, passes with a 5 ms tube.
  const std::string a = writeLog("shift_a.csv", 0.001, 1.0);
  const std::string b = writeLog("shift_b.csv", 0.001, 1.0, [](double t, double&, double&, double& mode) {
    mode = std::sin(2.0 * kPi * (t - 0.005)) > 0.0 ? 1.0 : -1.0;
    if (t == 0.0) mode = 0.0;
  });
  report::CompareOptions o;
  o.columns = {"mode"};
  EXPECT_FALSE(report::compareCsvFiles(a, b, o).pass());
  o.time_tolerance = 0.0055;
  const report::CompareResult r = report::compareCsvFiles(a, b, o);
  EXPECT_TRUE(r.pass()) << report::formatComparison(r);
}

TEST_F(Compare, ColumnsSelection) {
  const std::string a = writeLog("sel_a.csv", 0.01, 1.0);
  const std::string b = writeLog("sel_b.csv", 0.01, 1.0, [](double, double&, double& torque, double&) { torque += 1; });
  report::CompareOptions o;
  o.columns = {"angle[rad]", "mode"};  // repeated option; with and without a unit
  report::CompareResult r = report::compareCsvFiles(a, b, o);
  EXPECT_TRUE(r.pass());
  ASSERT_EQ(r.columns.size(), 2u);
  EXPECT_EQ(r.columns[0].name, "angle[rad]");
  EXPECT_EQ(r.columns[1].name, "mode[-]");
  o.columns = {" torque , angle"};  // comma-separated
  r = report::compareCsvFiles(a, b, o);
  ASSERT_EQ(r.columns.size(), 2u);
  EXPECT_FALSE(column(r, "torque[N·m]").pass);
  o.columns = {"speed"};
  EXPECT_THROW(report::compareCsvFiles(a, b, o), InputError);
}

TEST_F(Compare, ColumnMissingInBIsAnInputErrorUnlessDeselected) {
  const std::string a = writeLog("miss_a.csv", 0.01, 1.0);
  const auto dir = std::filesystem::path(a).parent_path();
  const std::string b = (dir / "miss_b.csv").string();
  {
    std::ofstream out(b);
    out << "time[s],angle[rad],extra[m]\n0,0,1\n0.5,0,1\n1,0,1\n";
  }
  try {
    report::compareCsvFiles(a, b);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("column 'torque[N·m]'"));
    EXPECT_THAT(e.what(), HasSubstr("missing"));
  }
  report::CompareOptions o;
  o.columns = {"angle"};
  o.rtol = 1.0;
  EXPECT_NO_THROW(report::compareCsvFiles(a, b, o));
  // Columns only in B are listed, not compared.
  const std::string sub = (dir / "miss_sub.csv").string();
  std::ofstream(sub) << "time[s],angle[rad]\n0,0\n0.5,0\n1,0\n";
  const report::CompareResult r = report::compareCsvFiles(sub, a, report::CompareOptions{});
  ASSERT_EQ(r.columns.size(), 1u);
  EXPECT_EQ(r.only_in_b, (std::vector<std::string>{"torque[N·m]", "mode[-]"}));
  EXPECT_THAT(report::formatComparison(r), HasSubstr("not compared (only in B): torque[N·m], mode[-]"));
}

TEST_F(Compare, DifferentUnitsAreIncompatible) {
  const auto dir = dir_.path();
  const std::string a = (dir / "unit_a.csv").string(), b = (dir / "unit_b.csv").string();
  std::ofstream(a) << "time[s],x[m]\n0,1\n1,2\n";
  std::ofstream(b) << "time[s],x[mm]\n0,1000\n1,2000\n";
  EXPECT_THROW(report::compareCsvFiles(a, b), InputError);
}

TEST_F(Compare, TimeRangesThatDoNotMatchAreInputErrors) {
  const std::string a = writeLog("range_a.csv", 0.01, 1.0);
  const auto dir = std::filesystem::path(a).parent_path();
  // No overlap at all.
  const std::string late = (dir / "late.csv").string();
  std::ofstream(late) << "time[s],angle[rad],torque[N·m],mode[-]\n5,0,0,0\n6,0,0,0\n";
  try {
    report::compareCsvFiles(a, late);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("do not overlap"));
  }
  // Overlapping but a much shorter B.
  const std::string short_b = writeLog("range_short.csv", 0.01, 0.5);
  try {
    report::compareCsvFiles(a, short_b);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("time ranges differ"));
  }
  report::CompareOptions o;
  o.time_range_tolerance = 0.6;  // explicitly allowed: compares the common part
  const report::CompareResult r = report::compareCsvFiles(a, short_b, o);
  EXPECT_EQ(r.rows_compared, 51);
  EXPECT_TRUE(r.pass());
}

TEST_F(Compare, UnreadableOrMalformedFilesAreInputErrors) {
  const std::string a = writeLog("bad_a.csv", 0.01, 1.0);
  EXPECT_THROW(report::compareCsvFiles(a, "/nonexistent/dir/log.csv"), InputError);
  EXPECT_THROW(report::compareCsvFiles("/nonexistent/dir/log.csv", a), InputError);
  const auto dir = std::filesystem::path(a).parent_path();
  const std::string header_only = (dir / "header_only.csv").string();
  std::ofstream(header_only) << "time[s],angle[rad],torque[N·m],mode[-]\n";
  EXPECT_THROW(report::compareCsvFiles(a, header_only), InputError);
  const std::string backwards = (dir / "backwards.csv").string();
  std::ofstream(backwards) << "time[s],angle[rad],torque[N·m],mode[-]\n0,0,0,0\n1,0,0,0\n0.5,0,0,0\n";
  EXPECT_THROW(report::compareCsvFiles(a, backwards), InputError);
  const std::string text = (dir / "text.csv").string();
  std::ofstream(text) << "time[s],angle[rad]\n0,abc\n";
  EXPECT_THROW(report::compareCsvFiles(a, text), InputError);
  report::CompareOptions o;
  o.rtol = -1.0;
  EXPECT_THROW(report::compareCsvFiles(a, a, o), InputError);
}

TEST_F(Compare, NonFiniteValuesMatchOnlyThemselves) {
  const auto dir = dir_.path();
  const std::string a = (dir / "nan_a.csv").string(), b = (dir / "nan_b.csv").string(),
                    c = (dir / "nan_c.csv").string();
  std::ofstream(a) << "time,x\n0,1\n1,nan\n2,3\n";
  std::ofstream(b) << "time,x\n0,1\n1,nan\n2,3\n";
  std::ofstream(c) << "time,x\n0,1\n1,2\n2,3\n";
  EXPECT_TRUE(report::compareCsvFiles(a, b).pass());
  const report::CompareResult r = report::compareCsvFiles(a, c);
  ASSERT_FALSE(r.pass());
  EXPECT_TRUE(std::isinf(r.columns[0].max_deviation));
  EXPECT_EQ(r.columns[0].time, 1.0);
  EXPECT_EQ(r.time_column, "time");
}

TEST_F(Compare, FirstColumnIsTimeWhenNoneIsNamedTime) {
  const auto dir = dir_.path();
  const std::string a = (dir / "first_a.csv").string(), b = (dir / "first_b.csv").string();
  std::ofstream(a) << "t[s],x[m],y[m]\n0,1,2\n1,2,3\n";
  std::ofstream(b) << "t[s],y[m],x[m]\n0,2,1\n1,3,2\n";  // other column order: matched by name
  const report::CompareResult r = report::compareCsvFiles(a, b);
  EXPECT_EQ(r.time_column, "t[s]");
  EXPECT_TRUE(r.pass()) << report::formatComparison(r);
  ASSERT_EQ(r.columns.size(), 2u);
}

// Was (found by fuzz_csv): a file whose header repeats a name ("-1,-1") compared with itself failed, its second
// column being paired with the first. Two columns with one base name make the pairing ambiguous: an error.
TEST_F(Compare, RepeatedColumnNamesAreAnInputError) {
  const auto dir = dir_.path();
  const std::string path = (dir / "repeated.csv").string();
  std::ofstream(path) << "time[s],x[m],x[mm]\n0,1,1000\n1,2,2000\n";
  EXPECT_THAT([&] { report::compareCsvFiles(path, path); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("repeated.csv: columns 2 and 3 have the same name 'x'")));
  const std::string fuzz = std::string(JOINTSIM_SOURCE_DIR) + "/tests/fuzz/regressions/csv/header_repeats_a_name.csv";
  EXPECT_THAT([&] { report::compareCsvFiles(fuzz, fuzz); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("columns 1 and 2 have the same name '-1'")));
}
