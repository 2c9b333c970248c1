// Fixture for tests/architecture/test_layering.cpp: an io source that includes an internal header of the
// report layer (a violation) and a header of its own layer (fine). Not compiled.
#include "jointsim/io/yaml.hpp"
#include "report/gnuplot.hpp"
