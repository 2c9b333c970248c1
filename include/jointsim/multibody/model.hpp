#pragma once
/// \file
/// The constant description of a rigid multibody tree (jointsim::multibody::Model) and the builder that
/// assembles and validates it. Mutable workspace lives in Data (data.hpp); algorithms are free functions
/// (algorithms.hpp) taking `const Model&` and `Data&`.

#include <limits>
#include <string>
#include <vector>

#include "jointsim/multibody/spatial.hpp"

namespace jointsim::multibody {

/// Joint kinds. Fixed joints are merged into their parent body when the Model is built: they carry no
/// degree of freedom, only a named frame.
enum class JointType { Revolute, Prismatic, Fixed };

const char* toString(JointType type);

/// Inertial parameters of a rigid body, expressed in the body (link) frame.
struct BodyInertia {
  double mass = 0.0;                                  ///< m [kg], >= 0
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      ///< centre of mass in the link frame [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< inertia about the CoM, link-frame axes [kg·m²]

  /// Returns an empty string when the parameters are physical, otherwise the reason: negative or
  /// non-finite mass, non-symmetric inertia, inertia not positive definite or violating the triangle
  /// inequality of principal moments (mass > 0), or not positive semi-definite (mass = 0).
  std::string validate() const;
  /// This body's inertia re-expressed in a frame in which the link frame has placement X.
  BodyInertia transformed(const Placement& X) const;
  /// Sum of two bodies expressed in the same frame (combined mass, CoM, inertia about the new CoM).
  BodyInertia operator+(const BodyInertia& other) const;
};

/// Joint limits (informative for now: no algorithm enforces them). SI units.
struct JointLimits {
  double lower = -std::numeric_limits<double>::infinity();    ///< [rad] or [m]
  double upper = std::numeric_limits<double>::infinity();     ///< [rad] or [m]
  double velocity = std::numeric_limits<double>::infinity();  ///< [rad/s] or [m/s]
  double effort = std::numeric_limits<double>::infinity();    ///< [N·m] or [N]
};

/// A named frame rigidly attached to a body (or to the base when joint == -1).
struct Frame {
  std::string name;
  int joint = -1;       ///< index of the movable joint whose body carries the frame; -1 = base
  Placement placement;  ///< pose of the frame in that body's joint frame [m, rad]
};

/// Visual geometry of a link as its robot file describes it (URDF `<visual>`), for viewers (`jointsim view`); no
/// algorithm uses it.
struct Visual {
  enum class Shape { Box, Cylinder, Sphere, Mesh };
  int joint = -1;       ///< index of the movable joint whose body carries it; -1 = base
  Placement placement;  ///< pose of the geometry in that body's joint frame [m, rad]
  Shape shape = Shape::Box;
  /// Box: edge lengths along x, y, z [m]; cylinder (axis z): radius, length [m], 0; sphere: radius [m], 0, 0;
  /// mesh: scale factors along x, y, z [-].
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  std::string mesh;       ///< mesh file as the robot file names it (e.g. package://ur_description/meshes/base.stl)
  std::string mesh_path;  ///< mesh: the file found for it (absolute), empty when not found
  Eigen::Vector4d rgba = Eigen::Vector4d::Constant(-1.0);  ///< material colour (0..1), all −1 when none
  std::string link;                                        ///< the link it belongs to
};

/// Constant description of a kinematic tree with nq single-degree-of-freedom joints (revolute about an
/// arbitrary axis or prismatic along one). Joint i moves body i; body frames are the joint frames.
/// Joints are ordered so that parents[i] < i ("from base to tip" for a serial chain).
struct Model {
  std::string name;                          ///< robot name
  int nq = 0;                                ///< number of movable joints (= nv)
  std::vector<std::string> joint_names;      ///< (nq)
  std::vector<std::string> body_names;       ///< (nq) name of the link moved by each joint
  std::vector<JointType> joint_types;        ///< (nq) Revolute or Prismatic
  std::vector<int> parents;                  ///< (nq) parent joint index, -1 for the base
  std::vector<Placement> joint_placements;   ///< (nq) joint frame in the parent body frame at q = 0
  std::vector<Eigen::Vector3d> axes;         ///< (nq) unit joint axis in the joint frame
  std::vector<BodyInertia> inertias;         ///< (nq) body inertia (incl. fixed children), joint frame
  Eigen::VectorXd armature;                  ///< (nq) rotor inertia reflected to the joint [kg·m² or kg]
  std::vector<JointLimits> limits;           ///< (nq)
  std::vector<Frame> frames;                 ///< every link frame plus extra named frames
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  ///< gravity acceleration in the base frame [m/s²]
  std::string base_name = "base";            ///< name of the root link (fixed to the world)
  std::string tip_frame;                     ///< default tool frame: the last link of the chain

