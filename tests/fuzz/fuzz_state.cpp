// Saved simulator states (sim::Simulator::loadState, sim::Snapshot::fromBytes and the plants' State::load): the input
// picks a plant and either is the byte string itself or edits a valid saved state of that plant (bytes overwritten,
// cut short, repeated, counts and tags changed). The plants are the UR5 twin under 20 kHz sampled control with a
// voltage command port and time-varying faults (inputs, controllers, encoder memory, the noise generator's text,
// fault values, stuck sensors), the drive chain of config/experiments/msl_friction.yaml (friction modes) and the
// RobotR3 robot (modes per axis).
//
// Oracle: loadState either succeeds or throws jointsim::InputError, and a refused load leaves the simulator's time and
// state as they were; after a successful load, an advance of at most 1 ms (at most 2000 solver steps) either
// succeeds or throws jointsim::Error (a state of garbage values may make the solver fail, never crash).
#include <memory>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/sim/simulator.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace {

namespace fuzz = jointsim::fuzz;

struct Subject {
  std::shared_ptr<jointsim::experiments::Experiment> experiment;
  std::unique_ptr<jointsim::sim::Simulator> sim;
  std::string valid;  // a saved state after a few steps
};

std::vector<Subject>& subjects() {
  static std::vector<Subject> all = [] {
    std::vector<Subject> s;
    const std::string dir = (fuzz::workspace() / "config" / "experiments").string();
    auto add = [&](const std::string& file, std::vector<std::string> overrides) {
      Subject x;
      x.experiment = jointsim::experiments::loadExperiment(dir + "/" + file, overrides);
      x.sim = jointsim::experiments::makeSimulator(x.experiment);
      if (const auto* robot = dynamic_cast<const jointsim::systems::RobotSystem*>(&x.sim->plant())) {
        robot->setCommandPort(x.sim->plantState(), 1, jointsim::systems::CommandPort::Voltage);
        robot->setCommand(x.sim->plantState(), 1, 2.0);
        robot->setExternalWrench(x.sim->plantState(), robot->model().tip_frame,
                                 (Eigen::Matrix<double, 6, 1>() << 0, 0, -5, 0, 0, 0).finished());
      }
      x.sim->advance(2e-3);
      x.valid = x.sim->saveState();
      s.push_back(std::move(x));
    };
    add("ur5_excitation.yaml", {"+control.rate=20000"});
    add("msl_friction.yaml", {});
    add("robotr3_full_robot.yaml", {});
    return s;
  }();
  return all;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Bytes in(data, size);
  Subject& x = subjects()[in.pick(subjects().size())];
  std::string bytes;
  if (in.flag()) {
    bytes = in.rest();
  } else {  // edits of a valid state
    bytes = x.valid;
    for (int edits = 1 + static_cast<int>(in.pick(4)); edits > 0 && !bytes.empty(); --edits) {
      const size_t at = in.u32() % bytes.size();
      switch (in.pick(5)) {
        case 0: bytes[at] = static_cast<char>(in.byte()); break;
        case 1: bytes.resize(at); break;
        case 2: bytes.insert(at, in.text(1 + in.pick(16))); break;
        case 3:
          for (size_t k = 0; k < 8 && at + k < bytes.size(); ++k) bytes[at + k] = static_cast<char>(0xFF);
          break;
        default: bytes.erase(at, 1 + in.pick(16)); break;
      }
    }
  }
  const double t = x.sim->time();
  const Eigen::VectorXd y = x.sim->state();
  try {
    x.sim->loadState(bytes);
  } catch (const jointsim::InputError& e) {
    fuzz::note(e);
    if (x.sim->time() != t || x.sim->state() != y) std::abort();  // a refused load changed the simulator
    return 0;
  }
  jointsim::sim::AdvanceLimits limits;
  limits.max_steps = 2000;
  x.sim->setLimits(limits);
  try {
    x.sim->advance(1e-3);
  } catch (const jointsim::Error& e) {
    fuzz::note(e);
  }
  x.sim->loadState(x.valid);  // back to a known state for the next input (must load)
  return 0;
}
