#pragma once
/// \file Umbrella header of the jointsim library.
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/multibody/model.hpp"
#include "jointsim/multibody/robot_loader.hpp"
#include "jointsim/multibody/spatial.hpp"
#include "jointsim/experiments/passive_robot.hpp"
#include "jointsim/experiments/runner.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
