#pragma once
// Fixture for tests/architecture/test_layering.cpp: a drive-layer header that includes an experiments-layer
// header (a violation: drive is below experiments). Not compiled.
#include <string>

#include "jointsim/common/error.hpp"
#include "jointsim/experiments/registry.hpp"
