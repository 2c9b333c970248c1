#pragma once
/// \file Umbrella header of the jointsim library.
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/multibody/spatial.hpp"
