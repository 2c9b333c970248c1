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
  /// Whether a port is driven by its profile now (not held): the inputs then depend on time.
  bool dependsOnTime(const HeldInputs& in) const {
    for (std::size_t k = 0; k < profile.size(); ++k)
      if (profile[k] && !in.held[k]) return true;
    return false;
  }
  /// The profiles' breakpoints in (0, t_end), to add to a plant's time events.
  std::vector<double> breakpoints(double t_end) const;
};

/// Base of a plant whose inputs are a fixed list of independent ports (no groups) held in its State's HeldInputs and
/// optionally driven by InputProfiles: the one implementation of the Plant input methods for such plants. A derived
/// plant fills `ports_` in its constructor (then `profiles_.resize(ports_.size())`), keeps a HeldInputs of that size
/// in its State, returns it from heldInputs(), and reads its ports in the right-hand side through
/// `profiles_.value(held, k, t)` and `profiles_.active(held, k)`.
class HeldInputPlant : public Plant {
 public:
  std::vector<InputPort> inputPorts() const override { return ports_; }
  /// Holds `value` at `port`: InputError (nothing changed) for a port out of range, a value out of its range.
  void setInput(PlantState& state, int port, double value) const override;
  /// The value held at `port` (0 until set and after a release).
  double input(const PlantState& state, int port) const override;
  /// In effect: held, driven by a profile, or a port that always acts (alwaysActive).
  bool inputActive(const PlantState& state, int port) const override;
  /// Port `port` driven by `profile` from the start of every run (only before a simulator uses the plant).
  void setInputProfile(int port, const control::Profile& profile) override;
  /// Port `port` no longer held: back to its profile, or to the model's own source.
  void releaseInput(PlantState& state, int port) const override;
  /// The model's own time events (modelTimeEvents()) followed by the profiles' breakpoints in (0, t_end): final, so
  /// that no model can leave its profiles' jumps out.
  std::vector<double> timeEvents(double t_end) const final;

 protected:
  /// The HeldInputs in `state` (a state of this plant; InputError for another plant's, as Plant::own).
  virtual HeldInputs& heldInputs(PlantState& state) const = 0;
  virtual const HeldInputs& heldInputs(const PlantState& state) const = 0;
  /// Whether `port` acts whatever is held (an input that adds to the model's forces, 0 until set) rather than
  /// replacing a source of the model (a command in place of a controller's, in effect once set). Default: every port.
  virtual bool alwaysActive(int /*port*/) const { return true; }
  /// The model's own input discontinuities in (0, t_end) [s] (its paths, sources; any order): default none.
  virtual std::vector<double> modelTimeEvents(double /*t_end*/) const { return {}; }

  std::vector<InputPort> ports_;  ///< the plant's inputs (set in its constructor)
  InputProfiles profiles_;        ///< profiles driving the ports (setInputProfile)
};

}  // namespace jointsim::sim
