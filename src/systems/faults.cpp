#include "jointsim/systems/faults.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/drive/dc_motor.hpp"
#include "jointsim/drive/friction.hpp"
#include "jointsim/drive/parameters.hpp"
#include "jointsim/drive/transmission.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems {
namespace {

const char* const kNames[] = {"gear_stiffness_scale",  "backlash_add",  "coulomb_friction_scale", "sigma0_scale",
                              "torque_constant_scale", "sensor_bias",   "sensor_dropout",         "sensor_stuck",
                              "sensor_spike",          "bearing_ripple"};
constexpr int kTypes = sizeof(kNames) / sizeof(kNames[0]);

bool factorType(FaultType t) {
  return t == FaultType::GearStiffnessScale || t == FaultType::CoulombFrictionScale || t == FaultType::Sigma0Scale ||
         t == FaultType::TorqueConstantScale;
}

[[noreturn]] void bad(const Fault& f, const std::string& what) {
  throw InputError("fault " + describe(f) + ": " + what);
}

[[noreturn]] void notApplicable(const Fault& f, const std::string& component) {
  throw InputError("fault " + describe(f) + ": does not apply to " + component);
}

// The parameter role a fault acts on, and whether it adds (an offset) or multiplies (a factor).
drive::ParameterRole roleOf(FaultType t) {
  switch (t) {
    case FaultType::GearStiffnessScale: return drive::ParameterRole::Stiffness;
    case FaultType::BacklashAdd: return drive::ParameterRole::Backlash;
    case FaultType::CoulombFrictionScale: return drive::ParameterRole::Coulomb;
    case FaultType::Sigma0Scale: return drive::ParameterRole::BristleStiffness;
    case FaultType::TorqueConstantScale: return drive::ParameterRole::TorqueConstant;
    default: return drive::ParameterRole::None;
  }
}

// Why a fault of type `t` does not apply to drive `d` (empty: it applies), from the components' parameter tables.
std::string refusal(const DriveSpec& d, FaultType t) {
  const drive::ParameterRole role = roleOf(t);
  switch (t) {
    case FaultType::GearStiffnessScale:
    case FaultType::BacklashAdd: {
      const drive::Transmission* tr = d.transmission.get();
      if (tr != nullptr && drive::hasRole(tr->parameters(), role)) return {};
      const std::string what = tr ? "a " + tr->type() + " transmission" : "a drive without transmission";
      return what + (t == FaultType::GearStiffnessScale ? " (no stiffness)"
                                                        : " (backlash needs an elastic or elasto_backlash gear)");
    }
    case FaultType::CoulombFrictionScale:
    case FaultType::Sigma0Scale: {
      const drive::Friction* fr = d.friction.get();
      if (fr == nullptr) return "a drive without friction";
      if (drive::hasRole(fr->parameters(), role)) return {};
      return fr->type() + " friction" +
             (t == FaultType::Sigma0Scale ? " (no bristle stiffness)" : " (no Coulomb level)");
    }
    case FaultType::TorqueConstantScale:
      return d.electrics ? std::string() : "a torque-controlled motor without electrics (k_t and k_e are not used)";
    case FaultType::SensorBias:
    case FaultType::SensorDropout:
    case FaultType::SensorStuck:
    case FaultType::SensorSpike:
      return d.controller.type == control::ControllerType::VoltageCascade
                 ? std::string()
                 : "a drive whose controller does not read the joint angle (only voltage_cascade does)";
    case FaultType::BearingRipple: return {};
  }
  return {};
}

}  // namespace

bool Fault::parameterFault() const { return static_cast<int>(type) <= static_cast<int>(FaultType::SensorBias); }

bool Fault::intermittent() const {
  return type == FaultType::SensorDropout || type == FaultType::SensorStuck || type == FaultType::SensorSpike;
}

bool Fault::timeVarying() const { return onset > 0.0 || progression != Progression::Step || !parameterFault(); }

const char* toString(FaultType type) { return kNames[static_cast<int>(type)]; }

std::vector<std::string> faultTypeNames() { return {std::begin(kNames), std::end(kNames)}; }

FaultType faultTypeFromString(const std::string& name) {
  for (int i = 0; i < kTypes; ++i)
    if (name == kNames[i]) return static_cast<FaultType>(i);
  std::string list;
  for (const char* n : kNames) list += (list.empty() ? "" : ", ") + std::string(n);
  throw InputError("unknown fault '" + name + "' (known: " + list + ")");
}

