// `jointsim view RUN_DIR [-o FILE.html]`: one self-contained interactive HTML page of a run or sweep folder.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/report/view.hpp"

namespace jointsim::cli {

void addViewCommand(CLI::App& app) {
  struct Options {
    std::string dir, output;
    report::ViewOptions view;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "view", "Write one self-contained HTML page of a run or sweep folder: the arm animated in 3D, interactive plots, "
              "the summary (opens offline in any current browser)");
  cmd->add_option("dir", opt->dir, "Output folder of `jointsim run` or `jointsim batch`")->required();
  cmd->add_option("-o,--output", opt->output, "The page to write (default: DIR/view.html)");
  cmd->add_option("--columns", opt->view.columns,
                  "Slices per plotted series: each keeps the rows of its minimum and maximum (peaks kept)")
      ->capture_default_str();
  cmd->add_option("--frames", opt->view.frames, "Most animation samples per run (the log's rows are strided beyond)")
      ->capture_default_str();
  cmd->add_option("--mesh-bytes", opt->view.mesh_bytes,
                  "Most bytes of URDF visual meshes embedded in the page (meshes beyond are listed as not drawn)")
      ->capture_default_str();
  cmd->add_option("--title", opt->view.title, "Page title (default: the experiment's or the sweep folder's name)");
  cmd->callback([opt] {
    const std::string path = report::writeView(opt->dir, opt->output, opt->view);
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(path, ec);
    std::printf("page: %s (%.1f MB); open it in a browser (no server needed)\n", path.c_str(),
                ec ? 0.0 : static_cast<double>(bytes) / 1.0e6);
  });
}

}  // namespace jointsim::cli
