// report::agreement (`jointsim agreement`): RMS in % of range, bias, correlation and best-fit lag against closed
// forms on synthetic signals, the time offset, the pair patterns, and the errors; the CLI on the files.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/report/agreement.hpp"
#include "test_util.hpp"

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using namespace jointsim;
using jointsim::test::TempDir;

namespace {

/// Writes `header` and rows (t, f(t)...) for t = t0, t0 + dt, ..., t1.
std::string writeSignal(const std::filesystem::path& dir, const std::string& name, const std::string& header, double t0,
                        double dt, double t1, const std::function<std::vector<double>(double)>& f) {
  const std::string path = (dir / name).string();
  std::ofstream out(path);
  out.precision(17);
  out << header << "\n";
  for (int k = 0;; ++k) {
    const double t = t0 + dt * k;
    if (t > t1 + 1e-12) break;
    out << t;
    for (double v : f(t)) out << "," << v;
    out << "\n";
  }
  return path;
}

double m(double t) { return 2.0 * std::sin(3.0 * t) + 0.5 * std::sin(11.0 * t); }

}  // namespace

TEST(Agreement, BiasScaleAndLagAgainstClosedForms) {
  const TempDir tmp;
  // Measured at 125 Hz over [0, 4] s; the run at 1 kHz: a = m + 0.1 (bias), b = m(t + 0.012) (the measurement
  // comes 12 ms later), c = 1.5 m (a scale: correlation 1, RMS = 0.5 RMS(m)).
  const auto meas = writeSignal(tmp, "meas.csv", "t_s,i", 0.0, 0.008, 4.0, [](double t) { return std::vector{m(t)}; });
  const auto run = writeSignal(tmp, "run.csv", "time[s],a[A],b[A],c[A]", -0.2, 0.001, 4.2, [](double t) {
    return std::vector{m(t) + 0.1, m(t + 0.012), 1.5 * m(t)};
  });
  const report::AgreementResult r =
      report::agreementOfFiles(run, meas, {{"a", "i"}, {"b", "i"}, {"c", "i"}}, report::AgreementOptions{0.0, 0.03});
  ASSERT_EQ(r.pairs.size(), 3u);
  const io::CsvTable mt = io::readCsv(meas);
  const double R = mt.data.col(1).maxCoeff() - mt.data.col(1).minCoeff();
  const double rms_m = std::sqrt(mt.data.col(1).squaredNorm() / static_cast<double>(mt.rows()));
  const auto& a = r.pairs[0];
  EXPECT_EQ(a.samples, 501);
  EXPECT_NEAR(a.range, R, 1e-12);
  EXPECT_NEAR(a.bias, 0.1, 1e-4);  // linear interpolation of the 1 kHz run: error ≲ h² max|m''|/8 ≈ 1e-5
  EXPECT_NEAR(a.rms, 0.1, 1e-4);
  EXPECT_NEAR(a.rms_percent, 10.0 / R, 1e-3);
  EXPECT_NEAR(a.correlation, 1.0, 1e-8);
  EXPECT_NEAR(a.lag, 0.0, 1e-12);
  const auto& b = r.pairs[1];
  EXPECT_NEAR(b.lag, 0.012, 1e-12);  // on the lag grid (2 ms steps): found exactly
  EXPECT_LT(b.rms_percent_at_lag, 0.01);
  EXPECT_GT(b.rms_percent, 1.0);
  const auto& c = r.pairs[2];
  EXPECT_NEAR(c.correlation, 1.0, 1e-8);
  EXPECT_NEAR(c.rms, 0.5 * rms_m, 1e-4);
  EXPECT_NEAR(c.bias, 0.5 * mt.data.col(1).mean(), 1e-4);

  // The same run started at log time 1.5 s: with the offset the figures are unchanged over the overlap.
  const auto late = writeSignal(tmp, "late.csv", "time[s],a[A]", 0.0, 0.001, 2.0,
                                [](double t) { return std::vector{m(t + 1.5) + 0.1}; });
  report::AgreementOptions o;
  o.time_offset = 1.5;
  o.max_lag = 0.0;
  const auto rl = report::agreementOfFiles(late, meas, {{"a[A]", "i"}}, o);
  EXPECT_NEAR(rl.t_begin, 1.504, 1e-9);  // the first measured sample at or after 1.5 s
  EXPECT_NEAR(rl.t_end, 3.496, 1e-9);
  EXPECT_NEAR(rl.pairs[0].bias, 0.1, 1e-4);
}

