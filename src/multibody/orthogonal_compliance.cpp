#include "jointsim/multibody/orthogonal_compliance.hpp"

#include <set>

#include <Eigen/Geometry>

#include "jointsim/common/error.hpp"

namespace jointsim::multibody {

Model withOrthogonalCompliance(const Model& model, const std::vector<std::string>& joints) {
  std::set<int> compliant;
  for (const auto& name : joints) {
    const int j = model.jointIndex(name);
    if (model.joint_types[static_cast<size_t>(j)] != JointType::Revolute)
      throw InputError("orthogonal compliance: joint '" + name + "' is not revolute");
    compliant.insert(j);
  }
  ModelBuilder b(model.name, model.base_name);
  b.setGravity(model.gravity);
  std::set<std::string> link_names(model.body_names.begin(), model.body_names.end());
  link_names.insert(model.base_name);
  for (int i = 0; i < model.nq; ++i) {
    const auto k = static_cast<size_t>(i);
    const std::string parent =
        model.parents[k] < 0 ? model.base_name : model.body_names[static_cast<size_t>(model.parents[k])];
    JointSpec js;
    js.name = model.joint_names[k];
    js.type = model.joint_types[k];
    js.origin = model.joint_placements[k];
    js.axis = model.axes[k];
    js.armature = model.armature.size() > i ? model.armature[i] : 0.0;
    js.limits = model.limits[k];
    if (!compliant.count(i)) {
      b.addLink(parent, js, model.body_names[k], model.inertias[k]);
      continue;
    }
    // getOrthVectors ([Olsson2017, A.15]).
    const Eigen::Vector3d n = model.axes[k].normalized();
    Eigen::Vector3d u;
    if (n.x() == 0.0)
      u = Eigen::Vector3d::UnitX().cross(n);
    else if (n.y() == 0.0)
      u = Eigen::Vector3d::UnitY().cross(n);
    else
      u = Eigen::Vector3d::UnitZ().cross(n);
    u.normalize();
    const Eigen::Vector3d v = n.cross(u);
    const std::string body = model.body_names[k];
    const std::string a = body + "__orth_a", c = body + "__orth_b";
    if (link_names.count(a) || link_names.count(c))
      throw InputError("orthogonal compliance: link name '" + a + "' is taken");
    b.addLink(parent, js, a, BodyInertia{});
    JointSpec ju;
    ju.name = js.name + "_orth_u";
    ju.axis = u;
    b.addLink(a, ju, c, BodyInertia{});
    JointSpec jv;
    jv.name = js.name + "_orth_v";
    jv.axis = v;
    b.addLink(c, jv, body, model.inertias[k]);
  }
  for (const auto& f : model.frames) {
    if (link_names.count(f.name)) continue;  // link frames are recreated by addLink
    b.addFrame(f.name, f.joint < 0 ? model.base_name : model.body_names[static_cast<size_t>(f.joint)], f.placement);
  }
  if (!model.tip_frame.empty()) b.setTipFrame(model.tip_frame);
  return b.build();
}

}  // namespace jointsim::multibody
