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

bool readAll(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return !in.bad();
}
}  // namespace

std::string contentHash(const std::string& bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "xxh3:%016llx",
                static_cast<unsigned long long>(XXH3_64bits(bytes.data(), bytes.size())));
  return buf;
}

std::string fileHash(const std::string& path) {
  std::string bytes;
  return readAll(path, bytes) ? contentHash(bytes) : std::string();
}

std::string readInputFile(const std::string& path, const std::string& what) {
  std::string bytes;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec) || !readAll(path, bytes))
    throw InputError(path + ": cannot open " + what + " for reading");
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