std::string describe(const Fault& f) {
  // Every number as the shortest text that reads back as exactly it: the description is part of a batch run's
  // fingerprint (resume), so two different faults must never read alike (rates 1e-7 and 5e-7 once did: "0.000000").
  auto n = [](double v) { return formatShortest(v); };
  std::string s = std::string(toString(f.type)) + "@" + f.joint + "=" + n(f.value);
  if (f.onset > 0.0) s += " from " + n(f.onset) + " s";
  if (f.progression != Progression::Step) {
    s += std::string(f.progression == Progression::Linear ? " linear" : " exponential") + " over " + n(f.ramp_time) +
         " s";
    if (f.progression == Progression::Exponential) s += " at rate " + n(f.rate) + " 1/s";
    s += " (" + std::to_string(f.steps) + " steps)";
  }
  if (f.intermittent()) {
    if (f.type == FaultType::SensorSpike) s += " width " + n(f.width) + " s";
    if (f.period > 0.0) s += " every " + n(f.period) + " s" + (f.count > 0 ? " x" + std::to_string(f.count) : "");
  }
  if (f.type == FaultType::BearingRipple) s += " order " + n(f.order);
  return s;
}

void checkFault(const Fault& f) {
  const double v = f.value;
  if (!std::isfinite(v)) bad(f, "the severity must be finite");
  if (factorType(f.type) && !(v > 0.0 && v <= 100.0)) bad(f, "the factor must be > 0 and <= 100");
  switch (f.type) {
    case FaultType::BacklashAdd:
      if (!(v >= 0.0 && v <= 0.5)) bad(f, "the added backlash must be >= 0 and <= 0.5 rad");
      break;
    case FaultType::SensorBias:
    case FaultType::SensorSpike:
      if (!(std::abs(v) <= M_PI)) bad(f, "the offset must be within ±π rad");
      break;
    case FaultType::SensorDropout:
    case FaultType::SensorStuck:
      if (!(v > 0.0)) bad(f, "the episode length must be > 0 s");
      break;
    case FaultType::BearingRipple:
      if (!(v >= 0.0)) bad(f, "the ripple amplitude must be >= 0 N·m");
      if (!(f.order > 0.0) || !std::isfinite(f.order)) bad(f, "order: expected a number > 0 (cycles per revolution)");
      break;
    default: break;
  }
  if (!(f.onset >= 0.0) || !std::isfinite(f.onset)) bad(f, "onset: expected a time >= 0 s");
  if (f.progression != Progression::Step) {
    if (f.intermittent()) bad(f, "an intermittent sensor fault has no progression (it acts in episodes)");
    if (!(f.ramp_time > 0.0) || !std::isfinite(f.ramp_time)) bad(f, "ramp_time: expected a duration > 0 s");
    if (f.steps < 1 || f.steps > 100000) bad(f, "steps: expected 1 to 100000 parameter updates");
  }
  if (f.progression == Progression::Exponential && !(f.rate > 0.0 && f.rate * f.ramp_time <= 700.0))
    bad(f, "rate: expected λ > 0 1/s with λ·ramp_time <= 700");
  if (f.intermittent()) {
    if (!(f.period >= 0.0) || !std::isfinite(f.period)) bad(f, "period: expected a time >= 0 s (0: one episode)");
    if (f.count < 0) bad(f, "count: expected a number of episodes >= 0 (0: unlimited)");
    if (f.type == FaultType::SensorSpike && !(f.width > 0.0 && std::isfinite(f.width)))
      bad(f, "width: expected a spike length > 0 s");
    const double length = f.type == FaultType::SensorSpike ? f.width : v;
    if (f.period > 0.0 && length > f.period) bad(f, "an episode must not be longer than the period");
  }
}

double faultProgress(const Fault& f, double t) {
  const double tau = t - f.onset;
  if (tau < 0.0) return 0.0;
  if (f.progression == Progression::Step || tau >= f.ramp_time) return 1.0;
  if (f.progression == Progression::Linear) return tau / f.ramp_time;
  // p = (e^{λτ} − 1)/(e^{λT} − 1); for λT below 1e-12 its limit τ/T (within λT/2 relative): expm1 of a rate near
  // the smallest double underflows to 0/0.
  if (f.rate * f.ramp_time < 1e-12) return tau / f.ramp_time;
  return std::expm1(f.rate * tau) / std::expm1(f.rate * f.ramp_time);
}

double faultValue(const Fault& f, double t) {
  const double nominal = factorType(f.type) ? 1.0 : 0.0;
  return nominal + (f.value - nominal) * faultProgress(f, t);
}

double scheduledFaultValue(const Fault& f, double t) {
  if (f.intermittent()) return f.value;
  if (f.progression == Progression::Step || t < f.onset || t >= f.onset + f.ramp_time) return faultValue(f, t);
  // Step k holds [t_k, t_k+1) with t_k = onset + T·k/steps computed exactly as faultEvents() does, so that the value
  // changes at the event itself and not one rounding error later.
  auto at = [&](int k) { return f.onset + f.ramp_time * k / f.steps; };
  int k = static_cast<int>(std::clamp(std::floor((t - f.onset) * f.steps / f.ramp_time), 0.0, f.steps - 1.0));
  while (k + 1 < f.steps && at(k + 1) <= t) ++k;
  while (k > 0 && at(k) > t) --k;
  return faultValue(f, f.onset + f.ramp_time * (k + 0.5) / f.steps);
}

