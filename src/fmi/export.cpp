// FMU export: the experiment's files into resources/, the binary and the libraries it carries into
// binaries/linux64/, modelDescription.xml; a zip archive (libzip) written to a temporary name and renamed.
#include <unistd.h>
#include <zip.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/fmi/fmu.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/output.hpp"

#ifndef JOINTSIM_FMU_BUILD_DIR
#define JOINTSIM_FMU_BUILD_DIR ""
#endif
#ifndef JOINTSIM_FMU_INSTALL_DIR
#define JOINTSIM_FMU_INSTALL_DIR "lib/jointsim/fmu/linux64"
#endif

namespace fs = std::filesystem;

namespace jointsim::fmi {

namespace {

bool isIdentifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

/// The bytes of a file the FMU carries (io::readBoundedFile; none of them is empty).
std::string readAll(const fs::path& p) {
  std::string bytes = io::readBoundedFile(p.string());
  if (bytes.empty()) throw Error("FMU export: cannot read " + p.string());
  return bytes;
}

/// The zip archive being written; discarded (and its temporary file removed) unless closed.
class ZipWriter {
 public:
  explicit ZipWriter(const std::string& path) : path_(path) {
    int err = 0;
    zip_ = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    if (zip_ == nullptr)
      throw Error("FMU export: cannot create " + path + " (libzip error " + std::to_string(err) + ")");
  }
  ~ZipWriter() {
    if (zip_ != nullptr) zip_discard(zip_);
  }
  void add(const std::string& name, std::string bytes) {
    data_.push_back(std::make_unique<std::string>(std::move(bytes)));
    zip_source_t* src = zip_source_buffer(zip_, data_.back()->data(), data_.back()->size(), 0);
    const zip_int64_t index =
        src == nullptr ? -1 : zip_file_add(zip_, name.c_str(), src, ZIP_FL_OVERWRITE | ZIP_FL_ENC_UTF_8);
    if (index < 0) {
      if (src != nullptr) zip_source_free(src);
      throw Error("FMU export: cannot add " + name + " to " + path_ + ": " + zip_strerror(zip_));
    }
    // Unix permissions of the entry: rw-r--r-- (rwxr-xr-x for the shared library), never writable by others.
    const bool library = name.size() > 3 && name.compare(name.size() - 3, 3, ".so") == 0;
    const zip_uint32_t mode = library ? 0100755U : 0100644U;
    if (zip_file_set_external_attributes(zip_, static_cast<zip_uint64_t>(index), 0, ZIP_OPSYS_UNIX, mode << 16) < 0)
      throw Error("FMU export: cannot set the permissions of " + name + " in " + path_ + ": " + zip_strerror(zip_));
  }
  void close() {
    if (zip_close(zip_) != 0) throw Error("FMU export: cannot write " + path_ + ": " + zip_strerror(zip_));
    zip_ = nullptr;
  }

