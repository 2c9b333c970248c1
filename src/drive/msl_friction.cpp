#include "jointsim/drive/msl_friction.hpp"

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

FrictionEventFlags frictionEventFlags(const std::vector<int>& fired, size_t k) {
  if (fired.size() < 2 * k + 2) return {};
  return {fired[2 * k] != 0, fired[2 * k] > 0, fired[2 * k + 1] < 0, fired[2 * k + 1] != 0};
}

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
    case FrictionMode::StartForward:
      if (w > 0 || (fired.w && w >= 0)) return FrictionMode::Forward;
      if (a + t0max < t0 || fired.second) return FrictionMode::Stuck;  // MSL: sa = a + τ0max must stay > τ0
      return m;
    case FrictionMode::StartBackward:
      if (w < 0 || (fired.w && w <= 0)) return FrictionMode::Backward;
      if (a - t0max > -t0 || fired.second) return FrictionMode::Stuck;
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

}  // namespace jointsim::drive
