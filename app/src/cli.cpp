#include "app/cli.h"

#include <CLI/CLI.hpp>

#include "app/render_command.h"

namespace app {
namespace {

void add_backend_options(CLI::App& cmd, BackendChoice& choice) {
  cmd.add_option("--backend", choice.backend, "Rasterizer: auto, cpu or vulkan")
      ->check(CLI::IsMember({"auto", "cpu", "vulkan"}))
      ->capture_default_str();
  cmd.add_option("--device", choice.device, "Vulkan device index (default: best available)");
  cmd.add_option("--threads", choice.threads, "CPU threads (0 = all)")->capture_default_str();
}

}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App cli{"gslam: 3D Gaussian Splatting SLAM"};
  cli.require_subcommand(1);

  RenderOptions render;
  CLI::App* render_cmd = cli.add_subcommand("render", "Render a map (.ply/.glb) along a trajectory or an orbit");
  render_cmd->add_option("map", render.map, "Map file: .ply (3DGS) or .glb/.gltf (KHR_gaussian_splatting)")->required();
  render_cmd->add_option("--out", render.out, "Output directory")->required();
  auto* trajectory = render_cmd->add_option("--trajectory", render.trajectory, "TUM trajectory (camera to world)");
  render_cmd->add_option("--intrinsics", render.intrinsics, "fx,fy,cx,cy,W,H for --trajectory")->needs(trajectory);
  auto* orbit = render_cmd->add_option("--orbit", render.orbit, "Views on a turntable orbit")->capture_default_str();
  render_cmd->add_option("--size", render.size, "Orbit image size WxH")->capture_default_str();
  render_cmd->add_option("--up", render.up, "Orbit axis x,y,z")->capture_default_str();
  trajectory->excludes(orbit);
  render_cmd->add_option("--format", render.formats, "png, exr or png,exr")->capture_default_str();
  render_cmd->add_option("--background", render.background, "Background RGB r,g,b in [0, 1]")->capture_default_str();
  add_backend_options(*render_cmd, render.backend);

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  }
  if (render_cmd->parsed()) return run_render(render);
  return 2;
}

}  // namespace app
