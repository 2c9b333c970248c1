// Identification of the static friction map (`jointsim identify friction`, jointsim::identify::fitFrictionMap):
// friction maps generated with the library's own LuGre model at the parameters of [Hauschild2003, Table 4.3] —
// its steady state (eq. 4.21) and a genuine time simulation of the velocity-plateau rig of [Hauschild2003] —
// plus seeded Gaussian measurement noise must give back Table 4.3 within 2 %, with standard errors that
// describe the scatter; the YAML output must be a friction block the model reader accepts; the CLI must map bad
// input to exit 2 and unidentifiable maps to exit 3.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <sys/wait.h>

#include <gmock/gmock.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/drive/drive_yaml.hpp"
#include "jointsim/drive/friction_models.hpp"
#include "jointsim/drive/parameters.hpp"
#include "jointsim/drive/transmissions.hpp"
#include "jointsim/identify/friction_fit.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "test_util.hpp"

using namespace jointsim;
using ::testing::HasSubstr;
using identify::DirectionFit;
using identify::FrictionFit;
using identify::FrictionFitOptions;
using identify::ParameterEstimate;

namespace {

// [Hauschild2003, Table 4.3] (Watflex shoulder, δ = 2): {α0 [N·m], α1 [N·m], α2 [N·m·s/rad], v_S [rad/s]}.
const drive::StribeckBranch kPositive{7.9707, 1.4476, 4.9349, 0.0363};
const drive::StribeckBranch kNegative{7.7538, 0.8626, 4.3267, 0.0221};

drive::LuGreFriction table43Model() {
  drive::LuGreParams p;  // σ0 = 259 N·m/rad, σ1 = 10 N·m·s/rad ([Hauschild2003, §4.5.4])
  p.positive = kPositive;
  p.negative = kNegative;
  return drive::LuGreFriction(p);
}

struct Map {
  std::vector<double> v, tau;
};

/// `n` speeds per direction, logarithmically spaced in [lo, hi] rad/s, torque = model steady state plus
/// Gaussian noise of standard deviation `noise` [N·m] from mt19937_64(seed).
Map steadyStateMap(const drive::Friction& model, int n, double lo, double hi, double noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Map m;
  for (int k = 0; k < n; ++k) {
    const double w = lo * std::pow(hi / lo, static_cast<double>(k) / (n - 1));
    for (double v : {w, -w}) {
      m.v.push_back(v);
      m.tau.push_back(model.steadyState(v) + noise * gauss(rng));
    }
  }
  return m;
}

struct ParamError {
  const char* name;
  double value, truth, std_error;
  double rel() const { return std::abs(value - truth) / truth; }
  double z() const { return std::abs(value - truth) / std_error; }
};

std::vector<ParamError> errors(const DirectionFit& d, const drive::StribeckBranch& t) {
  return {{"alpha0", d.alpha0.value, t.alpha0, d.alpha0.std_error},
          {"alpha1", d.alpha1.value, t.alpha1, d.alpha1.std_error},
          {"alpha2", d.alpha2.value, t.alpha2, d.alpha2.std_error},
          {"v_s", d.v_s.value, t.v_s, d.v_s.std_error}};
}

/// Every parameter of both directions within `rel_tol` of Table 4.3 and (when z_tol > 0) within z_tol standard
/// errors; prints the errors (they are quoted in docs/identify_friction.md).
void expectTable43(const FrictionFit& fit, double rel_tol, double z_tol, const std::string& label) {
  for (const auto& [d, t] : {std::pair{&fit.positive, kPositive}, std::pair{&fit.negative, kNegative}}) {
    for (const ParamError& e : errors(*d, t)) {
      std::printf("[%s] %s %-6s = %.6g (true %.6g): error %+.3f %%, %.2f std errors (std error %.3g)\n", label.c_str(),
                  d->direction.c_str(), e.name, e.value, e.truth, 100 * (e.value - e.truth) / e.truth, e.z(),
                  e.std_error);
      EXPECT_LE(e.rel(), rel_tol) << label << ": " << d->direction << " " << e.name << " = " << e.value;
      if (z_tol > 0) {
        EXPECT_LE(e.z(), z_tol) << label << ": " << d->direction << " " << e.name;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------- CLI helpers
std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Output captured per call (test::runCli); a private folder per test (test::TempDir).
using jointsim::test::CliResult;
using jointsim::test::runCli;
using jointsim::test::TempDir;

void writeMapCsv(const std::filesystem::path& path, const Map& m) {
  std::ofstream o(path);
  o << "velocity[rad/s],friction_torque[N*m]\n";
  o.precision(17);
  for (size_t i = 0; i < m.v.size(); ++i) o << m.v[i] << "," << m.tau[i] << "\n";
}

}  // namespace

// ================================================================================================ library

TEST(FrictionFit, NoiseFreeSteadyStateRecoversTable43Exactly) {
  const auto model = table43Model();
  Map m = steadyStateMap(model, 40, 1e-3, 1.0, 0.0, 1);
  // Order, duplicates and v = 0 points must not matter.
  std::mt19937 rng(7);
  std::vector<size_t> idx(m.v.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::shuffle(idx.begin(), idx.end(), rng);
  Map shuffled;
  for (size_t i : idx) shuffled.v.push_back(m.v[i]), shuffled.tau.push_back(m.tau[i]);
  for (size_t k = 0; k < 5; ++k) shuffled.v.push_back(m.v[k]), shuffled.tau.push_back(m.tau[k]);
  shuffled.v.push_back(0.0);
  shuffled.tau.push_back(0.3);
  shuffled.v.push_back(0.0);
  shuffled.tau.push_back(-0.2);

  const FrictionFit fit = identify::fitFrictionMap(shuffled.v, shuffled.tau);
  expectTable43(fit, 1e-7, 0.0, "noise-free");
  EXPECT_EQ(fit.dropped_zero, 2);
  EXPECT_EQ(fit.positive.points, 43);
  EXPECT_EQ(fit.negative.points, 42);
  EXPECT_LT(fit.positive.rms_residual, 1e-9);
  EXPECT_LT(fit.negative.rms_residual, 1e-9);
  EXPECT_FALSE(fit.delta_fitted);
  EXPECT_EQ(fit.delta.value, 2.0);
  for (double v : {-0.5, -0.02, -1e-3, 1e-3, 0.03, 0.7}) EXPECT_NEAR(fit.map(v), model.steadyState(v), 1e-8);
}

// The identified map applied to other friction models through their parameter tables: a LuGre model with other
// static parameters and bristles takes the map (its steady state is the identified one, its σ0 stays), a Stribeck
// model takes the map and δ, and a model without the static set is refused naming the key.
TEST(FrictionFit, TheMapAppliesToModelsByTheirTableKeys) {
  const auto truth = table43Model();
  const Map m = steadyStateMap(truth, 40, 1e-3, 1.0, 0.0, 1);
  const FrictionFit fit = identify::fitFrictionMap(m.v, m.tau);
  drive::LuGreParams other;
  other.sigma0 = 1234.0;
  other.positive = {1.0, 0.5, 1.0, 0.1};
  other.negative = {2.0, 0.1, 3.0, 0.2};
  const drive::LuGreFriction lugre(other);
  const auto applied = lugre.withParameters(identify::frictionChanges(fit, lugre));
  for (double v : {-0.5, -0.02, -1e-3, 1e-3, 0.03, 0.7})
    EXPECT_NEAR(applied->steadyState(v), truth.steadyState(v), 1e-7) << v;
  EXPECT_EQ(drive::parameterValue(applied->parameters(), "sigma0", "lugre"), 1234.0);
  const drive::StribeckFriction stribeck(drive::StribeckParams{});
  const auto st = stribeck.withParameters(identify::frictionChanges(fit, stribeck));
  EXPECT_EQ(drive::parameterValue(st->parameters(), "delta", "stribeck"), fit.delta.value);
  for (double v : {-0.5, -0.2, 0.2, 0.7}) EXPECT_NEAR(st->steadyState(v), fit.map(v), 1e-6) << v;  // limiter ≈ 1
  try {
    (void)identify::frictionChanges(fit, drive::CoulombViscousFriction(drive::CoulombViscousParams{}));
    FAIL() << "coulomb_viscous has no Stribeck static set";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("positive.alpha0"));
  }
}

TEST(FrictionFit, NoisySteadyStateRecoversTable43WithinTwoPercent) {
  // 80 speeds per direction from 1 mrad/s to 1 rad/s (half of them below 0.03 rad/s, as [Hauschild2003] measured more
  // points at low speed), noise 0.01 N·m (0.1 % of the friction level).
  const Map m = steadyStateMap(table43Model(), 80, 1e-3, 1.0, 0.01, 42);
  const FrictionFit fit = identify::fitFrictionMap(m.v, m.tau);
  expectTable43(fit, 0.02, 4.0, "steady state, noise 0.01 N·m");
  EXPECT_NEAR(fit.positive.rms_residual, 0.01, 0.002);
  EXPECT_NEAR(fit.negative.rms_residual, 0.01, 0.002);
  EXPECT_LT(fit.solve_time_s, 0.5);
}

TEST(FrictionFit, RigTimeSimulationRecoversTable43WithinTwoPercent) {
  // The measurement of [Hauschild2003, §4.5.4] (config/experiments/lugre_friction_map.yaml): the shoulder
  // (J = 3.41 kg·m², LuGre σ0 = 259, σ1 = 10, Table 4.3) under velocity PI control holds a staircase of speeds,
  // fast to slow in each direction; each plateau lasts 10 bristle time constants g/(σ0|v|) (>= 3 s), its second half
  // is averaged (torque command and speed). Then 0.01 N·m of seeded noise is added to the averages.
  const int n = 40;
  const double lo = 2e-3, hi = 0.6;
  std::vector<double> times, speeds;
  double t = 0;
  for (int dir : {1, -1})
    for (int k = n - 1; k >= 0; --k) {
      const double w = lo * std::pow(hi / lo, static_cast<double>(k) / (n - 1));
      times.push_back(t);
      speeds.push_back(dir * w);
      t += std::max(3.0, 10.0 * 9.4 / (259.0 * w));
    }
  systems::JointRigSetup s;
  s.name = "friction_map";
  s.rotor_inertia = 1e-3;
  s.transmission = std::make_shared<drive::RigidGear>(1.0);
  s.friction = std::make_shared<drive::LuGreFriction>(table43Model());
  s.friction_side = systems::Side::Output;
  s.load_inertia = 3.41;
  s.input = systems::RigInput::VelocityPI;
  s.pi = {200.0, 4000.0, 60.0, false, systems::Side::Output};
  std::vector<double> pt = times, pv = speeds;
  pt.push_back(t);
  pv.push_back(speeds.back());
  s.profile = control::Profile::piecewise(pt, pv, true);
  s.duration = t;
  s.log_rate = 4.0;
  s.solver.rtol = 1e-8;
  s.solver.atol = 1e-10;
  systems::JointRig rig(s);
  const int it = test::rowIndex(rig, "time"), iv = test::rowIndex(rig, "output_velocity"),
            iq = test::rowIndex(rig, "motor_torque");
  std::vector<double> sum_v(times.size(), 0.0), sum_tau(times.size(), 0.0), count(times.size(), 0.0);
  const auto wall0 = std::chrono::steady_clock::now();
  sim::simulate(rig, rig.simulateOptions(), [&](const Eigen::VectorXd& row) {
    const size_t k = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), row[it]) - times.begin()) - 1;
    const double end = k + 1 < times.size() ? times[k + 1] : t;
    if (row[it] >= 0.5 * (times[k] + end) && row[it] < end) {
      sum_v[k] += row[iv];
      sum_tau[k] += row[iq];
      count[k] += 1;
    }
  });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("[rig] %zu plateaus, %.0f s simulated in %.3f s wall time\n", times.size(), t, wall);
  std::mt19937_64 rng(2003);
  std::normal_distribution<double> gauss(0.0, 0.01);
  Map m;
  for (size_t k = 0; k < times.size(); ++k) {
    ASSERT_GT(count[k], 2) << "plateau " << k;
    m.v.push_back(sum_v[k] / count[k]);
    m.tau.push_back(sum_tau[k] / count[k] + gauss(rng));
    EXPECT_NEAR(m.v.back(), speeds[k], 1e-3 * std::abs(speeds[k])) << "plateau " << k;
  }
  const FrictionFit fit = identify::fitFrictionMap(m.v, m.tau);
  expectTable43(fit, 0.02, 4.0, "rig simulation, noise 0.01 N·m");
}

TEST(FrictionFit, StandardErrorsDescribeTheScatterAndShrinkWithData) {
  const auto model = table43Model();
  // Monte Carlo: over 25 seeds the normalised errors (estimate − truth)/std_error of all 8 parameters must
  // have an RMS near 1 (the std errors are neither optimistic nor pessimistic) and no outlier beyond 4.5.
  double sum_z2 = 0, max_z = 0;
  int count = 0;
  for (unsigned seed = 100; seed < 125; ++seed) {
    const Map m = steadyStateMap(model, 60, 1e-3, 1.0, 0.02, seed);
    const FrictionFit fit = identify::fitFrictionMap(m.v, m.tau);
    for (const auto& [d, t] : {std::pair{&fit.positive, kPositive}, std::pair{&fit.negative, kNegative}})
      for (const ParamError& e : errors(*d, t)) {
        sum_z2 += e.z() * e.z();
        max_z = std::max(max_z, e.z());
        ++count;
      }
  }
  const double rms_z = std::sqrt(sum_z2 / count);
  std::printf("[monte carlo] 25 seeds, noise 0.02 N·m, 60 points: RMS of error/std_error = %.3f, max %.2f\n", rms_z,
              max_z);
  EXPECT_GT(rms_z, 0.75);
  EXPECT_LT(rms_z, 1.3);
  EXPECT_LT(max_z, 4.5);

  // Half the noise: half the std errors (same seed, so the noise vector is scaled by exactly 1/2). Four times
  // the points (same spacing law): the std errors relative to the residual scatter halve, and the residual
  // standard deviation estimates the noise level.
  auto fitted = [&](int n, double noise) {
    const Map m = steadyStateMap(model, n, 1e-3, 1.0, noise, 5);
    return identify::fitFrictionMap(m.v, m.tau);
  };
  const FrictionFit base = fitted(60, 0.02), quiet = fitted(60, 0.01), dense = fitted(240, 0.02);
  for (const auto& [b, q, d] : {std::tuple{&base.positive, &quiet.positive, &dense.positive},
                                std::tuple{&base.negative, &quiet.negative, &dense.negative}}) {
    const ParameterEstimate* pb[] = {&b->alpha0, &b->alpha1, &b->alpha2, &b->v_s};
    const ParameterEstimate* pq[] = {&q->alpha0, &q->alpha1, &q->alpha2, &q->v_s};
    const ParameterEstimate* pd[] = {&d->alpha0, &d->alpha1, &d->alpha2, &d->v_s};
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_NEAR(pq[k]->std_error / pb[k]->std_error, 0.5, 0.02) << b->direction << " parameter " << k;
      EXPECT_NEAR((pd[k]->std_error / d->sigma) / (pb[k]->std_error / b->sigma), 0.5, 0.03)
          << b->direction << " parameter " << k;
    }
    EXPECT_NEAR(b->sigma, 0.02, 0.004) << b->direction;
    EXPECT_NEAR(d->sigma, 0.02, 0.002) << b->direction;
  }
}

