// Bridges from the experiment files to the drive components' own YAML readers.
#include "drive/friction_yaml.hpp"
#include "drive/strain_wave_gear_yaml.hpp"
#include "experiments/joint_rig_yaml.hpp"
#include "jointsim/drive/strain_wave_gear.hpp"

namespace jointsim::experiments::detail {

std::shared_ptr<const drive::Friction> readFrictionModel(const io::YamlValue& node) {
  return drive::frictionFromYaml(node);
}

std::shared_ptr<const drive::Transmission> readStrainWaveGear(const io::YamlValue& node) {
  return std::make_shared<drive::StrainWaveGear>(drive::swgParamsFromYaml(node));
}

}  // namespace jointsim::experiments::detail