 private:
  std::string path_;
  zip_t* zip_ = nullptr;
  std::vector<std::unique_ptr<std::string>> data_;  // alive until zip_close
};

}  // namespace

std::string defaultBinaryDir() {
  if (const char* env = std::getenv("JOINTSIM_FMU_BINARY_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path install_dir(JOINTSIM_FMU_INSTALL_DIR);  // the installation's lib folder (may be absolute)
    for (const fs::path& dir :
         {exe.parent_path() / "fmu" / "linux64",
          install_dir.is_absolute() ? install_dir : exe.parent_path().parent_path() / install_dir}) {
      if (io::isRegularFile((dir / "jointsim_fmu.so").string())) return dir.string();
    }
  }
  return JOINTSIM_FMU_BUILD_DIR;
}

FmuDescription exportFmu(const std::string& config, const std::string& fmu_path, const ExportOptions& options) {
  // The DefaultExperiment's stepSize: a schema-valid, usable communication step.
  if (!(options.step_size > 0.0) || !std::isfinite(options.step_size) || options.step_size > 1e6)
    throw InputError("FMU export: step size: expected a communication step > 0 s and at most 1e6 s, got " +
                     formatNumber(options.step_size));
  const fs::path out(fmu_path);
  if (out.extension() != ".fmu") throw InputError("FMU export: output file " + fmu_path + " must end in .fmu");
  if (std::error_code ec; !out.parent_path().empty() && !fs::is_directory(out.parent_path(), ec))
    throw InputError("FMU export: output folder '" + out.parent_path().string() + "' does not exist");
  const std::string model_identifier = out.stem().string();
  if (!isIdentifier(model_identifier))
    throw InputError("FMU export: the file name '" + model_identifier +
                     "' is the FMU's model identifier and must be a C identifier (letters, digits, _)");

  std::unique_ptr<experiments::Experiment> e = experiments::loadExperiment(config, options.overrides);
  experiments::checkRunSettings(*e);  // what jointsim run refuses, the FMU refuses at export
  FmuDescription d = describe(*e, options, model_identifier);
  d.overrides = options.overrides;

  // The files read, in their layout relative to their common folder.
  std::vector<fs::path> files;
  for (const io::InputFile& f : e->inputs()) files.emplace_back(f.path);
  if (files.empty()) throw InputError("FMU export: the experiment read no files");
  fs::path root = files.front().parent_path();
  for (const fs::path& f : files) {
    while (!root.empty() && fs::relative(f, root).string().rfind("..", 0) == 0) root = root.parent_path();
  }
  d.experiment_file = fs::relative(fs::path(e->inputs().front().path), root).generic_string();

  // Check that the copy is self-contained: the experiment loaded from a copy of the files reads only those.
  const fs::path tmpdir = fs::temp_directory_path() / ("jointsim_fmu_" + std::to_string(::getpid()) + "_" +
                                                       std::to_string(reinterpret_cast<std::uintptr_t>(&d)));
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{tmpdir};
  std::vector<std::pair<std::string, std::string>> resources;  // name in the archive, bytes
  for (const fs::path& f : files) {
    const std::string rel = fs::relative(f, root).generic_string();
    std::string bytes = readAll(f);
    fs::create_directories((tmpdir / rel).parent_path());
    std::ofstream(tmpdir / rel, std::ios::binary) << bytes;
    resources.emplace_back("resources/" + rel, std::move(bytes));
  }
  {
    std::unique_ptr<experiments::Experiment> copy =
        experiments::loadExperiment((tmpdir / d.experiment_file).string(), options.overrides);
    const std::string inside = fs::weakly_canonical(tmpdir).string() + "/";
    for (const io::InputFile& f : copy->inputs()) {
      if (f.path.rfind(inside, 0) != 0)
        throw InputError("FMU export: " + config + " reads " + f.path +
                         " through an absolute path; the FMU must carry its files: refer to it by a relative path");
    }
  }

  // GUID: from the description and the files' content.
  std::string stamp = d.toJson().dump();
  for (const auto& r : resources) stamp += r.first + io::contentHash(r.second);
  const std::string h = io::contentHash(stamp).substr(5);  // 16 hex digits
  const std::string h2 = io::contentHash(h + stamp).substr(5);
  d.guid = "{" + h.substr(0, 8) + "-" + h.substr(8, 4) + "-" + h.substr(12, 4) + "-" + h2.substr(0, 4) + "-" +
           h2.substr(4, 12) + "}";

  const std::string bin_dir = options.binary_dir.empty() ? defaultBinaryDir() : options.binary_dir;
  const fs::path binary = fs::path(bin_dir) / "jointsim_fmu.so";
  if (bin_dir.empty() || !io::isRegularFile(binary.string()))
    throw Error("FMU export: the FMU binary jointsim_fmu.so was not found in '" + bin_dir +
                "' (build the target jointsim_fmu, or set JOINTSIM_FMU_BINARY_DIR)");

  const std::string tmp = io::temporaryName(fmu_path);
  {
    ZipWriter zip(tmp);
    zip.add("modelDescription.xml", d.modelDescriptionXml());
    for (auto& r : resources) zip.add(r.first, std::move(r.second));
    zip.add("resources/jointsim_fmu.json", d.toJson().dump(2) + "\n");
    for (const auto& entry : fs::directory_iterator(bin_dir)) {
      if (!entry.is_regular_file()) continue;
      const std::string name = entry.path().filename().string();
      zip.add("binaries/linux64/" + (name == "jointsim_fmu.so" ? model_identifier + ".so" : name),
              readAll(entry.path()));
    }
    zip.close();
  }
  io::moveIntoPlace(tmp, fmu_path);
  return d;
}

}  // namespace jointsim::fmi
