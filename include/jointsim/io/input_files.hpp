#pragma once
/// \file
/// Reading input files (experiment, robot, drive and sweep files, CSV data) through one function, which
/// also records what a run read: summary.json lists every input file with a content hash, and a batch reuses a
/// finished run only while those hashes still match (experiments/batch.hpp).

#include <cstdint>
#include <string>
#include <vector>

namespace jointsim::io {

/// One file read by readInputFile.
struct InputFile {
  std::string path;        ///< absolute, normalised path
  std::string hash;        ///< content hash, "xxh3:" + 16 hex digits (XXH3 64-bit of the bytes)
  std::uint64_t size = 0;  ///< bytes
};

/// Largest file any reader accepts [bytes] (512 MiB).
constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t{512} << 20;

/// The whole file `path` as bytes. Throws InputError "PATH: cannot open WHAT for reading" (also for a folder),
/// "PATH: not a regular file: cannot read WHAT" (a FIFO or a device such as /dev/zero or /dev/stdin, which
/// could block or never end) or "PATH: larger than 512 MiB: cannot read WHAT". While an InputRecord is alive on
/// this thread, the file is added to it (once per path).
std::string readInputFile(const std::string& path, const std::string& what = "file");

/// Collects the files read by readInputFile on this thread during its lifetime (records nest: a file goes to
/// every record alive).
class InputRecord {
 public:
  InputRecord();
  ~InputRecord();
  InputRecord(const InputRecord&) = delete;
  InputRecord& operator=(const InputRecord&) = delete;
  const std::vector<InputFile>& files() const { return files_; }
  void add(const InputFile& file);

 private:
  std::vector<InputFile> files_;
  InputRecord* outer_ = nullptr;
};

/// "xxh3:" + the XXH3 64-bit hash of `bytes` in hex.
std::string contentHash(const std::string& bytes);
/// Whether `path` exists / is a regular file / is a folder. False also when it cannot be examined (a name
/// too long, a component without permission, a symlink loop): these never throw, unlike std::filesystem's
/// one-argument forms.
bool pathExists(const std::string& path);
bool isRegularFile(const std::string& path);
bool isDirectory(const std::string& path);
/// The bytes of a regular file of at most kMaxInputFileBytes; empty when it cannot be read (no record kept).
std::string readBoundedFile(const std::string& path);
/// contentHash of the file's bytes; empty when the file cannot be read.
std::string fileHash(const std::string& path);

}  // namespace jointsim::io
