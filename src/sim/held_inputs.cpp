#include "jointsim/sim/held_inputs.hpp"

#include <cmath>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"

namespace jointsim::sim {

void HeldInputs::resize(std::size_t n) {
  value.assign(n, 0.0);
  held.assign(n, 0);
}

void HeldInputs::checkIndex(int k, const std::string& plant) const {
  if (k < 0 || static_cast<std::size_t>(k) >= value.size())
    throw InputError(plant + ": input " + std::to_string(k) + " out of range (it has " + std::to_string(value.size()) +
                     " inputs)");
}

bool HeldInputs::set(std::size_t k, double v, const std::vector<InputPort>& ports, const std::string& plant) {
  checkIndex(static_cast<int>(k), plant);
  const InputPort& p = ports[k];
  if (!std::isfinite(v) || v < p.min || v > p.max)
    throw InputError(plant + ": input " + p.name + ": expected a finite value in [" + formatNumber(p.min) + ", " +
                     formatNumber(p.max) + "] " + p.unit + ", got " + formatNumber(v));
  const bool changed = !held[k] || value[k] != v;
  value[k] = v;
  held[k] = 1;
  return changed;
}

bool HeldInputs::release(std::size_t k) {
  if (k >= held.size() || !held[k]) return false;
  held[k] = 0;
  value[k] = 0.0;
  return true;
}

void HeldInputs::save(ByteWriter& out) const {
  out.u64(value.size());
  for (std::size_t k = 0; k < value.size(); ++k) {
    out.boolean(held[k] != 0);
    out.f64(value[k]);
  }
}

void HeldInputs::load(ByteReader& in) {
  const std::uint64_t n = in.u64("input count");
  if (n != value.size())
    in.fail("input count: expected " + std::to_string(value.size()) + ", got " + std::to_string(n));
  for (std::size_t k = 0; k < value.size(); ++k) {
    held[k] = in.boolean("input held") ? 1 : 0;
    value[k] = in.f64("input value");
    if (!std::isfinite(value[k])) in.fail("input value: not finite");
  }
}

void InputProfiles::set(int k, const control::Profile& p, const std::vector<InputPort>& ports,
                        const std::string& plant) {
  if (k < 0 || static_cast<std::size_t>(k) >= profile.size())
    throw InputError(plant + ": input " + std::to_string(k) + " out of range (it has " +
                     std::to_string(profile.size()) + " inputs)");
  const InputPort& port = ports[static_cast<std::size_t>(k)];
  if (!port.group.empty())
    throw InputError(plant + ": input " + port.name + ": one of the group " + port.group + " takes no profile");
  profile[static_cast<std::size_t>(k)] = std::make_shared<const control::Profile>(p);
}

std::vector<double> InputProfiles::breakpoints(double t_end) const {
  std::vector<double> out;
  for (const auto& p : profile)
    if (p)
      for (double b : p->breakpoints(t_end)) out.push_back(b);
  return out;
}

void HeldInputPlant::setInput(PlantState& state, int port, double value) const {
  HeldInputs& in = heldInputs(state);
  in.checkIndex(port, name());
  if (in.set(static_cast<std::size_t>(port), value, ports_, name())) state.inputsChanged();
}

double HeldInputPlant::input(const PlantState& state, int port) const {
  const HeldInputs& in = heldInputs(state);
  in.checkIndex(port, name());
  return in.value[static_cast<std::size_t>(port)];
}

bool HeldInputPlant::inputActive(const PlantState& state, int port) const {
  const HeldInputs& in = heldInputs(state);
  in.checkIndex(port, name());
  return alwaysActive(port) || profiles_.active(in, static_cast<std::size_t>(port));
}

void HeldInputPlant::setInputProfile(int port, const control::Profile& profile) {
  checkConfigurable("setInputProfile");
  profiles_.set(port, profile, ports_, name());
}

void HeldInputPlant::releaseInput(PlantState& state, int port) const {
  HeldInputs& in = heldInputs(state);
  in.checkIndex(port, name());
  if (in.release(static_cast<std::size_t>(port))) state.inputsChanged();
}

std::vector<double> HeldInputPlant::timeEvents(double t_end) const {
  std::vector<double> events = modelTimeEvents(t_end);
  for (double b : profiles_.breakpoints(t_end)) events.push_back(b);
  return events;
}

}  // namespace jointsim::sim
