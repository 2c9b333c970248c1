#include "jointsim/multibody/robot_loader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Geometry>
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::multibody {
namespace {

// ----------------------------------------------------------------------------------------- URDF

// Collects urdfdom's console_bridge messages so they go into the exception instead of stderr.
class CapturingOutputHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages += (messages.empty() ? "" : "; ") + text;
  }
  std::string messages;
};

struct ScopedOutputCapture {
  CapturingOutputHandler handler;
  ScopedOutputCapture() { console_bridge::useOutputHandler(&handler); }
  ~ScopedOutputCapture() { console_bridge::restorePreviousOutputHandler(); }
};

Placement fromUrdfPose(const urdf::Pose& pose) {
  Placement X;
  double qx, qy, qz, qw;
  pose.rotation.getQuaternion(qx, qy, qz, qw);
  X.R = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  X.p = {pose.position.x, pose.position.y, pose.position.z};
  return X;
}

BodyInertia fromUrdfInertial(const urdf::Link& link) {
  BodyInertia I;
  if (!link.inertial) return I;
  const urdf::Inertial& in = *link.inertial;
  const Placement X = fromUrdfPose(in.origin);
  Eigen::Matrix3d Ic;
  Ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  I.mass = in.mass;
  I.com = X.p;
  I.inertia = X.R * Ic * X.R.transpose();
  return I;
}

/// The file a URDF mesh name stands for: `file://` and absolute paths as they are, relative ones against the URDF's
/// folder, `package://PKG/REST` as DIR/PKG/REST for DIR in ROS_PACKAGE_PATH and in the URDF's folder and each of its
/// parents (a checkout of a description package). Empty when no such file exists.
std::string findMesh(const std::string& name, const std::string& urdf_file) {
  namespace fs = std::filesystem;
  const fs::path base = fs::absolute(fs::path(urdf_file)).parent_path();
  std::vector<fs::path> candidates;
  if (name.rfind("file://", 0) == 0) {
    candidates.emplace_back(name.substr(7));
  } else if (name.rfind("package://", 0) == 0) {
    const std::string rest = name.substr(10);
    for (const auto& part : fs::path(rest))
      if (part == "..") return {};  // a package path stays inside its package
    std::vector<fs::path> roots;
    if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
      std::stringstream ss(env);
      for (std::string d; std::getline(ss, d, ':');)
        if (!d.empty()) roots.emplace_back(d);
    }
    for (fs::path d = base; !d.empty(); d = d.parent_path()) {
      roots.push_back(d);
      if (d == d.parent_path()) break;
    }
    for (const auto& r : roots) candidates.push_back(r / rest);
  } else {
    const fs::path p(name);
    candidates.push_back(p.is_absolute() ? p : base / p);
  }
  for (const auto& c : candidates)
    if (io::isRegularFile(c.string())) return fs::absolute(c).lexically_normal().string();
  return {};
}

