#pragma once
/// \file
/// The values a run holds at a plant's input ports (sim::InputPort): one value per port and whether it has been set.
/// A plant keeps one in its State (saved with it, so snapshots and saved states carry the inputs) and reads it in its
/// right-hand side: a held command replaces the model's own source (a profile, a controller) until released, a
/// disturbance input adds to the model's forces. The one place that checks a value against its port.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "jointsim/common/bytes.hpp"
#include "jointsim/control/profile.hpp"
#include "jointsim/sim/plant.hpp"

namespace jointsim::sim {

struct HeldInputs {
  std::vector<double> value;  ///< per port, in the port's unit (0 until set)
  std::vector<char> held;     ///< per port: set since the start or the last release

  /// `n` ports, none held.
  void resize(std::size_t n);
  /// Sets port `k` of `ports` to v: InputError naming `plant`, the port and its range for a value that is not finite or
  /// out of range (nothing changed). Returns whether the value or its held flag changed (the caller then calls
  /// PlantState::inputsChanged()).
  bool set(std::size_t k, double v, const std::vector<InputPort>& ports, const std::string& plant);
  /// Port `k` no longer held (its value back to 0); whether that changed anything.
  bool release(std::size_t k);
  /// InputError naming `plant` when k is no port index.
  void checkIndex(int k, const std::string& plant) const;
  void save(ByteWriter& out) const;
  /// Reads what save() wrote; the count must equal this object's (InputError otherwise, or for a non-finite value).
  void load(ByteReader& in);
};

/// Profiles of time that drive input ports from the start of a run (Plant::setInputProfile): part of a plant's
/// configuration (constant during runs), read with the run's HeldInputs: a value set at a port holds it instead.
struct InputProfiles {
  std::vector<std::shared_ptr<const control::Profile>> profile;  ///< per port; null: none

  /// `n` ports, none with a profile.
  void resize(std::size_t n) { profile.assign(n, nullptr); }
  /// Port k (of `ports`) driven by `p`: InputError naming `plant` for a port out of range or of a group.
  void set(int k, const control::Profile& p, const std::vector<InputPort>& ports, const std::string& plant);
  /// Whether port k is in effect: held, or driven by a profile.
  bool active(const HeldInputs& in, std::size_t k) const { return in.held[k] || profile[k] != nullptr; }
  /// The value of port k at t: the held value, else its profile's, else 0 [the port's unit].
  double value(const HeldInputs& in, std::size_t k, double t) const {
    return in.held[k] ? in.value[k] : (profile[k] ? profile[k]->value(t) : 0.0);
  }
  /// The profiles' breakpoints in (0, t_end), to add to a plant's time events.
  std::vector<double> breakpoints(double t_end) const;
};

}  // namespace jointsim::sim
