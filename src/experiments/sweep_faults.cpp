// The faults of a sweep file (docs/batch.md, systems/faults.hpp): type, joint, severity and time law.
#include <string>

#include "experiments/sweep_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/systems/faults.hpp"

namespace jointsim::experiments::detail {

using io::YamlValue;

// The time law of a fault (onset, progression, episodes, ripple order) from the keys of `n`; checked with its
// severity (systems::checkFault), an error located at the node.

void readTimeLaw(const YamlValue& n, systems::Fault& f) {
  f.onset = n["onset"].asDouble(0.0, "an onset time in s");
  const std::string p = n["progression"].asString("step", "step, linear or exponential");
  if (p == "linear")
    f.progression = systems::Progression::Linear;
  else if (p == "exponential")
    f.progression = systems::Progression::Exponential;
  else if (p != "step")
    n["progression"].failExpected("step, linear or exponential");
  f.ramp_time = n["ramp_time"].asDouble(0.0, "a ramp time in s");
  f.rate = n["rate"].asDouble(0.0, "a rate in 1/s");
  if (n["steps"].defined()) {  // checked here, with the value as written (a clamp once reported 10^9 as 1000000)
    const long steps = n["steps"].asInt("a number of steps");
    if (steps < 1 || steps > 100000)
      n["steps"].fail("expected 1 to 100000 parameter updates, got " + std::to_string(steps));
    f.steps = static_cast<int>(steps);
  }
  f.period = n["period"].asDouble(0.0, "a period in s");
  if (n["count"].defined()) {
    const long count = n["count"].asInt("a number of episodes");
    if (count < 0 || count > 1000000000L)
      n["count"].fail("expected a number of episodes from 0 (unlimited) to 1e9, got " + std::to_string(count));
    f.count = static_cast<int>(count);
  }
  f.width = n["width"].asDouble(f.width, "a spike width in s");
  f.order = n["order"].asDouble(1.0, "an order (cycles per revolution)");
}

void checkAt(const YamlValue& n, const systems::Fault& f) {
  try {
    systems::checkFault(f);
  } catch (const InputError& e) {
    n.fail(e.what());
  }
}

systems::FaultType readFaultType(const YamlValue& t) {
  try {
    return systems::faultTypeFromString(t.asString("a fault type"));
  } catch (const InputError& e) {
    t.fail(e.what());
  }
}

systems::Fault readFault(const YamlValue& n) {
  n.expectMap("a fault {type, joint, value}");
  n.allowKeys({"type", "joint", "value", JOINTSIM_TIME_LAW_KEYS});
  systems::Fault f;
  f.type = readFaultType(n.required("type", "a fault type"));
  f.joint = n.required("joint", "the joint whose drive is affected").asString("a joint name");
  f.value = n.required("value", "the fault's severity").asDouble("a number");
  readTimeLaw(n, f);
  checkAt(n, f);
  return f;
}

}  // namespace jointsim::experiments::detail