std::vector<double> faultEvents(const Fault& f, double t_end) {
  std::vector<double> out;
  auto add = [&](double t) {
    if (t > 0.0 && t < t_end) out.push_back(t);
  };
  if (f.intermittent()) {
    const double length = f.type == FaultType::SensorSpike ? f.width : f.value;
    // The number of episodes that start before t_end, counted before any is listed: a tiny period (1e-9 s) must be
    // refused here, not fill memory with 10^10 edges.
    if (f.period > 0.0 && t_end > f.onset) {
      double episodes = std::ceil((t_end - f.onset) / f.period);
      if (f.count > 0) episodes = std::min(episodes, static_cast<double>(f.count));
      if (!(2.0 * episodes <= static_cast<double>(kMaxFaultEvents)))
        throw InputError("fault " + describe(f) + ": " + formatNumber(episodes, 3) + " episodes in " +
                         formatNumber(t_end) + " s (every " + formatNumber(f.period) + " s) give more than " +
                         std::to_string(kMaxFaultEvents) +
                         " time events, each a restart of the integrator; give a longer period or a count");
    }
    for (long k = 0;; ++k) {
      if (f.count > 0 && k >= f.count) break;
      const double start = f.onset + static_cast<double>(k) * f.period;
      if (start >= t_end || (f.period <= 0.0 && k > 0)) break;
      add(start);
      add(start + length);
    }
    return out;
  }
  add(f.onset);
  if (f.progression != Progression::Step)
    for (int k = 1; k <= f.steps; ++k) add(f.onset + f.ramp_time * k / f.steps);
  return out;
}

bool faultEpisode(const Fault& f, double t, long* episode) {
  if (!f.intermittent() || t < f.onset) return false;
  const double length = f.type == FaultType::SensorSpike ? f.width : f.value;
  long k = 0;
  if (f.period > 0.0) {
    k = static_cast<long>(std::floor((t - f.onset) / f.period));
    if (f.count > 0 && k >= f.count) return false;
  }
  const double start = f.onset + static_cast<double>(k) * f.period;
  if (t - start >= length) return false;
  if (episode) *episode = k;
  return true;
}

bool faultApplies(const DriveSpec& drive, FaultType type) { return refusal(drive, type).empty(); }

void applyFault(DriveSpec& d, const Fault& f, double value) {
  checkFault(f);
  if (std::isnan(value)) value = f.value;
  const std::string why = refusal(d, f.type);
  if (!why.empty()) notApplicable(f, why);
  // The parameter faults act on every parameter of their role in the components' tables (a new, validated component).
  const drive::ParameterRole role = roleOf(f.type);
  const bool add = f.type == FaultType::BacklashAdd;
  switch (f.type) {
    case FaultType::GearStiffnessScale:
    case FaultType::BacklashAdd:
      d.transmission =
          d.transmission->withParameters(drive::roleChanges(d.transmission->parameters(), role, value, add));
      break;
    case FaultType::CoulombFrictionScale:
    case FaultType::Sigma0Scale:
      d.friction = d.friction->withParameters(drive::roleChanges(d.friction->parameters(), role, value, add));
      break;
    case FaultType::TorqueConstantScale:
      d.motor = drive::withParameters(d.motor, drive::roleChanges(drive::parameterTable(d.motor), role, value, add));
      break;
    case FaultType::SensorBias: d.sensors.joint_bias += value; break;
    case FaultType::SensorDropout:
    case FaultType::SensorStuck:
    case FaultType::SensorSpike:
    case FaultType::BearingRipple: break;  // act in the right-hand side (RobotSystem::setFaults)
  }
}

drive::ParameterChanges tableFaultChanges(const std::vector<drive::ParameterInfo>& table, const Fault& f,
                                          const std::string& component, double value) {
  checkFault(f);
  if (std::isnan(value)) value = f.value;
  if (!f.parameterFault() || f.type == FaultType::SensorBias)
    notApplicable(f, component + " (" + toString(f.type) +
                         " needs the sensors and controllers of a robot with drives, experiment type tracking)");
  if (f.timeVarying())
    notApplicable(f, component + " with a time law (it takes constant faults, acting from t = 0; onsets and "
                                 "progressions need a robot with drives, experiment type tracking)");
  const drive::ParameterRole role = roleOf(f.type);
  if (!drive::hasRole(table, role))
    notApplicable(f, component + ", which has no " + drive::roleName(role) + " parameter");
  return drive::roleChanges(table, role, value, f.type == FaultType::BacklashAdd);
}

void applyFaults(std::vector<DriveSpec>& drives, const std::vector<Fault>& faults) {
  for (const auto& f : faults) {
    bool found = false;
    for (auto& d : drives)
      if (d.joint == f.joint) {
        if (!f.timeVarying()) applyFault(d, f);  // the others act during the run (RobotSystem::setFaults checks them)
        found = true;
      }
    if (!found) throw InputError("fault " + describe(f) + ": no drive moves joint '" + f.joint + "'");
  }
}

}  // namespace jointsim::systems
