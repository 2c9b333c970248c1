#include "jointsim/io/json.hpp"

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"

namespace jointsim::io {

nlohmann::ordered_json parseJson(const std::string& text, const std::string& name) {
  // The parser itself is iterative; the callback sees the depth of every value as it is read and stops
  // the parse before anything too deep is built.
  const nlohmann::ordered_json::parser_callback_t bound = [&name](int depth, nlohmann::ordered_json::parse_event_t,
                                                                  nlohmann::ordered_json&) {
    if (depth > kMaxJsonDepth)
      throw InputError(name + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    return true;
  };
  return nlohmann::ordered_json::parse(text, bound, /*allow_exceptions=*/false);
}

}  // namespace jointsim::io
