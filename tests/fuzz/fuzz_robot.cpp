// Robot description YAML (dh_hayati and tree conventions) and robot-with-drives YAML: load, then evaluate
// the dynamics of the model at a fixed state (every algorithm must accept any model the loader accepts).
#include <Eigen/Core>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

namespace {
void exercise(const jointsim::multibody::Model& model) {
  using namespace jointsim::multibody;
  Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(model.nq, -0.5, 0.7);
  const Eigen::VectorXd qd = Eigen::VectorXd::Constant(model.nq, 0.3);
  const Eigen::VectorXd tau = rnea(model, data, q, qd, qd);
  aba(model, data, q, qd, tau);
  crba(model, data, q);
  kineticEnergy(model, data, q, qd);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    exercise(multibody::loadRobotYamlString(text, "fuzz.yaml"));
  } catch (const Error& e) {
    fuzz::note(e);
  }
  // The same bytes as a robot-with-drives file beside the shipped robots (its `multibody:` may name them).
  const std::string path = fuzz::writeInput("config/robots/fuzz_drives.yaml", data, size);
  try {
    exercise(systems::loadRobotWithDrives(path).model());
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