/// The `<visual>` elements of every link, on the movable body that carries the link (fixed links merged).
void addUrdfVisuals(const urdf::ModelInterface& urdf_model, const std::string& file, Model& model) {
  std::vector<std::string> names;
  for (const auto& [name, link] : urdf_model.links_) names.push_back(name);
  std::sort(names.begin(), names.end());
  for (const auto& name : names) {
    const urdf::Link& link = *urdf_model.links_.at(name);
    if (!model.hasFrame(name) && name != model.base_name) continue;
    const Frame frame = name == model.base_name ? Frame{name, -1, Placement{}}
                                                : model.frames[static_cast<size_t>(model.frameIndex(name))];
    for (const auto& v : link.visual_array) {
      if (!v || !v->geometry) continue;
      Visual out;
      out.link = name;
      out.joint = frame.joint;
      out.placement = frame.placement * fromUrdfPose(v->origin);
      switch (v->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& b = static_cast<const urdf::Box&>(*v->geometry);
          out.shape = Visual::Shape::Box;
          out.size = {b.dim.x, b.dim.y, b.dim.z};
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& c = static_cast<const urdf::Cylinder&>(*v->geometry);
          out.shape = Visual::Shape::Cylinder;
          out.size = {c.radius, c.length, 0.0};
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& s = static_cast<const urdf::Sphere&>(*v->geometry);
          out.shape = Visual::Shape::Sphere;
          out.size = {s.radius, 0.0, 0.0};
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& m = static_cast<const urdf::Mesh&>(*v->geometry);
          out.shape = Visual::Shape::Mesh;
          out.size = {m.scale.x, m.scale.y, m.scale.z};
          out.mesh = m.filename;
          out.mesh_path = findMesh(m.filename, file);
          break;
        }
        default: continue;
      }
      if (!out.size.allFinite()) throw InputError(file + ": link '" + printable(name) + "' <visual>: non-finite size");
      if (v->material) {
        const auto& c = v->material->color;
        out.rgba = {c.r, c.g, c.b, c.a};
      }
      model.visuals.push_back(std::move(out));
    }
  }
}

/// Adds the links below `top`, depth first in document order, with an explicit stack (a chain of links as
/// long as ModelBuilder accepts must not exhaust the call stack).
void addUrdfSubtree(const urdf::Link& top, const std::string& file, ModelBuilder& builder) {
  std::vector<std::pair<const urdf::Link*, size_t>> stack{{&top, 0}};
  while (!stack.empty()) {
    auto& [link_ptr, next] = stack.back();
    const urdf::Link& link = *link_ptr;
    if (next == link.child_joints.size()) {
      stack.pop_back();
      continue;
    }
    const auto& joint = link.child_joints[next++];
    const std::string where = file + ": joint '" + joint->name + "'";
    JointSpec spec;
    spec.name = joint->name;
    switch (joint->type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS: spec.type = JointType::Revolute; break;
      case urdf::Joint::PRISMATIC: spec.type = JointType::Prismatic; break;
      case urdf::Joint::FIXED: spec.type = JointType::Fixed; break;
      default:
        throw InputError(where + ": joint type not supported (expected revolute, continuous, prismatic or fixed)");
    }
    spec.origin = fromUrdfPose(joint->parent_to_joint_origin_transform);
    spec.axis = {joint->axis.x, joint->axis.y, joint->axis.z};
    if (joint->limits) {
      // lower == upper (both 0 when the attributes are left out) means no position limits, as in MuJoCo.
      if (joint->type != urdf::Joint::CONTINUOUS && joint->limits->lower != joint->limits->upper) {
        spec.limits.lower = joint->limits->lower;
        spec.limits.upper = joint->limits->upper;
      }
      if (joint->limits->velocity > 0) spec.limits.velocity = joint->limits->velocity;
      if (joint->limits->effort > 0) spec.limits.effort = joint->limits->effort;
    }
    urdf::LinkSharedPtr child_link;
    for (const auto& c : link.child_links)
      if (c->name == joint->child_link_name) child_link = c;
    if (!child_link) throw InputError(where + ": child link '" + joint->child_link_name + "' not found");
    const BodyInertia inertia = fromUrdfInertial(*child_link);
    if (const std::string why = inertia.validate(); !why.empty())
      throw InputError(file + ": link '" + child_link->name + "' <inertial>: " + why);
    try {
      builder.addLink(link.name, spec, child_link->name, inertia);
    } catch (const InputError& e) {
      throw InputError(file + ": " + e.what());
    }
    stack.emplace_back(child_link.get(), 0);
  }
}

