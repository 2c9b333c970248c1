#pragma once
/// \file
/// Small text helpers shared by every layer: number formatting for messages, joining, and the `name[unit]`
/// convention of signal and CSV column names.

#include <string>
#include <utility>
#include <vector>

namespace jointsim {

/// A number for a message: %.<precision>g ("0.001", "2.5e+07").
std::string formatNumber(double value, int precision = 10);

/// Items joined by `separator`.
std::string join(const std::vector<std::string>& items, const std::string& separator);

/// The base name of a column `name[unit]` ("motor_angle[rad]" -> "motor_angle", "w_a[1][rad/s]" -> "w_a[1]":
/// the unit is the last bracket pair); trimmed; the whole text when it has no unit.
std::string columnBaseName(const std::string& column);

/// Splits `name[unit]` at its last bracket pair ("w_a[1][rad/s]" -> {"w_a[1]", "rad/s"}); unit empty if none.
std::pair<std::string, std::string> splitColumn(const std::string& column);

/// Text with leading and trailing blanks (space, tab, CR) removed.
std::string trim(const std::string& text);

}  // namespace jointsim