TEST(Agreement, PairPatternsAndErrors) {
  const auto pairs = report::SignalPair::expand("current_{joint}=i_actual_{j}", {"base", "shoulder"});
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[1].predicted, "current_shoulder");
  EXPECT_EQ(pairs[1].measured, "i_actual_2");
  EXPECT_EQ(report::SignalPair::expand("x_{i}=y", {"a", "b"})[0].predicted, "x_0");
  EXPECT_EQ(report::SignalPair::expand(" a = b ", {}).front().measured, "b");
  EXPECT_THAT([] { report::SignalPair::parse("a", "--pair"); },
              ThrowsMessage<InputError>(HasSubstr("--pair: expected PREDICTED=MEASURED")));
  EXPECT_THAT([] { report::SignalPair::expand("a_{j}=b", {}, "--pair"); },
              ThrowsMessage<InputError>(HasSubstr("give the joint names too")));

  const TempDir tmp;
  const auto meas = writeSignal(tmp, "meas.csv", "t_s,i,flat", 0.0, 0.01, 1.0, [](double t) {
    return std::vector{m(t), 1.0};
  });
  const auto run = writeSignal(tmp, "run.csv", "time[s],a", 0.0, 0.01, 1.0, [](double t) { return std::vector{m(t)}; });
  EXPECT_THAT(
      [&] {
        report::agreementOfFiles(run, meas, {{"b", "i"}});
      },
      ThrowsMessage<InputError>(HasSubstr("run.csv:1: missing column 'b'")));
  EXPECT_THAT(
      [&] {
        report::agreementOfFiles(run, meas, {{"a", "flat"}});
      },
      ThrowsMessage<InputError>(HasSubstr("meas.csv: column 'flat' is constant")));
  report::AgreementOptions o;
  o.time_offset = 50.0;
  EXPECT_THAT(
      [&] {
        report::agreementOfFiles(run, meas, {{"a", "i"}}, o);
      },
      ThrowsMessage<InputError>(HasSubstr("meas.csv: only 0 measured samples lie inside the run")));
  // A long lag search on a finely sampled log stays bounded (at most 1000 lags each way).
  report::AgreementOptions wide;
  wide.max_lag = 0.4;
  const auto fine = writeSignal(tmp, "fine.csv", "t_s,i", 0.0, 1e-5, 1.0, [](double t) { return std::vector{m(t)}; });
  EXPECT_NEAR(report::agreementOfFiles(run, fine, {{"a", "i"}}, wide).pairs[0].lag, 0.0, 1e-12);
  const auto back = writeSignal(tmp, "back.csv", "t_s,i", 0.0, 0.01, 0.05, [](double t) { return std::vector{t}; });
  std::ofstream(back, std::ios::app) << "0.01,3\n";
  EXPECT_THAT(
      [&] {
        report::agreementOfFiles(run, back, {{"a", "i"}});
      },
      ThrowsMessage<InputError>(HasSubstr("back.csv:8:1: column 't_s': time 0.01 s is not after")));
}

TEST(Agreement, CommandLineTableJsonAndExitStatus) {
  const TempDir tmp;
  const auto meas = writeSignal(tmp, "meas.csv", "t_s,i_actual_1,i_actual_2", 0.0, 0.008, 2.0, [](double t) {
    return std::vector{m(t), -m(t)};
  });
  const auto run = writeSignal(tmp, "run.csv", "time[s],current_a[A],current_b[A]", 0.0, 0.001, 2.0, [](double t) {
    return std::vector{m(t) + 0.2, -m(t)};
  });
  const std::string json = (tmp / "agreement.json").string();
  const auto ok = test::runCli("agreement " + run + " " + meas +
                               " --joint-names a,b --pair 'current_{joint}=i_actual_{j}' --json " + json);
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_THAT(ok.out, HasSubstr("current_a"));
  EXPECT_THAT(ok.out, HasSubstr("i_actual_2"));
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j["pairs"].size(), 2u);
  EXPECT_EQ(j["pairs"][0]["measured"], "i_actual_1");
  EXPECT_NEAR(j["pairs"][0]["bias"].get<double>(), 0.2, 1e-9);
  EXPECT_NEAR(j["pairs"][1]["rms_percent"].get<double>(), 0.0, 1e-9);
  const auto bad = test::runCli("agreement " + run + " " + meas + " --pair current_c=i_actual_1");
  EXPECT_EQ(bad.status, 2);
  EXPECT_THAT(bad.err, HasSubstr("missing column 'current_c'"));
}