/// Rejects XML that would make a recursive parser (TinyXML, inside urdfdom) exhaust the stack or build an
/// oversized tree: elements nested deeper than `kMaxDepth`, or more <link>/<joint> elements than a model
/// may have. A plain scan of tags (comments, CDATA, processing instructions, declarations and quoted
/// attribute values skipped); the XML parser reports every other error.
void checkXmlShape(const std::string& xml, const std::string& name) {
  // TinyXML (urdfdom's parser, and ours in checkJointGraph) steps over a UTF-8 sequence by its lead byte
  // alone, so a lead byte at the end of the text makes it read past the end (a heap overflow, found by
  // fuzz_urdf); and it stops at a NUL byte. XML is UTF-8 text without NUL: anything else is refused here.
  const size_t bad = std::min(firstInvalidUtf8(xml), xml.find('\0'));
  if (bad != std::string::npos) {
    const auto line = 1 + std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(bad), '\n');
    char byte[8];
    std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(xml[bad])));
    throw InputError(name + ":" + std::to_string(line) + ": byte " + byte +
                     (xml[bad] == '\0' ? " (NUL)" : " is not UTF-8") + "; a URDF is UTF-8 XML text");
  }
  constexpr int kMaxDepth = 100;
  int depth = 0;
  size_t links = 0, joints = 0, line = 1;
  auto skipTo = [&](size_t from, const char* end) {
    const size_t at = xml.find(end, from);
    const size_t stop = at == std::string::npos ? xml.size() : at + std::strlen(end);
    line += static_cast<size_t>(std::count(xml.begin() + static_cast<std::ptrdiff_t>(from),
                                           xml.begin() + static_cast<std::ptrdiff_t>(stop), '\n'));
    return stop;
  };
  for (size_t i = 0; i < xml.size();) {
    if (xml[i] == '\n') ++line;
    if (xml[i] != '<') {
      ++i;
      continue;
    }
    if (xml.compare(i, 4, "<!--") == 0) {
      i = skipTo(i, "-->");
    } else if (xml.compare(i, 9, "<![CDATA[") == 0) {
      i = skipTo(i, "]]>");
    } else if (xml.compare(i, 2, "<?") == 0) {
      i = skipTo(i, "?>");
    } else if (xml.compare(i, 2, "<!") == 0) {
      i = skipTo(i, ">");
    } else if (xml.compare(i, 2, "</") == 0) {
      depth = std::max(0, depth - 1);
      i = skipTo(i, ">");
    } else {
      size_t j = i + 1;
      while (j < xml.size() && (std::isalnum(static_cast<unsigned char>(xml[j])) || xml[j] == '_' || xml[j] == ':' ||
                                xml[j] == '-' || xml[j] == '.'))
        ++j;
      const std::string tag = xml.substr(i + 1, j - i - 1);
      links += tag == "link";
      joints += tag == "joint";
      // The end of the tag: '>' outside quoted attribute values; "/>" closes an empty element.
      char quote = 0;
      bool empty = false;
      for (; j < xml.size(); ++j) {
        const char c = xml[j];
        if (c == '\n') ++line;
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          empty = xml[j - 1] == '/';
          break;
        }
      }
      i = j + 1;
      if (!empty && ++depth > kMaxDepth)
        throw InputError(name + ":" + std::to_string(line) + ": elements nested deeper than " +
                         std::to_string(kMaxDepth) + " levels: not a URDF");
    }
  }
  if (links > ModelBuilder::kMaxLinks || joints > ModelBuilder::kMaxLinks)
    throw InputError(name + ": " + std::to_string(links) + " <link> and " + std::to_string(joints) +
                     " <joint> elements: a robot has at most " + std::to_string(ModelBuilder::kMaxLinks) + " links");
}

// ----------------------------------------------------------------------------------------- YAML

using io::YamlValue;

BodyInertia readInertia(const YamlValue& link) {
  BodyInertia I;
  const YamlValue mass = link.required("mass", "link mass in kg");
  I.mass = mass.asDouble("a mass in kg");
  if (I.mass < 0.0) mass.fail("mass must be >= 0 kg, got " + std::to_string(I.mass));
  I.com = link.required("com", "centre of mass [x, y, z] in m").asVector3("a list of 3 numbers [x, y, z] in m");
  const YamlValue inertia = link.required("inertia", "[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] in kg·m² about the CoM");
  const auto v = inertia.asDoubles(6, "a list of 6 numbers [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] in kg·m²");
  I.inertia << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
  if (const std::string why = I.validate(); !why.empty()) inertia.fail(why);
  return I;
}

