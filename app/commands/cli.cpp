#include "commands/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "splat/error.h"

#include "commands/benchmark_command.h"
#include "commands/eval_command.h"
#include "commands/generate_command.h"
#include "commands/live_command.h"
#include "commands/nearest_name.h"
#include "commands/reconstruct_command.h"
#include "commands/render_command.h"
#include "commands/version.h"
#include "commands/view_command.h"
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

// --test-every: 0 (none) or an integer >= 2.
const CLI::Validator kTestEvery(
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
    "N");

void add_backend_options(CLI::App& cmd, BackendChoice& choice) {
  cmd.add_option("--backend", choice.backend, "Rasterizer: auto, cpu or vulkan")
      ->check(CLI::IsMember({"auto", "cpu", "vulkan"}))
      ->capture_default_str();
  cmd.add_option("--device", choice.device, "Vulkan device index (default: best available)");
  cmd.add_option("--threads", choice.threads, "CPU threads (0 = all)")->check(CLI::Range(0, 256))->capture_default_str();
}

// A ROS recording's topics (found by message type unless named) and ground truth.
void add_topic_options(CLI::App& cmd, DatasetOptions& o) {
  cmd.add_option("--color-topic", o.color_topic, "ROS recording: the colour image topic (default: found by type)");
  cmd.add_option("--depth-topic", o.depth_topic, "ROS recording: the depth image topic (default: found by type)");
  cmd.add_option("--gt-frames", o.gt_frames,
                 "ROS recording: ground truth from /tf, PARENT,CHILD (e.g. world,kinect; default: groundtruth.txt beside it)");
}

// Label images from a segmenter (datasets/label_images.h), and the colour camera
// (datasets/color_registration.h): both belong to the colour images.
void add_label_option(CLI::App& cmd, DatasetOptions& o) {
  cmd.add_option("--labels", o.labels,
                 "Folder of label images (NAME.png per colour frame, class ids) with classes.json; default: labels/ "
                 "beside the colour folder when it has classes.json");
  cmd.add_option("--color-camera", o.color_camera,
                 "Colour not registered to depth: the colour camera's fx,fy,cx,cy, 'registered', or 'auto' (default: "
                 "found from where colour edges meet depth edges, applied only where that clearly beats registered)");
}

// The options benchmark and batch share: the settings of every run, and where the runs go.
void add_sequence_run_options(CLI::App& cmd, BenchmarkOptions& o) {
  cmd.add_option("--config", o.config, "JSON file with SLAM settings, the same for every sequence");
  cmd.add_option("--max-frames", o.max_frames, "Use only the first N frames of each sequence")->check(CLI::NonNegativeNumber);
  add_backend_options(cmd, o.backend);
  auto* jobs = cmd.add_option("--jobs", o.jobs, "Sequences run at once on this machine, each a child process")
                   ->check(CLI::Range(1, 256))
                   ->capture_default_str();
  auto* slurm = cmd.add_flag("--slurm", o.slurm,
                             "Run the sequences as one Slurm array job (sbatch), and merge their table in a job after "
                             "it; --out, the sequences and gslam must be on a filesystem the nodes share");
  slurm->excludes(jobs);
  cmd.add_option("--partition", o.slurm_options.partition, "--slurm: the partition (default: the cluster's)")->needs(slurm);
  cmd.add_option("--time", o.slurm_options.time_limit, "--slurm: time limit of each task, as sbatch --time (e.g. 2:00:00)")
      ->needs(slurm);
  cmd.add_option("--cpus-per-task", o.slurm_options.cpus_per_task, "--slurm: CPUs for each task")
      ->check(CLI::Range(1, 4096))
      ->needs(slurm);
  cmd.add_flag_callback("--no-wait", [&o] { o.wait = false; },
                        "--slurm: print the job ids and return; the table appears in --out when the merge job ends")
      ->needs(slurm);
}

