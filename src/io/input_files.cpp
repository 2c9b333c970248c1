#include "jointsim/io/input_files.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "jointsim/common/error.hpp"

namespace jointsim::io {
namespace {
thread_local InputRecord* g_innermost = nullptr;

/// Reads a regular file of at most kMaxInputFileBytes; "" on success, else why not. A FIFO, a device
/// (/dev/zero, /dev/stdin) or a folder is refused: reading it could block or never end.
std::string readAll(const std::string& path, std::string& out) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) return "cannot open";
  if (!std::filesystem::is_regular_file(status)) return "not a regular file: cannot read";
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot open";
  out.clear();
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    if (out.size() + static_cast<size_t>(in.gcount()) > kMaxInputFileBytes)
      return "larger than " + std::to_string(kMaxInputFileBytes >> 20) + " MiB: cannot read";
    out.append(buf, static_cast<size_t>(in.gcount()));
  }
  return in.bad() ? "cannot read" : "";
}
}  // namespace

bool pathExists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}
bool isRegularFile(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}
bool isDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

std::string contentHash(const std::string& bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "xxh3:%016llx",
                static_cast<unsigned long long>(XXH3_64bits(bytes.data(), bytes.size())));
  return buf;
}

std::string readBoundedFile(const std::string& path) {
  std::string bytes;
  return readAll(path, bytes).empty() ? bytes : std::string();
}

std::string fileHash(const std::string& path) {
  std::string bytes;
  return readAll(path, bytes).empty() ? contentHash(bytes) : std::string();
}

std::string readInputFile(const std::string& path, const std::string& what) {
  std::string bytes;
  std::error_code ec;
  if (const std::string why = readAll(path, bytes); !why.empty()) {
    if (why == "cannot open" && !pathExists(path))
      throw InputError::fileNotFound(path, "cannot open " + what + " for reading: no such file");
    throw InputError(path + ": " + why + " " + what + (why == "cannot open" ? " for reading" : ""));
  }
  if (g_innermost) {
    InputFile f;
    f.path = std::filesystem::absolute(path, ec).lexically_normal().string();
    if (ec) f.path = path;
    f.hash = contentHash(bytes);
    f.size = bytes.size();
    g_innermost->add(f);
  }
  return bytes;
}

InputRecord::InputRecord() : outer_(g_innermost) { g_innermost = this; }

InputRecord::~InputRecord() { g_innermost = outer_; }

void InputRecord::add(const InputFile& file) {
  bool seen = false;
  for (const auto& f : files_) seen = seen || f.path == file.path;
  if (!seen) files_.push_back(file);
  if (outer_) outer_->add(file);
}

}  // namespace jointsim::io
