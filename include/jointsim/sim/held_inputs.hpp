#pragma once
/// \file
/// The values a run holds at a plant's input ports (sim::InputPort): one value per port and whether it has been set.
/// A plant keeps one in its State (saved with it, so snapshots and saved states carry the inputs) and reads it in its
/// right-hand side: a held command replaces the model's own source (a profile, a controller) until released, a
/// disturbance input adds to the model's forces. The one place that checks a value against its port.

#include <cstddef>
#include <string>
#include <vector>

#include "jointsim/common/bytes.hpp"
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
  /// The held value of port k, or `otherwise` when it is not held.
  double valueOr(std::size_t k, double otherwise) const { return held[k] ? value[k] : otherwise; }
  /// InputError naming `plant` when k is no port index.
  void checkIndex(int k, const std::string& plant) const;
  void save(ByteWriter& out) const;
  /// Reads what save() wrote; the count must equal this object's (InputError otherwise, or for a non-finite value).
  void load(ByteReader& in);
};

}  // namespace jointsim::sim
