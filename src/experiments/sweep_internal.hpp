#pragma once
// Internal to the experiments layer: reading the faults of a sweep file (sweep_faults.cpp), shared by the sweep reader.
#include "jointsim/io/yaml.hpp"
#include "jointsim/systems/faults.hpp"

/// The keys of a fault's time law, allowed in a fault mapping besides its own.
#define JOINTSIM_TIME_LAW_KEYS "onset", "progression", "ramp_time", "rate", "steps", "period", "count", "width", "order"

namespace jointsim::experiments::detail {

/// The time law of a fault (onset, progression, episodes, ripple order) from the keys of `n`.
void readTimeLaw(const io::YamlValue& n, systems::Fault& f);
/// Checks the fault with its severity (systems::checkFault), an error located at `n`.
void checkAt(const io::YamlValue& n, const systems::Fault& f);
/// A fault type by its YAML name, an error located at `t`.
systems::FaultType readFaultType(const io::YamlValue& t);
/// One fault mapping {type, joint, value, time law...}.
systems::Fault readFault(const io::YamlValue& n);

}  // namespace jointsim::experiments::detail
