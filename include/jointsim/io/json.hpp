#pragma once
/// \file
/// Reading JSON written by jointsim (summary.json) that a user may have edited: nesting is bounded, because
/// nlohmann-json copies and prints values recursively and a value nested a million levels deep would
/// exhaust the stack on the first copy.

#include <string>

#include <nlohmann/json_fwd.hpp>

namespace jointsim::io {

/// Deepest nesting of arrays and objects readJson accepts (a summary needs fewer than 10 levels).
constexpr int kMaxJsonDepth = 64;

/// Parses `text` (read from `name`, used in messages). Returns a discarded value (is_discarded()) when
/// the text is not JSON.
/// \throws InputError "NAME: JSON nested deeper than 64 levels" when arrays or objects nest deeper.
nlohmann::ordered_json parseJson(const std::string& text, const std::string& name);

}  // namespace jointsim::io