// The commands --help lists (not the hidden ones the jobs of benchmark and batch run).
std::vector<std::string> listed_commands(const CLI::App& cli) {
  std::vector<std::string> names;
  for (const CLI::App* sub : cli.get_subcommands({})) {
    if (!sub->get_group().empty()) names.push_back(sub->get_name());
  }
  return names;
}

// The long names of a command's options ("--max-frames").
std::vector<std::string> option_names(const CLI::App& cmd) {
  std::vector<std::string> names;
  for (const CLI::Option* option : cmd.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
  }
  return names;
}

// A command line CLI11 refused, as one line that names the mistake and, for a mistyped name,
// the nearest one there is.
std::string describe_parse_error(const CLI::App& cli, const CLI::ParseError& e) {
  const CLI::App* cmd = nullptr;
  for (const CLI::App* sub : cli.get_subcommands({})) {
    if (sub->parsed()) cmd = sub;
  }
  if (!cmd && cli.remaining().empty()) {
    std::string commands;
    for (const std::string& name : listed_commands(cli)) commands += (commands.empty() ? "" : ", ") + name;
    return "give a command: " + commands + " (gslam --help describes them)";
  }
  const CLI::App& in = cmd ? *cmd : cli;
  const std::string where = cmd ? "gslam " + cmd->get_name() : "gslam";
  std::vector<std::string> extras = in.remaining();
  if (cmd) {
    for (const std::string& arg : cli.remaining()) extras.push_back(arg);
  }
  for (const std::string& arg : extras) {
    if (arg.size() < 2 || arg[0] != '-') continue;
    const std::string name = arg.substr(0, arg.find('='));
    const std::optional<std::string> near = nearest_name(name, option_names(in));
    return where + ": unknown option '" + name + "'" + (near ? "; did you mean '" + *near + "'?" : "") + " (" + where +
           " --help lists them)";
  }
  return where + ": " + e.what();
}

}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App cli{"gslam: 3D Gaussian Splatting SLAM"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", version_text(), "Print the version, the git commit and the backends built in");

  RenderOptions render;
  CLI::App* render_cmd = cli.add_subcommand(
      "render", "Render a map (.ply/.glb, or a run folder) along a path near its cameras, at them, or on an orbit");
  render_cmd->add_option("map", render.map, "Map file (.ply 3DGS, .glb/.gltf KHR_gaussian_splatting) or a reconstruct run folder")->required();
  render_cmd->add_option("--out", render.out, "Output directory")->required();
  auto* trajectory = render_cmd->add_option("--trajectory", render.trajectory, "TUM trajectory (camera to world)");
  render_cmd->add_option("--intrinsics", render.intrinsics, "fx,fy,cx,cy,W,H of the cameras");
  render_cmd->add_option("--path", render.path,
                         "Along camera poses: recorded (at them; the default with --trajectory) or novel (a smooth path "
                         "near them; the default for a run folder's own cameras)")
      ->check(CLI::IsMember({"novel", "recorded"}));
  render_cmd->add_option("--views", render.views, "Views along a novel path (default: one per pose)")->check(CLI::Range(1, kMaxOrbitViews));
  render_cmd->add_option("--offset", render.offset, "Novel path offset in each camera's axes, metres (right, down, forward)")->capture_default_str();
  auto* orbit = render_cmd->add_option("--orbit", render.orbit, "Views on an orbit (default for a map without cameras: 36)");
  render_cmd->add_option("--size", render.size, "Image size WxH where no camera is known")->capture_default_str();
  render_cmd->add_option("--up", render.up, "Orbit axis x,y,z (default: the cameras' up, else 0,0,1)");
  trajectory->excludes(orbit);
  render_cmd->add_option("--format", render.formats, "Comma-separated: png, exr, mp4 (H.264 video of the views)")->capture_default_str();
  render_cmd->add_option("--fps", render.fps, "Frame rate of the mp4")->check(CLI::Range(1.0, 240.0))->capture_default_str();
  render_cmd->add_option("--background", render.background, "Background RGB r,g,b in [0, 1]")->capture_default_str();
  render_cmd->add_flag("--overwrite", render.overwrite, "Replace the views of an earlier render in --out");
  render_cmd->add_flag("--labels", render.labels, "Draw the map's classes (fixed palette) instead of its colours");
  render_cmd->add_option("--only", render.only, "Keep only the Gaussians of these classes: names (a run folder) or ids, comma-separated");
  render_cmd->add_option("--highlight", render.highlight, "Draw the Gaussians of these classes in colour, the others grey and dim (names or ids)");
  add_backend_options(*render_cmd, render.backend);

  ReconstructOptions recon;
  CLI::App* recon_cmd = cli.add_subcommand("reconstruct", "RGB-D SLAM: trajectory and Gaussian map from a sequence");
  recon_cmd->add_option("dataset", recon.dataset,
                        "Sequence folder: TUM RGB-D (rgb.txt, depth.txt), the plain folder (the same lists + "
                        "intrinsics.txt), images (rgb/, depth/, intrinsics.txt) or Replica (results/, traj.txt); "
                        "or a ROS recording RUN.bag / RUN.mcap; docs/guide.md shows each; default: the bundled "
                        "synthetic sequence");
  recon_cmd->add_option("--out", recon.out, "Output directory (required unless --print-config)");
  recon_cmd->add_flag("--overwrite", recon.overwrite, "Replace the outputs of another run in --out");
  recon_cmd->add_flag("--resume", recon.resume, "Continue the interrupted run in --out from its checkpoint");
  recon_cmd->add_flag("--print-config", recon.print_config, "Write the effective SLAM configuration (defaults and --config) as JSON and stop");
  recon_cmd->add_option("--max-frames", recon.dataset_options.max_frames, "Use only the first N frames");
  recon_cmd->add_option("--intrinsics", recon.dataset_options.intrinsics,
                        "fx,fy,cx,cy, optionally followed by the lens distortion k1,k2,p1,p2[,k3] "
                        "(overrides the preset)");
  recon_cmd->add_option("--depth-scale", recon.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  add_topic_options(*recon_cmd, recon.dataset_options);
  add_label_option(*recon_cmd, recon.dataset_options);
  recon_cmd->add_option("--config", recon.config, "JSON file with SLAM settings");
  recon_cmd->add_option("--test-every", recon.test_every,
                        "Hold out every N-th frame as a test view: tracked, never mapped (gslam eval scores them apart)")
      ->check(kTestEvery);
  add_backend_options(*recon_cmd, recon.backend);

  EvalOptions eval;
  CLI::App* eval_cmd = cli.add_subcommand("eval", "Trajectory and rendering errors of a reconstruct run");
  eval_cmd->add_option("run", eval.run, "Output directory of gslam reconstruct")->required();
  eval_cmd->add_option("--dataset", eval.dataset, "The sequence the run used (with ground truth; default: the one its summary.json names)");
  eval_cmd->add_option("--intrinsics", eval.dataset_options.intrinsics,
                       "fx,fy,cx,cy, optionally followed by the lens distortion k1,k2,p1,p2[,k3] "
                       "(overrides the preset)");
  eval_cmd->add_option("--depth-scale", eval.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  add_topic_options(*eval_cmd, eval.dataset_options);
  add_label_option(*eval_cmd, eval.dataset_options);
  eval_cmd->add_flag("--sim3", eval.sim3, "Align with scale (similarity) instead of rigidly");
  eval_cmd->add_option("--every", eval.every, "Measure rendering quality on every N-th frame")->capture_default_str();
  add_backend_options(*eval_cmd, eval.backend);

  LiveOptions live;
  CLI::App* live_cmd = cli.add_subcommand("live", "Live SLAM on frames as they arrive, with a viewer window");
  live_cmd->add_option("source", live.source,
                       "Dataset folder or ROS recording (.bag, .mcap) to replay at its recorded rate, or with --watch the "
                       "folder a camera driver writes")->required();
  live_cmd->add_option("--out", live.out, "Output directory")->required();
  live_cmd->add_flag("--watch", live.watch, "Take frames written into SOURCE/rgb and SOURCE/depth as they appear");
  live_cmd->add_flag("--headless", live.headless, "No window (robots without a display)");
  live_cmd->add_flag("--overwrite", live.overwrite, "Replace the outputs of another run in --out");
  auto* speed = live_cmd->add_option("--speed", live.speed, "Replay rate relative to the recording")
                    ->check(kPositiveFinite)->capture_default_str();
  live_cmd->add_flag_callback("--every-frame", [&live] { live.speed = kEveryFrame; },
                              "Replay every frame, each once the previous one is tracked (none dropped, no clock); with --watch, "
                              "take every frame written, none dropped")
      ->excludes(speed);
  live_cmd->add_flag_callback("--no-catch-up", [&live] { live.catch_up = false; },
                              "At the end, write the outputs at once instead of first mapping the keyframes mapping skipped");
  live_cmd->add_option("--max-frames", live.dataset_options.max_frames,
                       "Replay only the first N frames of the recording (frames dropped among them count); with "
                       "--watch, stop after N frames are tracked");
  live_cmd->add_option("--intrinsics", live.dataset_options.intrinsics,
                       "fx,fy,cx,cy, optionally followed by the lens distortion k1,k2,p1,p2[,k3] "
                       "(overrides the preset or intrinsics.txt)");
  live_cmd->add_option("--depth-scale", live.dataset_options.depth_scale, "Depth units per metre (TUM: 5000)")->check(kPositiveFinite);
  add_topic_options(*live_cmd, live.dataset_options);
  add_label_option(*live_cmd, live.dataset_options);
  live_cmd->add_option("--idle-timeout", live.watch_options.idle_timeout, "--watch: seconds without frames that end the stream")->capture_default_str();
  live_cmd->add_option("--checkpoint-seconds", live.checkpoint_seconds, "Rewrite the outputs this often")->capture_default_str();
  live_cmd->add_option("--config", live.config, "JSON file with SLAM settings");
  live_cmd->add_option("--screenshot", live.screenshot, "Save the window to this PNG once --screenshot-after frames are tracked");
  live_cmd->add_option("--screenshot-after", live.screenshot_after, "Frames tracked before --screenshot");
  add_backend_options(*live_cmd, live.backend);

  ViewOptions view;
  CLI::App* view_cmd = cli.add_subcommand("view", "A window on a finished map and the cameras that made it (mouse and keys: README)");
  view_cmd->add_option("map", view.path, "Map file (.ply 3DGS, .glb/.gltf KHR_gaussian_splatting) or a run folder")->required();
  view_cmd->add_option("--screenshot", view.screenshot, "Save the first picture drawn to this PNG and exit");
  view_cmd->add_option("--camera", view.camera, "Start at recorded camera N (0-based, a line of trajectory.txt)");
  view_cmd->add_option("--up", view.up, "World up x,y,z (default: from the cameras and the floor, else 0,0,1)")
      ->delimiter(',')->expected(3)->check(CLI::Number);
  add_backend_options(*view_cmd, view.backend);

  BenchmarkOptions bench;
  CLI::App* bench_cmd = cli.add_subcommand(
      "benchmark", "Reconstruct and evaluate every sequence under a folder with the same settings; print their table");
  bench_cmd->add_option("folder", bench.root, "Folder of sequences (TUM, plain, Replica or images layouts, at any depth)")
      ->required();
  bench_cmd->add_option("--out", bench.out, "Output folder: a run folder per sequence, logs/, benchmark.md and .json")
      ->required();
  bench_cmd->add_option("--test-every", bench.test_every, "Hold out every N-th frame as a test view (reconstruct --test-every)")
      ->check(kTestEvery);
  bench_cmd->add_flag_callback("--no-baseline", [&bench] { bench.baseline = false; },
                               "Leave out the OpenCV RGB-D odometry baseline");
  add_sequence_run_options(*bench_cmd, bench);

  BenchmarkOptions batch;
  batch.evaluate = false;
  batch.baseline = false;
  CLI::App* batch_cmd = cli.add_subcommand(
      "batch", "Reconstruct every sequence under a folder or in a list, with the same settings; print their summary table");
  batch_cmd->add_option("sequences", batch.root,
                        "Folder of sequences (any layout, at any depth), or a text file naming sequence folders, one a "
                        "line (relative to the file)")
      ->required();
  batch_cmd->add_option("--out", batch.out, "Output folder: a run folder per sequence, logs/, batch.md and .json")
      ->required();
  add_sequence_run_options(*batch_cmd, batch);

  // What the jobs of benchmark and batch run (--jobs, --slurm); hidden from --help.
  std::filesystem::path task_out;
  std::size_t task_index = 0;
  CLI::App* task_cmd = cli.add_subcommand("benchmark-task", "Run task INDEX of the plan in OUT")->group("");
  task_cmd->add_option("out", task_out, "The --out of benchmark or batch")->required();
  task_cmd->add_option("index", task_index, "Task index (the Slurm array task id)")->required();
  CLI::App* merge_cmd = cli.add_subcommand("benchmark-merge", "Merge the run folders of the plan in OUT into its table")->group("");
  merge_cmd->add_option("out", task_out, "The --out of benchmark or batch")->required();

  GenerateOptions gen;
  CLI::App* gen_cmd = cli.add_subcommand(
      "generate", "Write a synthetic RGB-D sequence with exact ground truth (TUM layout), or the hard-case suite");
  gen_cmd->add_option("out", gen.out, "Output folder")->required();
  gen_cmd->add_flag("--suite", gen.suite, "The hard cases every default is checked on, a folder each (for gslam benchmark)");
  gen_cmd->add_flag("--overwrite", gen.overwrite, "Replace what an earlier generate wrote in the folder");
  SyntheticOptions& seq = gen.sequence;
  gen_cmd->add_option("--frames", seq.frames, "Frames")->check(CLI::Range(1, 100000));
  gen_cmd->add_option("--width", seq.width, "Image width")->check(CLI::Range(8, 8192));
  gen_cmd->add_option("--height", seq.height, "Image height")->check(CLI::Range(8, 8192));
  gen_cmd->add_option("--laps", seq.laps, "Laps of a circle back to the start (0: an arc through the room)")
      ->check(CLI::Range(0, 100));
  gen_cmd->add_option("--shake", seq.shake_peak_rate, "Yaw shake on top of the path, peak rate in rad/s")
      ->check(CLI::Range(0.0, 50.0));
  gen_cmd->add_option("--exposure", seq.exposure, "Motion blur: exposure in seconds (with --blur-samples)")
      ->check(CLI::Range(0.0, 1.0));
  gen_cmd->add_option("--blur-samples", seq.blur_samples, "Instants averaged over the exposure")->check(CLI::Range(1, 64));
  gen_cmd->add_option("--depth-noise", seq.depth_noise, "Depth noise in metres at 1 m, growing with depth squared")
      ->check(CLI::Range(0.0, 1.0));
  gen_cmd->add_option("--depth-holes", seq.depth_holes, "Fraction of pixels without depth, in blobs")
      ->check(CLI::Range(0.0, 0.99));
  gen_cmd->add_option("--depth-lag", seq.depth_lag,
                      "Depth taken up to this many seconds before or after its colour image (unsynchronized cameras)")
      ->check(CLI::Range(0.0, 0.1));
  gen_cmd
      ->add_option("--rolling-shutter", seq.rolling_shutter,
                   "Rolling shutter: colour and depth rows read top to bottom over this many seconds "
                   "(Kinect class: about 0.03)")
      ->check(CLI::Range(0.0, 1.0));
  gen_cmd
      ->add_option("--gain-swing", seq.gain_swing,
                   "Auto exposure hunting: the colour gain swings as exp(S sin(2 pi t / 3 s)), "
                   "saturating at white")
      ->check(CLI::Range(0.0, 2.0));
  gen_cmd->add_option("--focal-error", seq.focal_error, "intrinsics.txt's focal length off by this fraction")
      ->check(CLI::Range(-0.5, 0.5));
  gen_cmd
      ->add_option("--color-focal-ratio", seq.color_focal_ratio,
                   "Colour not registered to depth: the colour camera's focal length over the depth camera's")
      ->check(CLI::Range(0.5, 2.0));
  gen_cmd->add_option(
      "--distortion", gen.distortion,
      "k1,k2,p1,p2[,k3]: the images seen through a lens with this distortion (OpenCV's "
      "model; TUM fr1: 0.262383,-0.953104,-0.005358,0.002628,1.163314), stated in intrinsics.txt");
  gen_cmd->add_flag("--movers", seq.movers,
                    "People and objects moving through the room: a person walking across, a chair pushed, a crate appearing");
  CLI::Option* walkers = gen_cmd->add_flag("--walkers", seq.walkers,
                                           "Two people pacing across the view for the whole sequence, one near the "
                                           "camera (TUM's fr3/walking)");
  gen_cmd->add_flag("--patterned-walkers", seq.patterned_walkers,
                    "The walkers in patterned shirts, their motion showing all over them (plain: striped along their "
                    "walk, only their outlines show it)")
      ->needs(walkers);
  gen_cmd->add_flag("--labels", seq.labels, "Exact class ids per pixel in labels/, with labels/classes.json");
  gen_cmd->add_option("--seed", seq.seed, "Random seed (noise, holes)");
  gen_cmd->callback([gen_cmd, &gen] {
    if (!gen.suite) return;
    // Every option but these describes one sequence.
    for (const CLI::Option* option : gen_cmd->get_options()) {
      const std::string name = option->get_name();
      if (name == "--suite" || name == "--overwrite" || name == "--help" || option->get_positional()) continue;
      if (option->count() > 0) throw CLI::ValidationError(name + " describes one sequence; --suite writes its own");
    }
  });

  // A mistyped command: CLI11 would only say that one is required.
  const std::vector<std::string> commands = listed_commands(cli);
  const auto known = [&](const std::string& name) {
    for (const CLI::App* sub : cli.get_subcommands({})) {
      if (sub->get_name() == name) return true;
    }
    return false;
  };
  if (argc > 1 && argv[1][0] != '-' && !known(argv[1])) {
    const std::optional<std::string> near = nearest_name(argv[1], commands);
    throw splat::Error(std::string("unknown command '") + argv[1] + "'" + (near ? "; did you mean '" + *near + "'?" : "") +
                       " (gslam --help lists them)");
  }
  try {
    cli.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return cli.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return cli.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return cli.exit(e);
  } catch (const CLI::ParseError& e) {
    throw splat::Error(describe_parse_error(cli, e));
  }
  if (render_cmd->parsed()) return run_render(render);
  if (recon_cmd->parsed()) {
    if (recon.dataset_options.max_frames < 0) throw splat::Error("--max-frames must be >= 0");
    return run_reconstruct(recon);
  }
  if (eval_cmd->parsed()) return run_eval(eval);
  if (view_cmd->parsed()) return run_view(view);
  if (bench_cmd->parsed()) return run_benchmark(bench);
  if (batch_cmd->parsed()) return run_benchmark(batch);
  if (task_cmd->parsed()) return run_benchmark_task(task_out, task_index);
  if (merge_cmd->parsed()) return run_benchmark_merge(task_out);
  if (gen_cmd->parsed()) return run_generate(gen);
  if (live_cmd->parsed()) {
    if (live.dataset_options.max_frames < 0) throw splat::Error("--max-frames must be >= 0");
    if (!live.dataset_options.intrinsics.empty()) live.watch_options.intrinsics = live.dataset_options.intrinsics;
    if (live.dataset_options.depth_scale > 0) live.watch_options.depth_scale = live.dataset_options.depth_scale;
    parse_color_camera(live.dataset_options.color_camera);  // a bad value fails before any frame
    live.watch_options.color_camera = live.dataset_options.color_camera;
    return run_live(live);
  }
  return 2;
}

}  // namespace app