TEST(FrictionFit, FreeFormFactorIsFoundAndRobustLossRejectsOutliers) {
  const auto model = table43Model();
  Map m = steadyStateMap(model, 40, 1e-3, 1.0, 0.0, 1);
  FrictionFitOptions o;
  o.fit_delta = true;
  o.delta = 1.5;  // start value
  FrictionFit fit = identify::fitFrictionMap(m.v, m.tau, o);
  EXPECT_TRUE(fit.delta_fitted);
  EXPECT_NEAR(fit.delta.value, 2.0, 1e-6);
  expectTable43(fit, 1e-6, 0.0, "free delta, noise-free");

  // Three gross outliers (stick-slip plateaus): plain least squares is pulled off, a Cauchy loss is not.
  m = steadyStateMap(model, 60, 1e-3, 1.0, 0.01, 11);
  for (size_t i : {10u, 30u, 50u}) m.tau[i] += 1.5;
  FrictionFitOptions robust;
  robust.loss = identify::FitLoss::Cauchy;
  robust.loss_scale = 0.03;
  fit = identify::fitFrictionMap(m.v, m.tau, robust);
  expectTable43(fit, 0.02, 4.0, "cauchy loss with outliers");
}

TEST(FrictionFit, UnidentifiableMapsNameTheDirectionAndReason) {
  const auto model = table43Model();
  auto expectUnidentifiable = [](const Map& m, const std::string& direction, const std::string& reason) {
    try {
      identify::fitFrictionMap(m.v, m.tau);
      ADD_FAILURE() << "expected UnidentifiableError (" << reason << ")";
    } catch (const UnidentifiableError& e) {
      EXPECT_THAT(e.what(), HasSubstr(direction));
      EXPECT_THAT(e.what(), HasSubstr(reason));
    }
  };
  // Only v > 0.
  Map m = steadyStateMap(model, 30, 1e-3, 1.0, 0.01, 3), pos_only;
  for (size_t i = 0; i < m.v.size(); ++i)
    if (m.v[i] > 0) pos_only.v.push_back(m.v[i]), pos_only.tau.push_back(m.tau[i]);
  expectUnidentifiable(pos_only, "negative direction (v < 0)", "no points");
  // Too few points.
  expectUnidentifiable(steadyStateMap(model, 5, 1e-3, 1.0, 0.01, 3), "positive direction (v > 0)", "only 5 points");
  // No Stribeck dip (α1 = 0): Coulomb + viscous only, with and without noise.
  drive::LuGreParams flat;
  flat.positive.alpha1 = flat.negative.alpha1 = 0.0;
  const drive::LuGreFriction flat_model(flat);
  expectUnidentifiable(steadyStateMap(flat_model, 40, 1e-3, 1.0, 0.0, 3), "positive direction", "Stribeck dip");
  expectUnidentifiable(steadyStateMap(flat_model, 40, 1e-3, 1.0, 0.02, 3), "positive direction", "Stribeck dip");
  // Only fast points, far above v_S: the dip is not sampled.
  try {
    const Map fast = steadyStateMap(model, 40, 0.15, 1.0, 0.01, 3);
    identify::fitFrictionMap(fast.v, fast.tau);
    ADD_FAILURE() << "expected UnidentifiableError for a map without slow points";
  } catch (const UnidentifiableError& e) {
    EXPECT_THAT(e.what(), HasSubstr("direction"));
    std::printf("[fast-only map] %s\n", e.what());
  }
}

