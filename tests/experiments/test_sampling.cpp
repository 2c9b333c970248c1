// Sampling designs of sweeps against their definitions: Latin-hypercube stratification (one draw per
// equal-probability stratum of every parameter), the quantile maps of the three distributions, Monte-Carlo
// moments, reproducibility from the seed, and the sweep file's `sample:` block.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/experiments/sampling.hpp"
#include "test_util.hpp"

using namespace jointsim;
using namespace jointsim::experiments;
using Kind = ParameterDistribution::Kind;
using ::testing::HasSubstr;

namespace {
double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
}  // namespace

TEST(Sampling, QuantilesAreTheDistributionsInverses) {
  const ParameterDistribution u{Kind::Uniform, 2.0, 5.0}, lu{Kind::LogUniform, 1e-8, 1e-4}, nd{Kind::Normal, 1.3, 0.1};
  EXPECT_DOUBLE_EQ(u.quantile(0.25), 2.75);
  EXPECT_NEAR(std::log10(lu.quantile(0.25)), -7.0, 1e-12);
  EXPECT_NEAR(nd.quantile(0.975), 1.3 + 0.1 * 1.959963984540054, 1e-13);  // z_0.975 of the normal law
  for (double x : {-6.0, -2.5, -0.3, 0.0, 0.7, 3.1, 5.5}) {
    const ParameterDistribution z{Kind::Normal, 0.0, 1.0};
    EXPECT_NEAR(z.quantile(normalCdf(x)), x, 1e-9 * std::max(1.0, std::abs(x))) << x;
  }
}

TEST(Sampling, LatinHypercubeHasOneDrawInEveryStratumOfEveryParameter) {
  const int n = 37;
  const std::vector<ParameterDistribution> p = {{Kind::Uniform, 0.0, 1.0},
                                                {Kind::LogUniform, 1e-3, 10.0},
                                                {Kind::Normal, 5.0, 2.0}};
  const auto s = sampleDesign(SamplingDesign::LatinHypercube, n, p, 42);
  ASSERT_EQ(s.size(), static_cast<size_t>(n));
  for (size_t j = 0; j < p.size(); ++j) {
    std::vector<int> count(n, 0);
    for (const auto& row : s) {
      // Probability of the value under its own law, then its stratum.
      double u = 0.0;
      if (p[j].kind == Kind::Uniform) u = row[j];
      if (p[j].kind == Kind::LogUniform) u = (std::log(row[j]) - std::log(1e-3)) / (std::log(10.0) - std::log(1e-3));
      if (p[j].kind == Kind::Normal) u = normalCdf((row[j] - 5.0) / 2.0);
      const int k = static_cast<int>(std::floor(u * n));
      ASSERT_GE(k, 0);
      ASSERT_LT(k, n);
      ++count[static_cast<size_t>(k)];
    }
    for (int k = 0; k < n; ++k) EXPECT_EQ(count[static_cast<size_t>(k)], 1) << "parameter " << j << " stratum " << k;
  }
}

TEST(Sampling, MonteCarloMomentsAndSeededReproducibility) {
  const int n = 4000;
  const std::vector<ParameterDistribution> p = {{Kind::Uniform, -1.0, 3.0}, {Kind::Normal, 10.0, 0.5}};
  const auto a = sampleDesign(SamplingDesign::MonteCarlo, n, p, 7);
  double m0 = 0, m1 = 0, v1 = 0;
  for (const auto& r : a) {
    EXPECT_GT(r[0], -1.0);
    EXPECT_LT(r[0], 3.0);
    m0 += r[0] / n;
    m1 += r[1] / n;
  }
  for (const auto& r : a) v1 += (r[1] - m1) * (r[1] - m1) / (n - 1);
  EXPECT_NEAR(m0, 1.0, 4.0 * (4.0 / std::sqrt(12.0)) / std::sqrt(n));  // 4 standard errors
  EXPECT_NEAR(m1, 10.0, 4.0 * 0.5 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(v1), 0.5, 4.0 * 0.5 / std::sqrt(2.0 * n));
  EXPECT_EQ(sampleDesign(SamplingDesign::MonteCarlo, n, p, 7), a) << "same seed, same values to the bit";
  EXPECT_NE(sampleDesign(SamplingDesign::MonteCarlo, n, p, 8), a);
  EXPECT_EQ(sampleDesign(SamplingDesign::LatinHypercube, 10, p, 3),
            sampleDesign(SamplingDesign::LatinHypercube, 10, p, 3));
  EXPECT_THROW(sampleDesign(SamplingDesign::MonteCarlo, 0, p, 1), InputError);
  EXPECT_THROW(sampleDesign(SamplingDesign::MonteCarlo, 3, {{Kind::LogUniform, 0.0, 1.0}}, 1), InputError);
  EXPECT_THROW(samplingDesignFromString("sobol"), InputError);
}

