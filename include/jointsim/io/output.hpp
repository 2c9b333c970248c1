#pragma once
/// \file
/// Output files that never appear half-written: data go to a temporary file beside the target, which is
/// renamed into place only on commit(). A writer destroyed without commit() removes its temporary file.

#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointsim::io {

/// CSV with a header line of `name[unit]` columns and full double precision (%.17g) rows.
class CsvWriter {
 public:
  /// Opens a temporary file next to `path`; throws jointsim::Error if the directory is not writable.
  CsvWriter(std::string path, const std::vector<std::string>& header);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  /// Appends one row; its size must equal the number of columns.
  void writeRow(const Eigen::Ref<const Eigen::VectorXd>& row);
  /// Flushes and closes the temporary file (it stays under its temporary name). Throws jointsim::Error on I/O
  /// failure. Lets several outputs be complete before any of them is renamed into place.
  void finish();
  /// finish() if not done, then renames the temporary file to `path`. Throws jointsim::Error on I/O failure.
  void commit();
  size_t columns() const { return columns_; }
  size_t rows() const { return rows_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
  size_t columns_ = 0, rows_ = 0;
};

/// The temporary name under which an output is written before it is renamed into place: "PATH.tmp.<pid>" (beside
/// the target, so that the rename stays on one file system; a batch removes leftovers by the ".tmp." in the name).
std::string temporaryName(const std::string& path);
/// Renames the complete temporary file `tmp` to `path`; on failure removes `tmp` and throws Error naming `path`.
void moveIntoPlace(const std::string& tmp, const std::string& path);

/// Writes `content` to `path` through a temporary file and a rename.
void writeFileAtomically(const std::string& path, const std::string& content);

/// Creates a directory and its parents (no error if it exists); throws InputError when it cannot (a path too
/// long, a file in the way, no permission: the folder the user asked for is not usable).
void createDirectories(const std::string& path);

/// An advisory lock (flock) on `lock_file` (created if missing), held while the object lives; the kernel releases it
/// when its process ends, also on kill -9. Exclusive, or shared with other shared holders. Another process (or
/// another FileLock of this one) holding it in a conflicting way: InputError(`busy_message`) at once, no waiting.
/// flock works across the nodes of an NFS v4 file system.
class FileLock {
 public:
  FileLock(const std::string& lock_file, bool exclusive, const std::string& busy_message);
  /// An exclusive lock on the folder itself (no lock file left in it). Where the file system cannot lock folders
  /// (some NFS mounts), no lock is taken.
  static FileLock onFolder(const std::string& folder, const std::string& busy_message);
  FileLock(FileLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  FileLock() = default;
  int fd_ = -1;
};

}  // namespace jointsim::io