JointLimits readLimits(const YamlValue& node) {
  JointLimits lim;
  if (!node.defined()) return lim;
  node.expectMap("a mapping {lower, upper, velocity, effort}");
  node.allowKeys({"lower", "upper", "velocity", "effort"});
  lim.lower = node["lower"].asDouble(lim.lower, "a lower limit in rad or m");
  lim.upper = node["upper"].asDouble(lim.upper, "an upper limit in rad or m");
  lim.velocity = node["velocity"].asDouble(lim.velocity, "a velocity limit in rad/s or m/s");
  lim.effort = node["effort"].asDouble(lim.effort, "an effort limit in N·m or N");
  if (lim.lower > lim.upper) node.fail("lower limit exceeds upper limit");
  if (lim.velocity <= 0.0) node["velocity"].fail("velocity limit must be > 0");
  if (lim.effort <= 0.0) node["effort"].fail("effort limit must be > 0");
  return lim;
}

double readArmature(const YamlValue& joint) {
  const YamlValue a = joint["armature"];
  const double value = a.asDouble(0.0, "an armature (reflected rotor inertia) in kg·m²");
  if (value < 0.0) a.fail("armature must be >= 0");
  return value;
}

Placement readPose(const YamlValue& node, const std::string& what) {
  Placement X;
  if (!node.defined()) return X;
  node.expectMap(what);
  node.allowKeys({"xyz", "rpy"});
  if (node.has("xyz")) X.p = node["xyz"].asVector3("a list of 3 numbers [x, y, z] in m");
  if (node.has("rpy")) {
    const Eigen::Vector3d rpy = node["rpy"].asVector3("a list of 3 angles [roll, pitch, yaw] in rad");
    X.R = rotationFromRpy(rpy.x(), rpy.y(), rpy.z());
  }
  return X;
}

JointType readJointType(const YamlValue& node, bool allow_fixed) {
  const std::string t = node.asString("revolute", "a joint type");
  if (t == "revolute" || (allow_fixed && t == "continuous")) return JointType::Revolute;
  if (t == "prismatic") return JointType::Prismatic;
  if (allow_fixed && t == "fixed") return JointType::Fixed;
  node.failExpected(allow_fixed ? "one of revolute, continuous, prismatic, fixed" : "revolute or prismatic");
}

void rethrowWithFile(const YamlValue& where, const InputError& e) { where.fail(e.what()); }

