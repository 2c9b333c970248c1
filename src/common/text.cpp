#include "jointsim/common/text.hpp"

#include <cstdio>

namespace jointsim {

std::string formatNumber(double value, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, value);
  return buf;
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? separator : std::string()) + items[i];
  return out;
}

std::string trim(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t\r") - first + 1);
}

std::pair<std::string, std::string> splitColumn(const std::string& column) {
  if (!column.empty() && column.back() == ']') {
    const size_t open = column.rfind('[');
    if (open != std::string::npos && open > 0)
      return {column.substr(0, open), column.substr(open + 1, column.size() - open - 2)};
  }
  return {column, ""};
}

std::string columnBaseName(const std::string& column) { return trim(splitColumn(trim(column)).first); }

}  // namespace jointsim
