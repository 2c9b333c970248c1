#include "jointsim/common/text.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace jointsim {

std::string formatNumber(double value, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, value);
  return buf;
}

std::string formatDuration(double seconds) {
  if (!(seconds >= 0.0) || !std::isfinite(seconds)) return "?";
  const long long s = static_cast<long long>(std::llround(seconds));
  char buf[48];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%lld s", s);
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%lld min %02lld s", s / 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%lld h %02lld min", s / 3600, (s % 3600) / 60);
  return buf;
}

std::string formatShortest(double value) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, r.ptr);
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

bool isSafeName(const std::string& name) {
  if (name.empty() || name.size() > 128 || name[0] == '.' || name[0] == '-') return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_')) return false;
  return true;
}

std::string safeFileName(const std::string& name) {
  std::string out;
  for (const char c : name.substr(0, 128))
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  if (out.empty()) return "_";
  if (out[0] == '.' || out[0] == '-') out[0] = '_';
  return out;
}

namespace {
void appendEscaped(std::string& out, unsigned char c) {
  if (c == '\n')
    out += "\\n";
  else if (c == '\t')
    out += "\\t";
  else if (c == '\r')
    out += "\\r";
  else if (c < 0x20 || c == 0x7f) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "\\x%02x", c);
    out += buf;
  } else {
    out += static_cast<char>(c);
  }
}
bool continuationByte(char c) { return (static_cast<unsigned char>(c) & 0xC0) == 0x80; }
}  // namespace

std::string printable(const std::string& text, size_t max_length) {
  // The head (two thirds of the budget) and the tail (one third): a message usually ends with its reason.
  // Cuts fall only at the start of a UTF-8 sequence (not before a continuation byte 10xxxxxx).
  const size_t head_budget = max_length - max_length / 3, tail_budget = max_length / 3;
  std::string head;
  size_t i = 0;
  for (; i < text.size() && (head.size() < head_budget || continuationByte(text[i])); ++i)
    appendEscaped(head, static_cast<unsigned char>(text[i]));
  std::string tail_reversed;
  size_t j = text.size();
  for (; j > i && (tail_reversed.size() < tail_budget || continuationByte(text[j])); --j) {
    std::string one;
    appendEscaped(one, static_cast<unsigned char>(text[j - 1]));
    tail_reversed.append(one.rbegin(), one.rend());
  }
  std::string tail(tail_reversed.rbegin(), tail_reversed.rend());
  if (j == i) return head + tail;
  return head + "... (" + std::to_string(j - i) + " bytes cut) ..." + tail;
}

std::string columnBaseName(const std::string& column) { return trim(splitColumn(trim(column)).first); }

size_t firstInvalidUtf8(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    const unsigned c = p[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    // Length of the sequence and the range of its second byte (RFC 3629, table 3-7 of Unicode).
    size_t len = 0;
    unsigned lo = 0x80, hi = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      if (c == 0xE0) lo = 0xA0;  // no overlong form
      if (c == 0xED) hi = 0x9F;  // no surrogate
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      if (c == 0xF0) lo = 0x90;  // no overlong form
      if (c == 0xF4) hi = 0x8F;  // at most U+10FFFF
    } else {
      return i;
    }
    if (i + len > n || p[i + 1] < lo || p[i + 1] > hi) return i;
    for (size_t k = 2; k < len; ++k)
      if (p[i + k] < 0x80 || p[i + k] > 0xBF) return i;
    i += len;
  }
  return std::string::npos;
}

}  // namespace jointsim
