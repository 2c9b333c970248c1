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
/// The shortest text that reads back as exactly `value` ("0.8", not "0.80000000000000004").
std::string formatShortest(double value);
/// A duration [s] for a progress line, rounded to what a person reads: "8 s", "2 min 05 s", "1 h 12 min".
std::string formatDuration(double seconds);

/// Items joined by `separator`.
std::string join(const std::vector<std::string>& items, const std::string& separator);

/// The base name of a column `name[unit]` ("motor_angle[rad]" -> "motor_angle", "w_a[1][rad/s]" -> "w_a[1]":
/// the unit is the last bracket pair); trimmed; the whole text when it has no unit.
std::string columnBaseName(const std::string& column);

/// Splits `name[unit]` at its last bracket pair ("w_a[1][rad/s]" -> {"w_a[1]", "rad/s"}); unit empty if none.
std::pair<std::string, std::string> splitColumn(const std::string& column);

/// Text with leading and trailing blanks (space, tab, CR) removed.
std::string trim(const std::string& text);

/// A name that is safe as a file or folder name and inside a gnuplot string: 1 to 128 characters of letters,
/// digits, '.', '-', '_', not starting with '.' or '-' (so never "." or ".."). Experiment, sweep and run names
/// and the stems of output files must be safe names.
bool isSafeName(const std::string& name);
/// `name` with every character outside the safe set replaced by '_' (and a leading '.' or '-' too), cut to 128
/// characters; "_" for an empty name.
std::string safeFileName(const std::string& name);
/// Text for a one-line message: control characters (newline, tab, ESC, ...) escaped as \n, \t, \xHH, and, when
/// longer than about `max_length` bytes, cut in the middle ("... (N bytes cut) ...") keeping the head and the
/// tail (where a message gives its reason).
std::string printable(const std::string& text, size_t max_length = 400);
/// Offset of the first byte of `text` that does not begin a well-formed UTF-8 sequence (RFC 3629: no
/// overlong form, surrogate or code point above U+10FFFF; a sequence cut by the end counts), or
/// std::string::npos when all of it is UTF-8.
size_t firstInvalidUtf8(const std::string& text);

}  // namespace jointsim