TEST(FrictionFit, BadInputIsAnInputError) {
  EXPECT_THROW(identify::fitFrictionMap({0.1, 0.2}, {1.0}), InputError);
  EXPECT_THROW(identify::fitFrictionMap({0.1, NAN}, {1.0, 2.0}), InputError);
  FrictionFitOptions o;
  o.min_points = 2;
  EXPECT_THROW(identify::fitFrictionMap({0.1}, {1.0}, o), InputError);
  o = {};
  o.delta = -1;
  EXPECT_THROW(identify::fitFrictionMap({0.1}, {1.0}, o), InputError);
}

// ================================================================================================ YAML

TEST(FrictionFitYaml, FrictionBlockIsReadByTheModelReaderAndMatchesTheMap) {
  const Map m = steadyStateMap(table43Model(), 60, 1e-3, 1.0, 0.01, 9);
  const FrictionFit fit = identify::fitFrictionMap(m.v, m.tau);

  // Stribeck block: the model is the fitted map times the slope limiter 1 − e^{−k_S|v|} of
  // [Hauschild2003, eq. 4.24].
  identify::FrictionYamlOptions yo;
  yo.source = "map.csv";
  const std::string text = identify::frictionFitYaml(fit, yo);
  const io::YamlValue root = io::YamlValue::loadString(text, "fit.yaml");
  const auto stribeck = drive::frictionFromYaml(root["friction"]);
  ASSERT_EQ(stribeck->type(), "stribeck");
  for (double v = -1.0; v <= 1.0; v += 0.00125) {
    const double limiter = 1.0 - std::exp(-300.0 * std::abs(v));
    EXPECT_NEAR(stribeck->steadyState(v), fit.map(v) * limiter, 1e-12 * 10) << "v = " << v;
    if (std::abs(v) > 0.1) {  // e^{-30}: the limiter is 1 to 1e-13
      EXPECT_NEAR(stribeck->steadyState(v), fit.map(v), 1e-9) << "v = " << v;
    }
  }
  // The fit block: value, unit, std_error per parameter and direction; rms_residual and points.
  const io::YamlValue f = root["fit"];
  for (const auto& [dir, d] : {std::pair{"positive", &fit.positive}, std::pair{"negative", &fit.negative}}) {
    const io::YamlValue b = f[dir];
    EXPECT_EQ(b["points"].asInt(), d->points);
    EXPECT_EQ(b["rms_residual"].asDouble(), d->rms_residual);
    EXPECT_EQ(b["alpha0"]["value"].asDouble(), d->alpha0.value);
    EXPECT_EQ(b["alpha0"]["unit"].asString(), "N*m");
    EXPECT_EQ(b["alpha2"]["unit"].asString(), "N*m*s/rad");
    EXPECT_EQ(b["v_s"]["unit"].asString(), "rad/s");
    EXPECT_EQ(b["v_s"]["std_error"].asDouble(), d->v_s.std_error);
    EXPECT_EQ(b["alpha1"]["std_error"].asDouble(), d->alpha1.std_error);
  }
  EXPECT_EQ(f["source"].asString(), "map.csv");

  // LuGre block: the steady state of the model is exactly the fitted map.
  yo.lugre = true;
  yo.sigma0 = 259.0;
  yo.sigma1 = 10.0;
  const io::YamlValue lroot = io::YamlValue::loadString(identify::frictionFitYaml(fit, yo), "fit_lugre.yaml");
  const auto lugre = drive::frictionFromYaml(lroot["friction"]);
  ASSERT_EQ(lugre->type(), "lugre");
  EXPECT_THAT(identify::frictionFitYaml(fit, yo), HasSubstr("cannot determine"));
  for (double v = -1.0; v <= 1.0; v += 0.00125) EXPECT_NEAR(lugre->steadyState(v), fit.map(v), 1e-9) << "v = " << v;

  // LuGre has δ = 2: a fit with another δ cannot be written as a LuGre block.
  FrictionFit other = fit;
  other.delta.value = 1.7;
  EXPECT_THROW(identify::frictionFitYaml(other, yo), InputError);
}

