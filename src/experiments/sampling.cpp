// Seeded Monte-Carlo and Latin-hypercube designs (include/jointsim/experiments/sampling.hpp).
#include "jointsim/experiments/sampling.hpp"

#include <cmath>
#include <numeric>
#include <random>

#include <unsupported/Eigen/SpecialFunctions>

#include "jointsim/common/error.hpp"

namespace jointsim::experiments {

namespace {

/// A double in the open interval (0, 1) from the top 53 bits of one 64-bit draw: ((x >> 11) + 1/2) 2⁻⁵³.
double openUnit(std::mt19937_64& rng) { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; }

/// An index in 0..k−1 without modulo bias worth the name (k ≪ 2⁵³): ⌊u k⌋ with u in (0, 1).
std::size_t index(std::mt19937_64& rng, std::size_t k) {
  const auto i = static_cast<std::size_t>(openUnit(rng) * static_cast<double>(k));
  return i < k ? i : k - 1;
}

}  // namespace

double ParameterDistribution::quantile(double u) const {
  switch (kind) {
    case Kind::Uniform: return a + u * (b - a);
    case Kind::LogUniform: return std::exp(std::log(a) + u * (std::log(b) - std::log(a)));
    case Kind::Normal: return a + b * Eigen::numext::ndtri(u);
  }
  return a;
}

SamplingDesign samplingDesignFromString(const std::string& name) {
  if (name == "monte_carlo") return SamplingDesign::MonteCarlo;
  if (name == "latin_hypercube") return SamplingDesign::LatinHypercube;
  throw InputError("sampling design '" + name + "', expected monte_carlo or latin_hypercube");
}

std::vector<std::vector<double>> sampleDesign(SamplingDesign design, int n,
                                              const std::vector<ParameterDistribution>& parameters,
                                              std::uint64_t seed) {
  if (n < 1) throw InputError("a sampling design needs at least one run, got " + std::to_string(n));
  for (const ParameterDistribution& p : parameters) {
    const bool ok = p.kind == ParameterDistribution::Kind::Normal
                        ? std::isfinite(p.a) && std::isfinite(p.b) && p.b > 0.0
                        : std::isfinite(p.a) && std::isfinite(p.b) && p.b > p.a &&
                              (p.kind != ParameterDistribution::Kind::LogUniform || p.a > 0.0);
    if (!ok) throw InputError("invalid distribution parameters");
  }
  std::mt19937_64 rng(seed);
  const auto rows = static_cast<std::size_t>(n);
  std::vector<std::vector<double>> out(rows, std::vector<double>(parameters.size()));
  std::vector<std::size_t> perm(rows);
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    if (design == SamplingDesign::LatinHypercube) {
      // Stratum of run i: perm[i] (a uniformly random permutation, Fisher–Yates), position in it: uniform.
      std::iota(perm.begin(), perm.end(), std::size_t{0});
      for (std::size_t i = rows; i-- > 1;) std::swap(perm[i], perm[index(rng, i + 1)]);
      for (std::size_t i = 0; i < rows; ++i)
        out[i][j] = parameters[j].quantile((static_cast<double>(perm[i]) + openUnit(rng)) / static_cast<double>(n));
    } else {
      for (std::size_t i = 0; i < rows; ++i) out[i][j] = parameters[j].quantile(openUnit(rng));
    }
  }
  return out;
}

}  // namespace jointsim::experiments
