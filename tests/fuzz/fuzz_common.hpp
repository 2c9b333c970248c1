#pragma once
// Shared by the libFuzzer targets (tests/fuzz/README.md): a private copy of config/ per process, so that
// inputs can name the shipped robot and data files by the same relative paths as the shipped experiments,
// and the one oracle of every target — an input may only end in a jointsim::Error (input error, solver
// failure, budget run out); any other exception escapes LLVMFuzzerTestOneInput and libFuzzer reports it as a
// crash, as it does for every sanitizer report, leak or timeout.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include <unistd.h>

namespace jointsim::fuzz {

/// The process's workspace: a copy of the source tree's config/ (experiments/, robots/, sweeps/) in a fresh
/// temporary folder of its own (mkdtemp under $TMPDIR, default /tmp: no other process can get it), removed at exit.
inline const std::filesystem::path& workspace() {
  static const std::filesystem::path dir = [] {
    namespace fs = std::filesystem;
    const char* tmpdir = std::getenv("TMPDIR");
    std::string templ =
        (fs::path(tmpdir != nullptr && *tmpdir != '\0' ? tmpdir : "/tmp") / "jointsim_fuzz.XXXXXX").string();
    if (::mkdtemp(templ.data()) == nullptr) {
      std::perror(("mkdtemp " + templ).c_str());
      std::abort();
    }
    const fs::path d = templ;
    fs::copy(fs::path(JOINTSIM_SOURCE_DIR) / "config", d / "config", fs::copy_options::recursive);
    static const std::string keep = d.string();
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(keep, ec);
    });
    return d;
  }();
  return dir;
}

/// Writes the input to `relative` (inside the workspace) and returns its path.
inline std::string writeInput(const std::string& relative, const uint8_t* data, size_t size) {
  const std::filesystem::path p = workspace() / relative;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return p.string();
}

/// A new, empty folder `<workspace>/<prefix>.XXXXXX` (mkdtemp) for one input; remove it with removeDir.
inline std::filesystem::path makeInputDir(const std::string& prefix) {
  std::string templ = (workspace() / (prefix + ".XXXXXX")).string();
  if (::mkdtemp(templ.data()) == nullptr) {
    std::perror(("mkdtemp " + templ).c_str());
    std::abort();
  }
  return templ;
}

/// Removes a folder made by makeInputDir with everything in it (errors ignored: the workspace goes at exit).
inline void removeDir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

/// Reads the fuzz bytes front to back as small numbers; past the end every read gives 0 (an input is never
/// rejected for being short). `rest` takes what is left as text.
class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t left() const { return size_ - pos_; }
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  uint16_t u16() { return static_cast<uint16_t>(byte() << 8 | byte()); }
  uint32_t u32() { return static_cast<uint32_t>(u16()) << 16 | u16(); }
  bool flag() { return (byte() & 1) != 0; }
  /// One of `n` choices (n > 0).
  size_t pick(size_t n) { return byte() % n; }
  template <class T, size_t N>
  const T& pick(const T (&choices)[N]) {
    return choices[pick(N)];
  }
  /// The next `n` bytes (fewer at the end) as text.
  std::string text(size_t n) {
    const size_t k = n < left() ? n : left();
    std::string s(reinterpret_cast<const char*>(data_ + pos_), k);
    pos_ += k;
    return s;
  }
  std::string rest() { return text(left()); }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

/// With JOINTSIM_FUZZ_VERBOSE set, prints the error an input ended in (to see what a corpus reaches).
inline void note(const char* text) {
  static const bool verbose = std::getenv("JOINTSIM_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "  -> %s\n", text);
}
inline void note(const std::exception& e) { note(e.what()); }

}  // namespace jointsim::fuzz
