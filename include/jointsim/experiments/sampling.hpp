#pragma once
/// \file
/// Sampling designs for sweeps (`sample:` in a sweep file, docs/batch.md): seeded Monte-Carlo and Latin-hypercube
/// samples of parameter ranges with uniform, normal and log-uniform distributions. Reproducible from the seed on
/// every platform: the generator is std::mt19937_64 (fully specified by the C++ standard) and every mapping from
/// its integers to numbers is written out here (no std::*_distribution, whose algorithms the standard leaves
/// open).

#include <cstdint>
#include <string>
#include <vector>

namespace jointsim::experiments {

enum class SamplingDesign {
  MonteCarlo,      ///< independent draws
  LatinHypercube,  ///< per parameter, exactly one draw in each of the n equal-probability strata
};

struct ParameterDistribution {
  enum class Kind { Uniform, Normal, LogUniform } kind = Kind::Uniform;
  double a = 0.0;  ///< uniform, log-uniform: lower bound (log-uniform: > 0); normal: mean
  double b = 1.0;  ///< uniform, log-uniform: upper bound (> a); normal: standard deviation (> 0)
  /// The value at probability u ∈ (0, 1): low + u (high − low); exp(ln low + u (ln high − ln low)); or
  /// mean + std Φ⁻¹(u) (Φ⁻¹ from Eigen's ndtri).
  double quantile(double u) const;
};

/// n samples (rows) of the parameters (columns), from `seed`. Throws InputError for n < 1 or an invalid
/// distribution.
std::vector<std::vector<double>> sampleDesign(SamplingDesign design, int n,
                                              const std::vector<ParameterDistribution>& parameters, std::uint64_t seed);

/// "monte_carlo", "latin_hypercube" (InputError listing them otherwise).
SamplingDesign samplingDesignFromString(const std::string& name);

}  // namespace jointsim::experiments
