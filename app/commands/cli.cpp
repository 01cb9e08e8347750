#include "commands/cli.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>

#include "splat/error.h"

#include "commands/eval_command.h"
#include "commands/live_command.h"
#include "commands/reconstruct_command.h"
#include "commands/render_command.h"
#include "viewer/views.h"

namespace app {
namespace {

// A finite number above zero (CLI11's PositiveNumber lets NaN through).
const CLI::Validator kPositiveFinite(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || !(v > 0)) {
        return "expected a finite number > 0, got '" + text + "'";
      }
      return {};
    },
    "POSITIVE");

void add_backend_options(CLI::App& cmd, BackendChoice& choice) {
  cmd.add_option("--backend", choice.backend, "Rasterizer: auto, cpu or vulkan")
      ->check(CLI::IsMember({"auto", "cpu", "vulkan"}))
      ->capture_default_str();
  cmd.add_option("--device", choice.device, "Vulkan device index (default: best available)");
  cmd.add_option("--threads", choice.threads, "CPU threads (0 = all)")->check(CLI::Range(0, 256))->capture_default_str();
}

}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App cli{"gslam: 3D Gaussian Splatting SLAM"};
  cli.require_subcommand(1);

  RenderOptions render;
  CLI::App* render_cmd = cli.add_subcommand(
      "render", "Render a map (.ply/.glb, or a run folder) along a path near its cameras, at them, or on an orbit");
  render_cmd->add_option("map", render.map, "Map file (.ply 3DGS, .glb/.gltf KHR_gaussian_splatting) or a reconstruct run folder")->required();
  render_cmd->add_option("--out", render.out, "Output directory")->required();
  auto* trajectory = render_cmd->add_option("--trajectory", render.trajectory, "TUM trajectory (camera to world)");
  render_cmd->add_option("--intrinsics", render.intrinsics, "fx,fy,cx,cy,W,H of the cameras");
  render_cmd->add_option("--path", render.path, "Along camera poses: novel (a smooth path near them) or recorded (at them)")
      ->check(CLI::IsMember({"novel", "recorded"}))->capture_default_str();
  render_cmd->add_option("--views", render.views, "Views along a novel path (default: one per pose)")->check(CLI::Range(1, kMaxOrbitViews));
  render_cmd->add_option("--offset", render.offset, "Novel path offset in each camera's axes, metres (right, down, forward)")->capture_default_str();
  auto* orbit = render_cmd->add_option("--orbit", render.orbit, "Views on an orbit (default for a map without cameras: 36)");
  render_cmd->add_option("--size", render.size, "Image size WxH where no camera is known")->capture_default_str();
  render_cmd->add_option("--up", render.up, "Orbit axis x,y,z (default: the cameras' up, else 0,0,1)");
  trajectory->excludes(orbit);
  render_cmd->add_option("--format", render.formats, "Comma-separated: png, exr, mp4 (H.264 video of the views)")->capture_default_str();
  render_cmd->add_option("--fps", render.fps, "Frame rate of the mp4")->check(CLI::Range(1.0, 240.0))->capture_default_str();
  render_cmd->add_option("--background", render.background, "Background RGB r,g,b in [0, 1]")->capture_default_str();
  add_backend_options(*render_cmd, render.backend);

  ReconstructOptions recon;
  CLI::App* recon_cmd = cli.add_subcommand("reconstruct", "RGB-D SLAM: trajectory and Gaussian map from a sequence");
  recon_cmd->add_option("dataset", recon.dataset, "TUM RGB-D folder (default: the bundled synthetic sequence)");
  recon_cmd->add_option("--out", recon.out, "Output directory (required unless --print-config)");
  recon_cmd->add_flag("--overwrite", recon.overwrite, "Replace the outputs of another run in --out");
  recon_cmd->add_flag("--resume", recon.resume, "Continue the interrupted run in --out from its checkpoint");
  recon_cmd->add_flag("--print-config", recon.print_config, "Write the effective SLAM configuration (defaults and --config) as JSON and stop");
  recon_cmd->add_option("--max-frames", recon.dataset_options.max_frames, "Use only the first N frames");
  recon_cmd->add_option("--intrinsics", recon.dataset_options.intrinsics, "fx,fy,cx,cy (overrides the preset)");
  recon_cmd->add_option("--depth-scale", recon.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  recon_cmd->add_option("--config", recon.config, "JSON file with SLAM settings");
  recon_cmd->add_option("--test-every", recon.test_every,
                        "Hold out every N-th frame as a test view: tracked, never mapped (gslam eval scores them apart)")
      ->check(CLI::Validator(
          [](const std::string& text) -> std::string {
            const std::string expected = "expected 0 (none) or an integer >= 2, got '" + text + "'";
            std::size_t used = 0;
            try {
              const long v = std::stol(text, &used);
              return used == text.size() && (v == 0 || (v >= 2 && v <= 1000000)) ? std::string() : expected;
            } catch (const std::exception&) {
              return expected;
            }
          },
          "N"));
  add_backend_options(*recon_cmd, recon.backend);

  EvalOptions eval;
  CLI::App* eval_cmd = cli.add_subcommand("eval", "Trajectory and rendering errors of a reconstruct run");
  eval_cmd->add_option("run", eval.run, "Output directory of gslam reconstruct")->required();
  eval_cmd->add_option("--dataset", eval.dataset, "The sequence the run used (with ground truth; default: the one its summary.json names)");
  eval_cmd->add_option("--intrinsics", eval.dataset_options.intrinsics, "fx,fy,cx,cy (overrides the preset)");
  eval_cmd->add_option("--depth-scale", eval.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  eval_cmd->add_flag("--sim3", eval.sim3, "Align with scale (similarity) instead of rigidly");
  eval_cmd->add_option("--every", eval.every, "Measure rendering quality on every N-th frame")->capture_default_str();
  add_backend_options(*eval_cmd, eval.backend);

  LiveOptions live;
  CLI::App* live_cmd = cli.add_subcommand("live", "Live SLAM on frames as they arrive, with a viewer window");
  live_cmd->add_option("source", live.source, "Dataset folder to replay at its recorded rate, or with --watch the folder a camera driver writes")->required();
  live_cmd->add_option("--out", live.out, "Output directory")->required();
  live_cmd->add_flag("--watch", live.watch, "Take frames written into SOURCE/rgb and SOURCE/depth as they appear");
  live_cmd->add_flag("--headless", live.headless, "No window (robots without a display)");
  live_cmd->add_flag("--overwrite", live.overwrite, "Replace the outputs of another run in --out");
  live_cmd->add_option("--speed", live.speed, "Replay rate relative to the recording")->capture_default_str();
  live_cmd->add_option("--max-frames", live.dataset_options.max_frames, "Stop after tracking N frames");
  live_cmd->add_option("--intrinsics", live.dataset_options.intrinsics, "fx,fy,cx,cy (overrides the preset or intrinsics.txt)");
  live_cmd->add_option("--depth-scale", live.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  live_cmd->add_option("--idle-timeout", live.watch_options.idle_timeout, "--watch: seconds without frames that end the stream")->capture_default_str();
  live_cmd->add_option("--checkpoint-seconds", live.checkpoint_seconds, "Rewrite the outputs this often")->capture_default_str();
  live_cmd->add_option("--config", live.config, "JSON file with SLAM settings");
  live_cmd->add_option("--screenshot", live.screenshot, "Save the window to this PNG once --screenshot-after frames are tracked");
  live_cmd->add_option("--screenshot-after", live.screenshot_after, "Frames tracked before --screenshot");
  add_backend_options(*live_cmd, live.backend);

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e);
  }
  if (render_cmd->parsed()) return run_render(render);
  if (recon_cmd->parsed()) {
    if (recon.dataset_options.max_frames < 0) throw splat::Error("--max-frames must be >= 0");
    return run_reconstruct(recon);
  }
  if (eval_cmd->parsed()) return run_eval(eval);
  if (live_cmd->parsed()) {
    if (live.dataset_options.max_frames < 0) throw splat::Error("--max-frames must be >= 0");
    if (!live.dataset_options.intrinsics.empty()) live.watch_options.intrinsics = live.dataset_options.intrinsics;
    if (live.dataset_options.depth_scale > 0) live.watch_options.depth_scale = live.dataset_options.depth_scale;
    return run_live(live);
  }
  return 2;
}

}  // namespace app
