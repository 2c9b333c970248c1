#include "jointsim/io/output.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "jointsim/common/error.hpp"

namespace jointsim::io {

std::string temporaryName(const std::string& path) {
  return path + ".tmp." + std::to_string(static_cast<long>(::getpid()));
}

void moveIntoPlace(const std::string& tmp, const std::string& path) {
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw Error(path + ": cannot move output into place: " + std::strerror(err));
  }
}

CsvWriter::CsvWriter(std::string path, const std::vector<std::string>& header)
    : path_(std::move(path)), tmp_path_(temporaryName(path_)), columns_(header.size()) {
  file_ = std::fopen(tmp_path_.c_str(), "w");
  if (file_ == nullptr) throw Error(path_ + ": cannot write output file: " + std::strerror(errno));
  for (size_t i = 0; i < header.size(); ++i) std::fprintf(file_, "%s%s", i ? "," : "", header[i].c_str());
  std::fputc('\n', file_);
}

CsvWriter::~CsvWriter() {
  if (file_ != nullptr) std::fclose(file_);
  if (!committed_) std::remove(tmp_path_.c_str());
}

void CsvWriter::writeRow(const Eigen::Ref<const Eigen::VectorXd>& row) {
  if (static_cast<size_t>(row.size()) != columns_)
    throw Error(path_ + ": row has " + std::to_string(row.size()) + " values, header has " + std::to_string(columns_));
  // Each value as printf's %.17g would write it (std::to_chars with the general format and a precision is
  // specified as that), several times faster than fprintf; one fwrite per row.
  char buf[64];
  for (Eigen::Index i = 0; i < row.size(); ++i) {
    char* p = buf;
    if (i > 0) *p++ = ',';
    const std::to_chars_result r = std::to_chars(p, buf + sizeof buf - 1, row[i], std::chars_format::general, 17);
    if (r.ec != std::errc()) throw Error(path_ + ": cannot format a value");
    std::fwrite(buf, 1, static_cast<size_t>(r.ptr - buf), file_);
  }
  std::fputc('\n', file_);
  ++rows_;
}

void CsvWriter::finish() {
  if (file_ == nullptr) return;
  const bool ok = std::fflush(file_) == 0 && std::ferror(file_) == 0;
  const int close_rc = std::fclose(file_);
  file_ = nullptr;
  if (!ok || close_rc != 0) throw Error(path_ + ": writing failed: " + std::strerror(errno));
}

void CsvWriter::commit() {
  if (committed_) throw Error(path_ + ": already committed");
  finish();
  moveIntoPlace(tmp_path_, path_);
  committed_ = true;
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  const std::string tmp = temporaryName(path);
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (f == nullptr) throw Error(path + ": cannot write output file: " + std::strerror(errno));
  bool ok = std::fwrite(content.data(), 1, content.size(), f) == content.size() && std::fflush(f) == 0;
  int err = ok ? 0 : errno;
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    std::remove(tmp.c_str());
    throw Error(path + ": writing failed: " + std::strerror(err));  // e.g. "No space left on device"
  }
  moveIntoPlace(tmp, path);
}

void createDirectories(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) throw InputError(path + ": cannot create output directory: " + ec.message());
}

FileLock::FileLock(const std::string& lock_file, bool exclusive, const std::string& busy_message) {
  fd_ = ::open(lock_file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(lock_file + ": cannot create the lock file: " + std::strerror(errno));
  if (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK) throw InputError(busy_message);
    throw InputError(lock_file + ": cannot lock: " + std::strerror(err));
  }
}

FileLock FileLock::onFolder(const std::string& folder, const std::string& busy_message) {
  FileLock lock;
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return lock;  // the caller finds out about the folder itself when it writes
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    if (err == EWOULDBLOCK) throw InputError(busy_message);
    return lock;  // folders cannot be locked here: go on unlocked
  }
  lock.fd_ = fd;
  return lock;
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace jointsim::io
