// URDF text: the depth and size check, urdfdom (TinyXML) and the model builder; then the dynamics of the model.
#include <Eigen/Core>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/robot_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  try {
    const multibody::Model model =
        multibody::loadUrdfString(std::string(reinterpret_cast<const char*>(data), size), "fuzz.urdf");
    multibody::Data d(model);
    const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(model.nq, -0.5, 0.7);
    const Eigen::VectorXd qd = Eigen::VectorXd::Constant(model.nq, 0.3);
    const Eigen::VectorXd tau = multibody::rnea(model, d, q, qd, qd);
    multibody::aba(model, d, q, qd, tau);
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