  // Derived from `inertias` by ModelBuilder (cached for the algorithms): spatial inertia about the
  // joint-frame origin as (m, h = m·c, I_O = I_c - m [c]²).
  std::vector<double> mass;                     ///< (nq) [kg]
  std::vector<Eigen::Vector3d> first_moment;    ///< (nq) h = m c [kg·m]
  std::vector<Eigen::Matrix3d> inertia_origin;  ///< (nq) I_O [kg·m²]
  std::vector<int> axis_kind;                   ///< (nq) 0, 1, 2: axis is +x, +y, +z exactly; 3: other

  std::vector<Visual> visuals;  ///< visual geometry of the links (URDF `<visual>`), for viewers only

  /// Index of the joint with this name; throws InputError naming the known joints if absent.
  int jointIndex(const std::string& name) const;
  /// Index of the frame with this name; throws InputError naming the known frames if absent.
  int frameIndex(const std::string& name) const;
  /// Whether a frame of this name exists.
  bool hasFrame(const std::string& name) const;
  /// Recomputes the cached spatial inertias from `inertias` (call after editing inertias directly).
  void updateDerived();
};

/// Description of one joint for ModelBuilder::addLink.
struct JointSpec {
  std::string name;
  JointType type = JointType::Revolute;
  Placement origin;                                 ///< joint frame in the parent link frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< axis in the joint frame (normalised on build)
  double armature = 0.0;                            ///< reflected rotor inertia [kg·m² or kg], >= 0
  JointLimits limits;
};

/// Assembles a Model from links and joints given parent-first (as a URDF tree is walked). Fixed joints
/// are merged: the child's inertia is added to the nearest movable ancestor (or dropped when the ancestor
/// is the base, which is fixed to the world) and its frame is kept as a named Frame.
class ModelBuilder {
 public:
  /// Most links (base and fixed-joint links included) a model may have: far beyond any robot, small
  /// enough that the O(n²) mass matrix of a hostile input stays a few MB.
  static constexpr size_t kMaxLinks = 1000;

  explicit ModelBuilder(std::string robot_name, std::string base_link = "base");

  /// Adds link `child_name` with inertia `inertia`, attached to the existing link `parent_link` by
  /// `joint`. The child link frame coincides with the joint frame. Throws InputError on a duplicate
  /// name, an unknown parent, a zero axis, a negative armature, an unphysical inertia or more than
  /// kMaxLinks links.
  ModelBuilder& addLink(const std::string& parent_link, const JointSpec& joint, const std::string& child_name,
                        const BodyInertia& inertia);
  /// Adds an extra named frame rigidly attached to an existing link.
  ModelBuilder& addFrame(const std::string& name, const std::string& link, const Placement& placement);
  ModelBuilder& setGravity(const Eigen::Vector3d& gravity);
  /// Overrides the default tool frame (otherwise the deepest link, first found).
  ModelBuilder& setTipFrame(const std::string& frame);

  /// Name of the link added last on the deepest branch (the default tool frame of a chain).
  const std::string& tipLink() const { return tip_link_; }

  Model build() const;

 private:
  struct LinkRecord {
    int joint;            // movable joint carrying this link (-1: base)
    Placement placement;  // link frame in that joint frame
    int depth;
  };
  Model model_;
  std::vector<std::pair<std::string, LinkRecord>> links_;
  std::string tip_link_;
  std::string tip_override_;
  int tip_depth_ = 0;
  const LinkRecord* findLink(const std::string& name) const;
};

}  // namespace jointsim::multibody
