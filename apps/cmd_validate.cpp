// `jointsim validate FILE [--set key.path=value ...]`: checks an experiment or sweep file completely (every key,
// every referenced file, every run of a sweep) without simulating; prints what it found. Exit status 0 when the
// file is valid, 2 with the usual message (file, line, key path) otherwise.
#include <unistd.h>

#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/experiments/batch.hpp"

namespace jointsim::cli {

void addValidateCommand(CLI::App& app) {
  struct Options {
    std::string file;
    std::vector<std::string> overrides;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "Check an experiment or sweep file completely (keys, referenced files, every run) without running it");
  cmd->add_option("file", opt->file, "Experiment or sweep description (.yaml)")->required();
  cmd->add_option("--set", opt->overrides,
                  "Override a scalar as in `run`: key.path=value, or +key.path=value to add a key (repeatable)");
  cmd->callback([opt] {
    const experiments::ValidationReport r = experiments::validateFile(opt->file, opt->overrides, ::isatty(2) != 0);
    if (r.kind == "sweep")
      std::printf("%s: valid sweep '%s': %d runs of a %s experiment (each loaded with its settings)\n",
                  opt->file.c_str(), r.name.c_str(), r.runs, r.type.c_str());
    else
      std::printf("%s: valid %s experiment '%s': %d states, %d signals, %g s\n", opt->file.c_str(), r.type.c_str(),
                  r.name.c_str(), r.states, r.signals, r.duration);
    std::printf("files read:\n");
    for (const std::string& f : r.files) std::printf("  %s\n", f.c_str());
  });
}

}  // namespace jointsim::cli
