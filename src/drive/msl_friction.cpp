#include "jointsim/drive/msl_friction.hpp"

#include <cstdint>
#include <string>

#include "jointsim/common/interpolate.hpp"

namespace jointsim::drive {

double frictionTableValue(const std::vector<std::array<double, 2>>& t, double v) {
  return interpolateLinear(
      t.size(), [&t](size_t i) { return t[i][0]; }, [&t](size_t i) { return t[i][1]; }, v, Ends::Extrapolate);
}

int frictionModeNumber(FrictionMode m) {
  switch (m) {
    case FrictionMode::Forward: return 1;
    case FrictionMode::Backward: return -1;
    case FrictionMode::Free: return 2;
    default: return 0;  // stuck and start phases
  }
}

double frictionTorque(FrictionMode m, double f, double stuck_torque) {
  switch (m) {
    case FrictionMode::Forward:
    case FrictionMode::StartForward: return f;
    case FrictionMode::Backward:
    case FrictionMode::StartBackward: return -f;
    case FrictionMode::Free: return 0.0;
    case FrictionMode::Stuck: break;
  }
  return stuck_torque;
}

FrictionEventFlags frictionEventFlags(const std::vector<int>& fired, size_t k, int normal_slot) {
  if (fired.size() < 2 * k + 2) return {};
  FrictionEventFlags f{fired[2 * k] != 0, fired[2 * k] > 0, fired[2 * k + 1] < 0, fired[2 * k + 1] != 0};
  if (normal_slot >= 0 && static_cast<size_t>(normal_slot) < fired.size()) {
    f.engage = fired[static_cast<size_t>(normal_slot)] > 0;
    f.release = fired[static_cast<size_t>(normal_slot)] < 0;
  }
  return f;
}

namespace {
constexpr double kStartExitMargin = 1e-9;  // [-], relative to τ0max, see the start phases below
}  // namespace

FrictionMode nextFrictionMode(FrictionMode m, bool free, double S, double w, double a, double t0, double t0max,
                              const FrictionEventFlags& fired) {
  if (free) return FrictionMode::Free;
  switch (m) {
    case FrictionMode::Free:
      return w > 0 ? FrictionMode::Forward : (w < 0 ? FrictionMode::Backward : FrictionMode::Stuck);
    case FrictionMode::Stuck:
      if (S > t0max || fired.up) return w > 0 ? FrictionMode::Forward : FrictionMode::StartForward;
      if (S < -t0max || fired.down) return w < 0 ? FrictionMode::Backward : FrictionMode::StartBackward;
      return m;
    // A start phase locks again when its acceleration leaves the starting direction: MSL keeps startForward while
    // sa = a + τ0max > τ0. A start entered at a located root sits on the threshold S = ±τ0max to rounding; with
    // τ0max = τ0 (no breakaway peak) its acceleration is then zero to rounding, of either sign. So the comparison
    // without a reported crossing needs a margin beyond rounding (kStartExitMargin), and of the crossings of the
    // exit function only one out of the start region locks: a crossing into it is the start going on (its
    // acceleration growing in the starting direction). Without both, such a start locked again at once, and a
    // change of rounding elsewhere (e.g. in the mass matrix) decided whether an axis broke away or stayed stuck.
    case FrictionMode::StartForward:
      if (w > 0 || (fired.w && w >= 0)) return FrictionMode::Forward;
      if (a + t0max < t0 - kStartExitMargin * t0max || (fired.second && fired.down)) return FrictionMode::Stuck;
      return m;
    case FrictionMode::StartBackward:
      if (w < 0 || (fired.w && w <= 0)) return FrictionMode::Backward;
      if (a - t0max > -t0 + kStartExitMargin * t0max || (fired.second && !fired.down)) return FrictionMode::Stuck;
      return m;
    case FrictionMode::Forward: return (fired.w || w <= 0) ? FrictionMode::Stuck : m;
    case FrictionMode::Backward: return (fired.w || w >= 0) ? FrictionMode::Stuck : m;
  }
  return m;
}

namespace {
constexpr double kStartSpeed = 1e-10;  // [rad/s], see frictionRoots
}  // namespace

void frictionRoots(FrictionMode m, double S, double w, double a, double t0, double t0max, double& g0, double& g1) {
  g0 = g1 = 1.0;
  switch (m) {
    case FrictionMode::Stuck:
      g0 = S - t0max;
      g1 = S + t0max;
      break;
    // Start phases end when w has become strictly positive (negative). They usually begin at w = 0
    // exactly, and CVODE does not report a root function that leaves zero at a restart, so the speed
    // root is offset by kStartSpeed (1e-10 rad/s): the switch happens when |w| reaches it.
    case FrictionMode::StartForward:
      g0 = w - kStartSpeed;
      g1 = a + t0max - t0;
      break;
    case FrictionMode::StartBackward:
      g0 = w + kStartSpeed;
      g1 = a - t0max + t0;
      break;
    case FrictionMode::Forward:
    case FrictionMode::Backward: g0 = w; break;
    case FrictionMode::Free: break;
  }
}

void saveModes(ByteWriter& out, const std::vector<FrictionMode>& modes) {
  out.u64(modes.size());
  for (FrictionMode m : modes) out.u64(static_cast<std::uint64_t>(m));
}

void loadModes(ByteReader& in, std::vector<FrictionMode>& modes) {
  const std::uint64_t n = in.u64("friction mode count");
  if (n != modes.size())
    in.fail("friction mode count: expected " + std::to_string(modes.size()) + ", got " + std::to_string(n));
  for (FrictionMode& m : modes) {
    const std::uint64_t v = in.u64("friction mode");
    if (v > static_cast<std::uint64_t>(FrictionMode::Free)) in.fail("friction mode: bad value " + std::to_string(v));
    m = static_cast<FrictionMode>(v);
  }
}

}  // namespace jointsim::drive
