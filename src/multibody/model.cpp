#include "jointsim/multibody/model.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "jointsim/common/error.hpp"
#include "jointsim/multibody/data.hpp"

namespace jointsim::multibody {

Eigen::Matrix3d rotationFromRpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

const char* toString(JointType type) {
  switch (type) {
    case JointType::Revolute: return "revolute";
    case JointType::Prismatic: return "prismatic";
    case JointType::Fixed: return "fixed";
  }
  return "?";
}

// ------------------------------------------------------------------------------------ BodyInertia

std::string BodyInertia::validate() const {
  std::ostringstream os;
  if (!std::isfinite(mass) || mass < 0.0) {
    os << "mass must be a finite number >= 0 kg, got " << mass;
    return os.str();
  }
  if (!com.allFinite()) return "centre of mass must be finite";
  if (!inertia.allFinite()) return "inertia tensor must be finite";
  const double scale = std::max(inertia.cwiseAbs().maxCoeff(), 1e-300);
  if ((inertia - inertia.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) return "inertia tensor must be symmetric";
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia).eigenvalues();
  if (mass > 0.0 && ev.minCoeff() <= 0.0) {
    os << "inertia tensor about the CoM must be positive definite for a body with mass > 0, "
          "its eigenvalues are ["
       << ev(0) << ", " << ev(1) << ", " << ev(2) << "] kg·m²";
    return os.str();
  }
  // Principal moments of a real body satisfy I_a + I_b >= I_c (equality for a planar body).
  if (mass > 0.0 && ev(0) + ev(1) < ev(2) * (1.0 - 1e-9)) {
    os << "principal moments of inertia [" << ev(0) << ", " << ev(1) << ", " << ev(2)
       << "] kg·m² violate the triangle inequality I1 + I2 >= I3 of a rigid body";
    return os.str();
  }
  if (mass == 0.0 && ev.minCoeff() < -1e-14 * scale) {
    os << "inertia tensor must be positive semi-definite, its eigenvalues are [" << ev(0) << ", " << ev(1) << ", "
       << ev(2) << "] kg·m²";
    return os.str();
  }
  return {};
}

BodyInertia BodyInertia::transformed(const Placement& X) const {
  return {mass, X.act(com), X.R * inertia * X.R.transpose()};
}

BodyInertia BodyInertia::operator+(const BodyInertia& o) const {
  const double m = mass + o.mass;
  if (m <= 0.0) return {0.0, Eigen::Vector3d::Zero(), inertia + o.inertia};
  const Eigen::Vector3d c = (mass * com + o.mass * o.com) / m;
  // Parallel-axis theorem: I_c = Σ I_k + m_k (|d_k|² 1 − d_k d_kᵀ), d_k = c_k − c.
  auto shift = [&](double mk, const Eigen::Vector3d& ck) -> Eigen::Matrix3d {
    const Eigen::Vector3d d = ck - c;
    return mk * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  };
  return {m, c, inertia + o.inertia + shift(mass, com) + shift(o.mass, o.com)};
}

// ------------------------------------------------------------------------------------ Model

namespace {
template <class Names>
std::string listNames(const Names& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}
}  // namespace

int Model::jointIndex(const std::string& joint_name) const {
  for (int i = 0; i < nq; ++i)
    if (joint_names[static_cast<size_t>(i)] == joint_name) return i;
  throw InputError("unknown joint '" + joint_name + "' in robot '" + name +
                   "'; known joints: " + listNames(joint_names));
}

bool Model::hasFrame(const std::string& frame_name) const {
  for (const auto& f : frames)
    if (f.name == frame_name) return true;
  return false;
}

int Model::frameIndex(const std::string& frame_name) const {
  for (size_t i = 0; i < frames.size(); ++i)
    if (frames[i].name == frame_name) return static_cast<int>(i);
  std::vector<std::string> names;
  for (const auto& f : frames) names.push_back(f.name);
  throw InputError("unknown frame '" + frame_name + "' in robot '" + name + "'; known frames: " + listNames(names));
}

void Model::updateDerived() {
  const auto n = static_cast<size_t>(nq);
  mass.resize(n);
  first_moment.resize(n);
  inertia_origin.resize(n);
  axis_kind.resize(n);
  for (size_t i = 0; i < n; ++i) {
    axis_kind[i] = 3;
    for (int a = 0; a < 3; ++a)
      if (axes[i] == Eigen::Vector3d::Unit(a)) axis_kind[i] = a;
    const BodyInertia& I = inertias[i];
    mass[i] = I.mass;
    first_moment[i] = I.mass * I.com;
    const Eigen::Matrix3d C = skew(I.com);
    inertia_origin[i] = I.inertia - I.mass * C * C;
  }
}

// ------------------------------------------------------------------------------------ ModelBuilder

ModelBuilder::ModelBuilder(std::string robot_name, std::string base_link) {
  model_.name = std::move(robot_name);
  model_.base_name = base_link;
  links_.push_back({base_link, LinkRecord{-1, Placement::Identity(), 0}});
  model_.frames.push_back({base_link, -1, Placement::Identity()});
  tip_link_ = base_link;
}

const ModelBuilder::LinkRecord* ModelBuilder::findLink(const std::string& name) const {
  for (const auto& [n, rec] : links_)
    if (n == name) return &rec;
  return nullptr;
}

ModelBuilder& ModelBuilder::addLink(const std::string& parent_link, const JointSpec& joint,
                                    const std::string& child_name, const BodyInertia& inertia) {
  const std::string where = "robot '" + model_.name + "', joint '" + joint.name + "'";
  if (links_.size() >= kMaxLinks)
    throw InputError(where + ": more than " + std::to_string(kMaxLinks) + " links: not a robot this library models");
  const LinkRecord* parent = findLink(parent_link);
  if (parent == nullptr) throw InputError(where + ": parent link '" + parent_link + "' is not defined (yet)");
  if (findLink(child_name) != nullptr || model_.hasFrame(child_name))
    throw InputError(where + ": link or frame '" + child_name + "' is defined twice");
  for (const auto& n : model_.joint_names)
    if (n == joint.name) throw InputError(where + ": joint name defined twice");
  if (const std::string why = inertia.validate(); !why.empty())
    throw InputError("robot '" + model_.name + "', link '" + child_name + "': " + why);
  if (!(joint.armature >= 0.0) || !std::isfinite(joint.armature))
    throw InputError(where + ": armature must be a finite number >= 0");
  if (!joint.origin.R.allFinite() || !joint.origin.p.allFinite()) throw InputError(where + ": origin must be finite");
  if (!(joint.limits.lower <= joint.limits.upper) || std::isnan(joint.limits.velocity) ||
      std::isnan(joint.limits.effort))
    throw InputError(where + ": limits: expected lower <= upper (got [" + std::to_string(joint.limits.lower) + ", " +
                     std::to_string(joint.limits.upper) + "]) and no NaN");

  const Placement parent_placement = parent->placement;  // parent link in its joint frame
  const int parent_joint = parent->joint;
  const int depth = parent->depth + 1;
  LinkRecord rec{};
  if (joint.type == JointType::Fixed) {
    rec = {parent_joint, parent_placement * joint.origin, depth};
    if (parent_joint >= 0) {
      auto& body = model_.inertias[static_cast<size_t>(parent_joint)];
      body = body + inertia.transformed(rec.placement);
    }
  } else {
    const double axis_norm = joint.axis.norm();
    if (!std::isfinite(axis_norm) || axis_norm < 1e-12)
      throw InputError(where + ": joint axis must be a non-zero finite vector");
    model_.joint_names.push_back(joint.name);
    model_.body_names.push_back(child_name);
    model_.joint_types.push_back(joint.type);
    model_.parents.push_back(parent_joint);
    model_.joint_placements.push_back(parent_placement * joint.origin);
    model_.axes.push_back(joint.axis / axis_norm);
    model_.inertias.push_back(inertia);
    model_.limits.push_back(joint.limits);
    model_.armature.conservativeResize(model_.nq + 1);
    model_.armature(model_.nq) = joint.armature;
    rec = {model_.nq, Placement::Identity(), depth};
    ++model_.nq;
  }
  links_.push_back({child_name, rec});
  model_.frames.push_back({child_name, rec.joint, rec.placement});
  if (depth > tip_depth_) {
    tip_depth_ = depth;
    tip_link_ = child_name;
  }
  return *this;
}

ModelBuilder& ModelBuilder::addFrame(const std::string& name, const std::string& link, const Placement& placement) {
  const LinkRecord* rec = findLink(link);
  if (rec == nullptr)
    throw InputError("robot '" + model_.name + "', frame '" + name + "': link '" + link + "' is not defined");
  if (model_.hasFrame(name)) throw InputError("robot '" + model_.name + "': frame '" + name + "' is defined twice");
  model_.frames.push_back({name, rec->joint, rec->placement * placement});
  return *this;
}

ModelBuilder& ModelBuilder::setGravity(const Eigen::Vector3d& gravity) {
  if (!gravity.allFinite()) throw InputError("robot '" + model_.name + "': gravity must be finite");
  model_.gravity = gravity;
  return *this;
}

ModelBuilder& ModelBuilder::setTipFrame(const std::string& frame) {
  if (!model_.hasFrame(frame))
    throw InputError("robot '" + model_.name + "': tip frame '" + frame + "' is not defined");
  tip_override_ = frame;
  return *this;
}

Model ModelBuilder::build() const {
  Model m = model_;
  m.tip_frame = tip_override_.empty() ? tip_link_ : tip_override_;
  if (m.nq == 0) throw InputError("robot '" + m.name + "' has no movable joint");
  m.updateDerived();
  return m;
}

// ------------------------------------------------------------------------------------ Data

Data::Data(const Model& model)
    : nq(model.nq),
      liMi(static_cast<size_t>(model.nq)),
      oMi(static_cast<size_t>(model.nq)),
      oMf(model.frames.size()),
      v(static_cast<size_t>(model.nq), Vector6d::Zero()),
      a(static_cast<size_t>(model.nq), Vector6d::Zero()),
      f(static_cast<size_t>(model.nq), Vector6d::Zero()),
      c(static_cast<size_t>(model.nq), Vector6d::Zero()),
      IA(static_cast<size_t>(model.nq), Matrix6d::Zero()),
      pA(static_cast<size_t>(model.nq), Vector6d::Zero()),
      U(static_cast<size_t>(model.nq), Vector6d::Zero()),
      D(Eigen::VectorXd::Zero(model.nq)),
      u(Eigen::VectorXd::Zero(model.nq)),
      Yc_m(static_cast<size_t>(model.nq), 0.0),
      Yc_h(static_cast<size_t>(model.nq), Eigen::Vector3d::Zero()),
      Yc_I(static_cast<size_t>(model.nq), Eigen::Matrix3d::Zero()),
      tau(Eigen::VectorXd::Zero(model.nq)),
      g(Eigen::VectorXd::Zero(model.nq)),
      nle(Eigen::VectorXd::Zero(model.nq)),
      ddq(Eigen::VectorXd::Zero(model.nq)),
      M(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      llt(model.nq),
      J(Matrix6Xd::Zero(6, model.nq)),
      zeros(Eigen::VectorXd::Zero(model.nq)),
      dtau_dq(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      dtau_dqd(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      ddq_dq(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      ddq_dqd(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      Minv(Eigen::MatrixXd::Zero(model.nq, model.nq)),
      oS(static_cast<size_t>(model.nq), Vector6d::Zero()),
      ov(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oa(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oF(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oh(static_cast<size_t>(model.nq), Vector6d::Zero()),
      ou(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oc(static_cast<size_t>(model.nq), Vector6d::Zero()),
      odS(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oP(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oDa(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oDF(static_cast<size_t>(model.nq), Vector6d::Zero()),
      oI(static_cast<size_t>(model.nq), Matrix6d::Zero()),
      oIc(static_cast<size_t>(model.nq), Matrix6d::Zero()),
      oB(static_cast<size_t>(model.nq), Matrix6d::Zero()) {
  // A factorisation (of the identity) so that the LLT's status is defined before the first use: copying a
  // Data copies it (reading an unset status is undefined behaviour).
  llt.compute(Eigen::MatrixXd::Identity(model.nq, model.nq));
}

}  // namespace jointsim::multibody
