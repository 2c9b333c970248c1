#pragma once
/// \file
/// Orthogonal (bending) compliance of revolute joints: two extra revolute joints per joint, orthogonal to
/// its axis ([Olsson2017, §3.7]), used by the clamped-robot model.

#include <string>
#include <vector>

#include "jointsim/multibody/model.hpp"

namespace jointsim::multibody {

/// Copy of `model` in which every joint named in `joints` is followed by two revolute joints about
/// axes u and v orthogonal to its axis n ([Olsson2017, A.15] getOrthVectors: u = e_x × n if n_x = 0, else
/// e_y × n if n_y = 0, else e_z × n, normalised; v = n × u), named `<joint>_orth_u` and `<joint>_orth_v`, with two
/// massless links between; the original link, its frames and its children follow the last one. The
/// orthogonal joints rotate with the joint (for an isotropic bending stiffness this is the same spring).
/// Throws InputError for an unknown or prismatic joint.
Model withOrthogonalCompliance(const Model& model, const std::vector<std::string>& joints);

}  // namespace jointsim::multibody