// Hayati DH chain: frame J_i (joint frame, body i) = DH frame i−1 rotated by q about z; DH frame i =
// J_i · C_i with C_i = Transl(z,d) Rot(z,θ_off) Transl(x,a) Rot(x,α) Rot(y,β) (Rot(z,q) commutes with
// Transl(z,d), and for a prismatic joint Transl(z,q) comes first).
Model buildDhChain(const YamlValue& root, const std::string& name) {
  root.allowKeys({"name", "gravity", "convention", "dh_units", "links", "tool", "base_link"});
  double length_scale = 1.0, angle_scale = 1.0;
  if (const YamlValue units = root["dh_units"]; units.defined()) {
    units.expectMap("a mapping {length: m|mm, angle: rad|deg}");
    units.allowKeys({"length", "angle"});
    const std::string L = units["length"].asString("m", "m or mm");
    const std::string A = units["angle"].asString("rad", "rad or deg");
    if (L == "mm")
      length_scale = 1e-3;
    else if (L != "m")
      units["length"].failExpected("m or mm");
    if (A == "deg")
      angle_scale = kPi / 180.0;
    else if (A != "rad")
      units["angle"].failExpected("rad or deg");
  }
  ModelBuilder builder(name, root["base_link"].asString("base", "a link name"));
  const YamlValue links = root.required("links", "the list of links of the chain");
  links.expectSequence("a list of links");
  if (links.size() == 0) links.fail("expected at least one link");
  std::string parent = root["base_link"].asString("base", "a link name");
  for (size_t i = 0; i < links.size(); ++i) {
    const YamlValue link = links.at(i);
    link.expectMap("a link mapping {name, joint, mass, com, inertia}");
    link.allowKeys({"name", "joint", "mass", "com", "inertia"});
    const std::string link_name = link.required("name", "link name").asString("a link name");
    const YamlValue joint = link.required("joint", "the DH joint of this link");
    joint.expectMap("a joint mapping {name, type, a, alpha, beta, d, theta, armature, limits}");
    joint.allowKeys({"name", "type", "a", "alpha", "beta", "d", "theta", "armature", "limits"});
    JointSpec spec;
    spec.name = joint.required("name", "joint name").asString("a joint name");
    spec.type = readJointType(joint["type"], false);
    spec.axis = Eigen::Vector3d::UnitZ();
    spec.armature = readArmature(joint);
    spec.limits = readLimits(joint["limits"]);
    const double a = joint.required("a", "DH link length a").asDouble("a length") * length_scale;
    const double alpha = joint.required("alpha", "DH twist alpha").asDouble("an angle") * angle_scale;
    const double beta = joint["beta"].asDouble(0.0, "an angle") * angle_scale;
    const double d = joint.required("d", "DH offset d").asDouble("a length") * length_scale;
    const double theta = joint.required("theta", "DH angle offset theta").asDouble("an angle") * angle_scale;
    const BodyInertia inertia = readInertia(link);
    Placement C;  // DH frame i in the joint frame J_i
    C.R = (Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()) *
           Eigen::AngleAxisd(beta, Eigen::Vector3d::UnitY()))
              .toRotationMatrix();
    C.p = Eigen::Vector3d(0.0, 0.0, d) + Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(a, 0, 0);
    try {
      // The moving body is the joint frame (named after the joint); the DH link frame is fixed to it.
      builder.addLink(parent, spec, spec.name, BodyInertia{});
      JointSpec fixed;
      fixed.name = spec.name + "_dh";
      fixed.type = JointType::Fixed;
      fixed.origin = C;
      builder.addLink(spec.name, fixed, link_name, inertia);
    } catch (const InputError& e) {
      rethrowWithFile(link, e);
    }
    parent = link_name;
  }
  if (const YamlValue tool = root["tool"]; tool.defined()) {
    tool.expectMap("a mapping {name, xyz, rpy}");
    tool.allowKeys({"name", "xyz", "rpy"});
    const std::string tool_name = tool.required("name", "tool frame name").asString("a frame name");
    Placement X;
    if (tool.has("xyz")) X.p = tool["xyz"].asVector3("a list of 3 numbers [x, y, z] in m");
    if (tool.has("rpy")) {
      const Eigen::Vector3d rpy = tool["rpy"].asVector3("a list of 3 angles [roll, pitch, yaw] in rad");
      X.R = rotationFromRpy(rpy.x(), rpy.y(), rpy.z());
    }
    try {
      builder.addFrame(tool_name, parent, X);
    } catch (const InputError& e) {
      rethrowWithFile(tool, e);
    }
  }
  if (root.has("gravity")) builder.setGravity(root["gravity"].asVector3("a list of 3 numbers in m/s²"));
  return builder.build();
}