// ================================================================================================ CLI

TEST(FrictionFitCli, WritesYamlAndSummary) {
  const TempDir tmp("cli_ok");
  const std::filesystem::path& dir = tmp.path();
  const Map m = steadyStateMap(table43Model(), 80, 1e-3, 1.0, 0.01, 42);
  writeMapCsv(dir / "map.csv", m);
  const auto out = dir / "fitted.yaml";
  const auto t0 = std::chrono::steady_clock::now();
  const CliResult r = runCli("identify friction " + (dir / "map.csv").string() + " -o " + out.string());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[cli] one identification (process start to exit): %.3f s\n%s", wall, r.out.c_str());
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_TRUE(std::filesystem::exists(out));
  EXPECT_THAT(r.out, HasSubstr("alpha0"));
  EXPECT_THAT(r.out, HasSubstr("wall time"));
  const io::YamlValue root = io::YamlValue::loadFile(out.string());
  const auto model = drive::frictionFromYaml(root["friction"]);
  EXPECT_NEAR(model->steadyState(0.5), table43Model().steadyState(0.5), 0.02);
  EXPECT_NEAR(model->steadyState(-0.5), table43Model().steadyState(-0.5), 0.02);

  // Default output name, --lugre, and stdout output.
  const CliResult d = runCli("identify friction " + (dir / "map.csv").string() + " --lugre 259,10");
  ASSERT_EQ(d.status, 0) << d.err;
  const io::YamlValue droot = io::YamlValue::loadFile((dir / "map_friction.yaml").string());
  EXPECT_EQ(drive::frictionFromYaml(droot["friction"])->type(), "lugre");
  // `jointsim run` takes the block as the model of a joint-rig friction entry, unchanged (re-indented).
  const std::string written = slurp(dir / "map_friction.yaml");
  const size_t a = written.find("friction:\n") + 10, b = written.find("\nfit:");
  std::string model_block = "  " + written.substr(a, b - a);
  for (size_t pos = model_block.find('\n'); pos != std::string::npos; pos = model_block.find('\n', pos + 1))
    model_block.insert(pos + 1, "  ");
  std::ofstream(dir / "rig.yaml") << "experiment: {name: rig, type: joint_rig}\nrotor_inertia: 1.0e-3\n"
                                     "transmission: {type: rigid, ratio: 1}\nfriction:\n  side: output\n  model:\n"
                                  << model_block
                                  << "\nload: {inertia: 3.41}\ninput:\n  type: velocity_pi\n"
                                     "  controller: {kp: 200, ki: 4000, limit: 60, output: torque, measure: output}\n"
                                     "  profile: {type: constant, value: 0.1}\nduration: 1.0\nlog_rate: 10\n";
  const CliResult run = runCli("run " + (dir / "rig.yaml").string() + " -o " + (dir / "rig_out").string());
  EXPECT_EQ(run.status, 0) << run.err << slurp(dir / "rig.yaml");
  const CliResult s = runCli("identify friction " + (dir / "map.csv").string() + " -o -");
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_THAT(s.out, HasSubstr("friction:\n  type: stribeck"));
}

