// Bridges from the experiment files to the drive components' own YAML readers.
#include "experiments/joint_rig_yaml.hpp"
#include "jointsim/common/error.hpp"

namespace jointsim::experiments::detail {

std::shared_ptr<const drive::Friction> readFrictionModel(const io::YamlValue& node) {
  node.fail("friction models are not available yet");
}

std::shared_ptr<const drive::Transmission> readStrainWaveGear(const io::YamlValue& node) {
  node.fail("the strain-wave gear is not available yet");
}

}  // namespace jointsim::experiments::detail