Model buildTree(const YamlValue& root, const std::string& name) {
  root.allowKeys({"name", "gravity", "convention", "links", "joints"});
  const YamlValue links = root.required("links", "the list of links");
  const YamlValue joints = root.required("joints", "the list of joints");
  links.expectSequence("a list of links");
  joints.expectSequence("a list of joints");
  std::map<std::string, size_t> link_index;
  std::vector<std::string> link_order;
  for (size_t i = 0; i < links.size(); ++i) {
    const YamlValue link = links.at(i);
    link.expectMap("a link mapping {name, mass, com, inertia}");
    link.allowKeys({"name", "mass", "com", "inertia"});
    const std::string n = link.required("name", "link name").asString("a link name");
    if (link_index.count(n)) link["name"].fail("link '" + n + "' is defined twice");
    link_index[n] = i;
    link_order.push_back(n);
  }
  // Joints by parent link; each child at most once.
  std::map<std::string, std::vector<size_t>> children;
  std::map<std::string, size_t> parent_joint;
  for (size_t j = 0; j < joints.size(); ++j) {
    const YamlValue joint = joints.at(j);
    joint.expectMap("a joint mapping {name, type, parent, child, origin, axis, armature, limits}");
    joint.allowKeys({"name", "type", "parent", "child", "origin", "axis", "armature", "limits"});
    joint.required("name", "joint name");
    const YamlValue p = joint.required("parent", "parent link name");
    const YamlValue c = joint.required("child", "child link name");
    if (!link_index.count(p.asString("a link name"))) p.fail("unknown link '" + p.asString() + "'");
    if (!link_index.count(c.asString("a link name"))) c.fail("unknown link '" + c.asString() + "'");
    if (parent_joint.count(c.asString())) c.fail("link '" + c.asString() + "' is the child of two joints");
    parent_joint[c.asString()] = j;
    children[p.asString()].push_back(j);
  }
  std::string base;
  for (const auto& n : link_order)
    if (!parent_joint.count(n)) {
      if (!base.empty())
        links.fail("links '" + base + "' and '" + n + "' both have no parent joint; expected a single root");
      base = n;
    }
  if (base.empty()) links.fail("every link has a parent joint (a cycle); expected one root link");
  ModelBuilder builder(name, base);
  size_t added = 1;
  // Depth-first from the root, in file order, so parents come before children.
  std::vector<std::string> stack{base};
  while (!stack.empty()) {
    const std::string parent = stack.back();
    stack.pop_back();
    const auto& js = children[parent];
    for (auto it = js.rbegin(); it != js.rend(); ++it) stack.push_back(joints.at(*it)["child"].asString());
    for (size_t j : js) {
      const YamlValue joint = joints.at(j);
      JointSpec spec;
      spec.name = joint["name"].asString("a joint name");
      spec.type = readJointType(joint["type"], true);
      spec.origin = readPose(joint["origin"], "a mapping {xyz: [m], rpy: [rad]}");
      if (spec.type != JointType::Fixed)
        spec.axis = joint.required("axis", "joint axis [x, y, z]").asVector3("a list of 3 numbers");
      spec.armature = readArmature(joint);
      spec.limits = readLimits(joint["limits"]);
      const std::string child = joint["child"].asString();
      const BodyInertia inertia = readInertia(links.at(link_index[child]));
      try {
        builder.addLink(parent, spec, child, inertia);
      } catch (const InputError& e) {
        rethrowWithFile(joint, e);
      }
      ++added;
    }
  }
  if (added != link_order.size()) links.fail("some links are not connected to the root link '" + base + "'");
  if (root.has("gravity")) builder.setGravity(root["gravity"].asVector3("a list of 3 numbers in m/s²"));
  return builder.build();
}

