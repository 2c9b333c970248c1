#pragma once
/// \file
/// Robot descriptions: URDF (through urdfdom) and jointsim's YAML robot format.
///
/// YAML format (documented in full in docs/robot_format.md):
/// - `convention: dh_hayati` — a serial chain given per link by the Hayati-modified Denavit–Hartenberg
///   parameters of [Raviola2023, §2.6, eq. 8]: ^{i-1}A_i = Transl(z,d) Rot(z,θ) Transl(x,a) Rot(x,α) Rot(y,β),
///   with θ = q + theta (revolute) or d = d + q (prismatic). Link i's frame (CoM, inertia) is DH frame i.
/// - `convention: tree` — URDF-like links and joints (origin xyz/rpy, axis), any tree.
/// Every error is an InputError naming the file, the line, the key path and what was expected.

#include <string>

#include "jointsim/multibody/model.hpp"

namespace jointsim::multibody {

/// Loads a URDF file. The root link is fixed to the world; gravity is (0, 0, −9.81) m/s².
Model loadUrdf(const std::string& path);
/// Parses URDF text; `name` stands for the file name in error messages.
Model loadUrdfString(const std::string& xml, const std::string& name = "<urdf string>");

/// Loads a YAML robot description (convention dh_hayati or tree).
Model loadRobotYaml(const std::string& path);
/// Parses YAML robot text; `name` stands for the file name in error messages.
Model loadRobotYamlString(const std::string& text, const std::string& name = "<yaml string>");

/// Loads a robot by file extension: .urdf → URDF, .yaml/.yml → YAML. Throws InputError otherwise.
Model loadRobot(const std::string& path);

}  // namespace jointsim::multibody
