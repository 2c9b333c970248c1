#pragma once
/// \file
/// Small spatial-algebra types shared by the multibody layer.
///
/// Conventions (Featherstone, "Rigid Body Dynamics Algorithms", 2008):
/// - A motion vector (twist, spatial acceleration) is stacked [ω; v]: angular part first, then the linear
///   velocity of the point at the frame origin, both resolved in that frame.
/// - A force vector (wrench) is stacked [n; f]: moment about the frame origin first, then the force.
/// - A Placement (R, p) gives a child frame in its parent frame: R's columns are the child axes resolved in
///   the parent, p is the child origin in the parent [m]. A point x_c in the child is x_p = R x_c + p.

#include <Eigen/Core>

namespace jointsim::multibody {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Rigid transform (element of SE(3)): the pose of a child frame in a parent frame.
struct Placement {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< rotation, child axes in parent coordinates
  Eigen::Vector3d p = Eigen::Vector3d::Zero();      ///< child origin in parent coordinates [m]

  /// Composition: (this * other) maps other's child frame into this placement's parent frame.
  Placement operator*(const Placement& other) const { return {R * other.R, R * other.p + p}; }
  /// Inverse transform (parent in child).
  Placement inverse() const { return {R.transpose(), -(R.transpose() * p)}; }
  /// Maps a point given in the child frame to the parent frame.
  Eigen::Vector3d act(const Eigen::Vector3d& x) const { return R * x + p; }
  /// 4x4 homogeneous matrix.
  Eigen::Matrix4d homogeneous() const {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = R;
    T.topRightCorner<3, 1>() = p;
    return T;
  }
  static Placement Identity() { return {}; }
};

/// Rotation from URDF-style roll-pitch-yaw (fixed axes x, then y, then z): R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d rotationFromRpy(double roll, double pitch, double yaw);

/// Skew-symmetric matrix [x]: [x] y = x × y.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& x) {
  Eigen::Matrix3d S;
  S << 0.0, -x.z(), x.y(), x.z(), 0.0, -x.x(), -x.y(), x.x(), 0.0;
  return S;
}

}  // namespace jointsim::multibody