Model buildFromYaml(const YamlValue& root) {
  root.expectMap("a robot description mapping");
  const std::string name = root.required("name", "robot name").asString("a robot name");
  const YamlValue convention = root.required("convention", "dh_hayati or tree");
  const std::string conv = convention.asString("dh_hayati or tree");
  if (conv == "dh_hayati") return buildDhChain(root, name);
  if (conv == "tree") return buildTree(root, name);
  convention.failExpected("dh_hayati or tree");
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Rejects a joint graph that is not a tree before urdfdom sees it: a link that is the child of two joints,
/// or a cycle of joints. urdfdom links parents and children by shared_ptr both ways, so either builds a
/// reference cycle it never frees (and a cycle with no root fails inside urdfdom after building it); it
/// also keeps only the last parent of a link, silently cutting the links of the cycle off the robot.
/// Parsed with TinyXML, urdfdom's own XML parser (after checkXmlShape has bounded the nesting); XML
/// errors and missing elements are left to urdfdom's messages.
void checkJointGraph(const std::string& xml, const std::string& name) {
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) return;
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) return;
  struct Edge {
    std::string parent, joint;
    int line;
  };
  std::map<std::string, Edge> parent_of;  // child link -> its joint
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j != nullptr; j = j->NextSiblingElement("joint")) {
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* parent = p != nullptr ? p->Attribute("link") : nullptr;
    const char* child = c != nullptr ? c->Attribute("link") : nullptr;
    if (parent == nullptr || child == nullptr) continue;
    const char* joint = j->Attribute("name");
    const Edge edge{parent, joint != nullptr ? joint : "", j->Row()};
    const auto [it, fresh] = parent_of.emplace(child, edge);
    if (!fresh)
      throw InputError(name + ":" + std::to_string(edge.line) + ": joint '" + printable(edge.joint) + "': link '" +
                       printable(child) + "' is already the child of joint '" + printable(it->second.joint) +
                       "' (line " + std::to_string(it->second.line) + "); a link has at most one parent joint");
  }
  // Follow each link's parents; meeting a link of the current walk again closes a cycle.
  std::map<std::string, int> state;  // 1: on the current walk, 2: leads to a root
  for (const auto& start : parent_of) {
    std::vector<const std::string*> walk;
    const std::string* link = &start.first;
    while (true) {
      const int st = state[*link];
      if (st == 2) break;
      if (st == 1) {
        const Edge& e = parent_of.at(*link);
        throw InputError(name + ":" + std::to_string(e.line) + ": joint '" + printable(e.joint) +
                         "' closes a cycle of joints through link '" + printable(*link) +
                         "'; a URDF describes a tree (closed chains are not supported)");
      }
      state[*link] = 1;
      walk.push_back(link);
      const auto up = parent_of.find(*link);
      if (up == parent_of.end()) break;
      link = &up->second.parent;
    }
    for (const std::string* l : walk) state[*l] = 2;
  }
}

}  // namespace

Model loadUrdfString(const std::string& xml, const std::string& name) {
  checkXmlShape(xml, name);
  checkJointGraph(xml, name);
  ScopedOutputCapture capture;
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(xml);
  if (!urdf_model) {
    throw InputError(name + ": not a valid URDF" +
                     (capture.handler.messages.empty() ? std::string() : ": " + capture.handler.messages));
  }
  const urdf::LinkConstSharedPtr root = urdf_model->getRoot();
  ModelBuilder builder(urdf_model->getName(), root->name);
  addUrdfSubtree(*root, name, builder);
  Model model;
  try {
    model = builder.build();
  } catch (const InputError& e) {
    throw InputError(name + ": " + e.what());
  }
  addUrdfVisuals(*urdf_model, name, model);
  return model;
}

Model loadUrdf(const std::string& path) { return loadUrdfString(io::readInputFile(path, "URDF file"), path); }

Model loadRobotYamlString(const std::string& text, const std::string& name) {
  return buildFromYaml(YamlValue::loadString(text, name));
}

Model loadRobotYaml(const std::string& path) { return buildFromYaml(YamlValue::loadFile(path)); }

Model loadRobot(const std::string& path) {
  if (endsWith(path, ".urdf")) return loadUrdf(path);
  if (endsWith(path, ".yaml") || endsWith(path, ".yml")) return loadRobotYaml(path);
  throw InputError(path + ": unknown robot file type (expected a .urdf, .yaml or .yml file)");
}

}  // namespace jointsim::multibody