TEST(Sampling, SweepFileSampleBlockMakesSeededRunsWithExactOverrides) {
  const test::TempDir tmp;
  const auto& dir = tmp.path();
  const std::string exp = std::string(JOINTSIM_SOURCE_DIR) + "/config/experiments/ur5_swg_joint_velocity.yaml";
  auto write = [&](const std::string& name, const std::string& sample) {
    std::ofstream(dir / name) << "sweep:\n  name: s\n  experiment: " << exp << "\n  set: {duration: 0.1}\n" << sample;
    return (dir / name).string();
  };
  const std::string good =
      write("good.yaml", "sample:\n  design: latin_hypercube\n  runs: 12\n  seed: 5\n  parameters:\n"
                         "    load.inertia: {distribution: normal, mean: 1.279, std: 0.05}\n"
                         "    input.controller.ki: {distribution: log_uniform, low: 5, high: 50}\n");
  const Sweep a = loadSweep(good), b = loadSweep(good);
  ASSERT_EQ(a.runs.size(), 12u);
  EXPECT_EQ(a.runs.front().name, "sample-00");
  EXPECT_EQ(a.runs.back().name, "sample-11");
  const auto values =
      sampleDesign(SamplingDesign::LatinHypercube, 12, {{Kind::Normal, 1.279, 0.05}, {Kind::LogUniform, 5.0, 50.0}}, 5);
  for (size_t i = 0; i < a.runs.size(); ++i) {
    EXPECT_EQ(a.runs[i].overrides, b.runs[i].overrides);
    ASSERT_EQ(a.runs[i].overrides.size(), 3u);  // duration (common), then the two sampled keys
    EXPECT_EQ(a.runs[i].overrides[0], "duration=0.1");
    const std::string& o = a.runs[i].overrides[1];
    ASSERT_EQ(o.rfind("load.inertia=", 0), 0u);
    EXPECT_EQ(std::stod(o.substr(13)), values[i][0]) << "the override text reads back the sampled double";
  }
  EXPECT_EQ(validateFile(good).runs, 12) << "every sampled run loads";

  struct Bad {
    std::string sample, message;
  } bad[] = {
      {"sample: {design: sobol, runs: 3, seed: 1, parameters: {load.inertia: {distribution: uniform, low: 1, high: 2}}}\n",
       "monte_carlo or latin_hypercube"},
      {"sample: {design: monte_carlo, runs: 0, seed: 1, parameters: {load.inertia: {distribution: uniform, low: 1, high: 2}}}\n",
       "number of runs"},
      {"sample: {design: monte_carlo, runs: 3, seed: 1, parameters: {load.inertia: {distribution: uniform, low: 2, high: 1}}}\n",
       "upper bound above low"},
      {"sample: {design: monte_carlo, runs: 3, seed: 1, parameters: {load.inertia: {distribution: normal, mean: 1, std: -1}}}\n",
       "standard deviation > 0"},
      {"sample: {design: monte_carlo, runs: 3, seed: 1, parameters: {load.inertia: {distribution: log_uniform, low: 0, high: 1}}}\n",
       "lower bound > 0"},
      {"sample: {design: monte_carlo, runs: 3, seed: 1, parameters: {load.inertia: {distribution: cauchy}}}\n",
       "uniform, normal or log_uniform"},
      {"sample: {design: monte_carlo, runs: 3, parameters: {load.inertia: {distribution: uniform, low: 1, high: 2}}}\n",
       "seed"},
  };
  for (const Bad& c : bad) {
    try {
      loadSweep(write("bad.yaml", c.sample));
      ADD_FAILURE() << "accepted: " << c.sample;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(c.message)) << c.sample;
      EXPECT_THAT(e.what(), HasSubstr("bad.yaml:")) << "file and line";
    }
  }
}