TEST(FrictionFitCli, BadInputExitTwoWithFileLineAndNoOutput) {
  const TempDir tmp("cli_bad");
  const std::filesystem::path& dir = tmp.path();
  struct Case {
    std::string name, csv, expected;
  };
  const std::string good_rows = "0.001,9.4\n0.002,9.3\n";
  const std::vector<Case> cases = {
      {"missing_column", "velocity[rad/s],torque[N*m]\n" + good_rows,
       "missing_column.csv:1: missing column 'friction_torque"},
      {"nan_cell", "velocity[rad/s],friction_torque[N*m]\n" + good_rows + "0.003,nan\n",
       "nan_cell.csv:4:2: column 'friction_torque[N*m]'"},
      {"non_numeric", "velocity[rad/s],friction_torque[N*m]\n0.001,9.4\nfast,9.3\n",
       "non_numeric.csv:3:1: column 'velocity[rad/s]': expected a number, got 'fast'"},
      {"wrong_unit", "velocity[deg/s],friction_torque[N*m]\n" + good_rows,
       "wrong_unit.csv:1: column 'velocity[deg/s]': expected the unit rad/s"},
      {"empty", "velocity[rad/s],friction_torque[N*m]\n", "empty.csv: no data rows"},
  };
  for (const Case& c : cases) {
    const auto csv = dir / (c.name + ".csv");
    std::ofstream(csv) << c.csv;
    const auto out = dir / (c.name + ".yaml");
    const CliResult r = runCli("identify friction " + csv.string() + " -o " + out.string());
    EXPECT_EQ(r.status, 2) << c.name << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.expected)) << c.name;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.name << ": one-line message expected: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.name;
    EXPECT_FALSE(std::filesystem::exists(dir / (c.name + "_friction.yaml"))) << c.name;
  }
  const CliResult r = runCli("identify friction " + (dir / "nonexistent.csv").string());
  EXPECT_EQ(r.status, 2) << r.err;
  const CliResult l = runCli("identify friction " + (dir / "empty.csv").string() + " --lugre 259");
  EXPECT_EQ(l.status, 2) << l.err;
  EXPECT_THAT(l.err, HasSubstr("--lugre"));
}

TEST(FrictionFitCli, UnidentifiableMapsExitThree) {
  const TempDir tmp("cli_unident");
  const std::filesystem::path& dir = tmp.path();
  Map m = steadyStateMap(table43Model(), 30, 1e-3, 1.0, 0.01, 3), pos_only;
  for (size_t i = 0; i < m.v.size(); ++i)
    if (m.v[i] > 0) pos_only.v.push_back(m.v[i]), pos_only.tau.push_back(m.tau[i]);
  writeMapCsv(dir / "positive_only.csv", pos_only);
  CliResult r = runCli("identify friction " + (dir / "positive_only.csv").string());
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("cannot identify: negative direction (v < 0): no points"));
  EXPECT_FALSE(std::filesystem::exists(dir / "positive_only_friction.yaml"));

  drive::LuGreParams flat;
  flat.positive.alpha1 = flat.negative.alpha1 = 0.0;
  writeMapCsv(dir / "flat.csv", steadyStateMap(drive::LuGreFriction(flat), 40, 1e-3, 1.0, 0.02, 3));
  r = runCli("identify friction " + (dir / "flat.csv").string());
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("Stribeck dip"));
  EXPECT_FALSE(std::filesystem::exists(dir / "flat_friction.yaml"));
}
