#pragma once
/// \file
/// Mathematical constants shared by the library's sources (one definition, so that no source file needs its own, and
/// unity batches see one); internal: not installed, not part of the public API.

#include <limits>

namespace jointsim {

inline constexpr double kPi = 3.14159265358979323846;                    ///< π
inline constexpr double kTwoPi = 2.0 * kPi;                              ///< 2π [rad per turn]
inline constexpr double kInf = std::numeric_limits<double>::infinity();  ///< +∞

}  // namespace jointsim
