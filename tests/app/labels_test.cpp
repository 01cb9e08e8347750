// Label images through the commands: generate --labels, reconstruct (the map's classes fused
// into map.ply), eval (mIoU against label images, held-out views apart), with clean and with
// noisy labels; and the one-line errors of bad label folders.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "app/run_gslam.h"
#include "commands/label_maps.h"
#include "datasets/dataset.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "support/json_file.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::RunResult;
using gslam::test::TempDir;

// The last line of a command's output (errors found while reading frames follow its progress).
std::string last_line(const std::string& output) {
  const std::size_t end = output.find_last_not_of('\n');
  if (end == std::string::npos) return "";
  const std::size_t start = output.rfind('\n', end);
  return output.substr(start == std::string::npos ? 0 : start + 1, end + 1 - (start == std::string::npos ? 0 : start + 1)) + "\n";
}

using gslam::test::read_json;

// A copy of `from`'s label images in `to` with `share` of their pixels set to a random listed
// class (another class or the same: what a poor segmenter gets wrong).
void corrupt_labels(const std::filesystem::path& from, const std::filesystem::path& to, double share) {
  std::filesystem::create_directories(to);
  std::filesystem::copy_file(from / "classes.json", to / "classes.json");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coin(0, 1);
  std::uniform_int_distribution<int> id(1, 5);  // the static room's classes (wall..cabinet)
  for (const auto& entry : std::filesystem::directory_iterator(from)) {
    if (entry.path().extension() != ".png") continue;
    splat::Image16 labels = app::read_png_gray16(entry.path());
    for (uint16_t& l : labels.data) {
      if (coin(rng) < share) l = static_cast<uint16_t>(id(rng));
    }
    app::write_png_gray16(to / entry.path().filename(), labels);
  }
}

// render --labels draws the classes at the run's first pose in the palette that the given label
// image takes there; --only keeps the Gaussians of the classes named.
void expect_renders_classes(const TempDir& dir, const std::string& run) {
  const std::string out = (dir / "render").string();
  const RunResult r = run_gslam("render " + run + " --out " + out + " --labels --path recorded");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const app::Dataset d = app::open_dataset(dir / "seq", {});
  const std::vector<uint8_t> expected = app::label_colours(d.load(0).labels);
  const splat::Image8 drawn = app::read_png_rgb8(std::filesystem::path(out) / "view_0000.png");
  ASSERT_EQ(drawn.data.size(), expected.size());
  std::size_t same = 0;
  for (std::size_t p = 0; p < expected.size(); p += 3) {
    same += std::equal(expected.begin() + static_cast<std::ptrdiff_t>(p), expected.begin() + static_cast<std::ptrdiff_t>(p + 3),
                       drawn.data.begin() + static_cast<std::ptrdiff_t>(p));
  }
  EXPECT_GT(static_cast<double>(same) / static_cast<double>(expected.size() / 3), 0.9);

  // --highlight wall: at the same pose, wall pixels keep the plain render's colour and the others
  // turn grey.
  const RunResult plain = run_gslam("render " + run + " --out " + (dir / "plain").string() + " --path recorded");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const RunResult walls = run_gslam("render " + run + " --out " + (dir / "walls").string() + " --path recorded --highlight wall");
  ASSERT_EQ(walls.exit_code, 0) << walls.output;
  const splat::Image8 coloured = app::read_png_rgb8(dir / "plain" / "view_0000.png");
  const splat::Image8 highlighted = app::read_png_rgb8(dir / "walls" / "view_0000.png");
  const std::vector<uint16_t>& truth = d.load(0).labels;
  const uint16_t wall = 1;  // the generator's class ids (classes.json)
  std::size_t wall_pixels = 0, wall_kept = 0, other_pixels = 0, other_grey = 0, other_coloured_before = 0;
  for (std::size_t p = 0; p < truth.size(); ++p) {
    const uint8_t* a = &coloured.data[3 * p];
    const uint8_t* b = &highlighted.data[3 * p];
    const bool grey = std::abs(b[0] - b[1]) <= 2 && std::abs(b[1] - b[2]) <= 2;
    if (truth[p] == wall) {
      ++wall_pixels;
      wall_kept += std::abs(a[0] - b[0]) <= 3 && std::abs(a[1] - b[1]) <= 3 && std::abs(a[2] - b[2]) <= 3;
    } else if (truth[p] != 0) {
      ++other_pixels;
      other_grey += grey;
      other_coloured_before += !(std::abs(a[0] - a[1]) <= 2 && std::abs(a[1] - a[2]) <= 2);
    }
  }
  ASSERT_GT(wall_pixels, truth.size() / 20) << "the first view shows walls";
  EXPECT_GT(double(wall_kept) / double(wall_pixels), 0.8);
  EXPECT_GT(double(other_grey) / double(other_pixels), 0.8);
  EXPECT_GT(double(other_coloured_before) / double(other_pixels), 0.5) << "the plain render is in colour";

  const RunResult only = run_gslam("render " + run + " --out " + (dir / "balls").string() + " --only ball --orbit 2");
  ASSERT_EQ(only.exit_code, 0) << only.output;
  EXPECT_NE(only.output.find("--only ball: "), std::string::npos) << only.output;
  const RunResult unknown = run_gslam("render " + run + " --out " + (dir / "sofas").string() + " --only sofa");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_EQ(last_line(unknown.output),
            "error: --only: unknown class 'sofa' (the run's classes: ball, cabinet, ceiling, chair, crate, floor, person, wall)\n");
}

TEST(CliLabels, FusedClassesRenderBackOnHeldOutViewsEvenFromNoisyLabels) {
  TempDir dir;
  const std::string seq = (dir / "seq").string();
  ASSERT_EQ(run_gslam("generate " + seq + " --frames 48 --labels").exit_code, 0);
  corrupt_labels(dir / "seq" / "labels", dir / "noisy", 0.2);
  double clean_confidence = 0;
  for (const bool noisy : {false, true}) {
    const std::string run = (dir / (noisy ? "noisy_run" : "run")).string();
    const std::string labels = noisy ? " --labels " + (dir / "noisy").string() : "";
    const RunResult r = run_gslam("reconstruct " + seq + " --out " + run + " --test-every 8" + labels);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // map.ply carries each Gaussian's classes; summary.json counts them.
    const app::LoadedMap map = app::load_map(std::filesystem::path(run) / "map.ply");
    ASSERT_EQ(map.labels.size(), map.gaussians.size());
    // The noisy labels were the ones fused: each Gaussian is less sure of its class.
    double confidence = 0;
    for (std::size_t i = 0; i < map.labels.size(); ++i) confidence += map.labels.probabilities[i * map.labels.top];
    confidence /= static_cast<double>(map.labels.size());
    if (noisy) {
      EXPECT_LT(confidence, clean_confidence - 0.05);
    } else {
      clean_confidence = confidence;
    }
    const nlohmann::json summary = read_json(std::filesystem::path(run) / "summary.json");
    EXPECT_GT(summary.at("labels").at("classes").at("wall").get<std::size_t>(), 0u);
    EXPECT_TRUE(summary.at("dynamic").at("ghosts_removed").is_number_unsigned());
    // Scored against the clean labels (beside the colour folder), whatever the run was given.
    const RunResult e = run_gslam("eval " + run);
    ASSERT_EQ(e.exit_code, 0) << e.output;
    const nlohmann::json labels_eval = read_json(std::filesystem::path(run) / "eval.json").at("labels");
    const double held_out = labels_eval.at("held_out").at("miou").get<double>();
    std::printf("%s labels: mean top probability %.3f, mIoU %.3f, held-out views %.3f\n", noisy ? "20% corrupted" : "clean",
                confidence, labels_eval.at("miou").get<double>(), held_out);
    EXPECT_GE(held_out, noisy ? 0.85 : 0.9);
    EXPECT_EQ(labels_eval.at("held_out").at("views").get<int>(), 6);  // frames 0, 8, ..., 40
    for (const char* name : {"wall", "floor", "ball", "cabinet"}) EXPECT_TRUE(labels_eval.at("per_class").contains(name)) << name;
    if (!noisy) expect_renders_classes(dir, run);
  }
  // live fuses the recording's label images too.
  const std::filesystem::path live = dir / "live";
  const RunResult l = run_gslam("live " + seq + " --out " + live.string() + " --headless --every-frame");
  ASSERT_EQ(l.exit_code, 0) << l.output;
  const app::LoadedMap live_map = app::load_map(live / "map.ply");
  EXPECT_EQ(live_map.labels.size(), live_map.gaussians.size());
  EXPECT_GT(read_json(live / "summary.json").at("labels").at("classes").at("floor").get<std::size_t>(), 0u);
}

TEST(CliLabels, BadLabelFoldersAreOneLineErrors) {
  TempDir dir;
  const std::string seq = (dir / "seq").string();
  ASSERT_EQ(run_gslam("generate " + seq + " --frames 3 --width 32 --height 24 --labels").exit_code, 0);
  const std::filesystem::path labels = dir / "seq" / "labels";
  const std::string first = app::open_dataset(dir / "seq", {}).entries.front().rgb.stem().string();
  const std::string out = " --out " + (dir / "run").string() + " --overwrite";

  // A class id classes.json does not list.
  splat::Image16 image = app::read_png_gray16(labels / (first + ".png"));
  image.data[5] = 99;
  app::write_png_gray16(labels / (first + ".png"), image);
  RunResult r = run_gslam("reconstruct " + seq + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(last_line(r.output), "error: " + (labels / (first + ".png")).string() + ": class id 99 is not in " +
                          (labels / "classes.json").string() + "\n");
  // A label image of another size.
  app::write_png_gray16(labels / (first + ".png"), splat::Image16(16, 12, 1));
  r = run_gslam("reconstruct " + seq + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(last_line(r.output), "error: " + (labels / (first + ".png")).string() + ": label image is 16x12, its colour image 32x24\n");
  // classes.json that repeats an id; then none at all with --labels naming the folder.
  std::ofstream(labels / "classes.json") << R"({"classes": [{"id": 1, "name": "a"}, {"id": 1, "name": "b"}]})";
  r = run_gslam("reconstruct " + seq + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.output, "error: " + (labels / "classes.json").string() + ": class id 1 is listed twice\n");
  std::filesystem::create_directories(dir / "empty");
  r = run_gslam("reconstruct " + seq + out + " --labels " + (dir / "empty").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.output, "error: " + (dir / "empty" / "classes.json").string() +
                          ": missing: a labels folder needs classes.json naming its class ids\n");
}

// 8-bit label images read as 16-bit ones; frames without a label image are unlabelled.
TEST(LabelImages, EightBitImagesAndUnlabelledFrames) {
  TempDir dir;
  ASSERT_EQ(run_gslam("generate " + (dir / "seq").string() + " --frames 2 --width 32 --height 24 --labels").exit_code, 0);
  app::Dataset d = app::open_dataset(dir / "seq", {});
  ASSERT_TRUE(d.labels.has_value());
  const std::filesystem::path first = d.labels->dir / (d.entries[0].rgb.stem().string() + ".png");
  const splat::Image16 wide = app::read_png_gray16(first);
  splat::Image8 narrow(wide.width, wide.height, 1);
  std::copy(wide.data.begin(), wide.data.end(), narrow.data.begin());
  std::filesystem::remove(first);
  app::write_png_gray8(first, narrow);
  std::filesystem::remove(d.labels->dir / (d.entries[1].rgb.stem().string() + ".png"));
  EXPECT_EQ(d.load(0).labels, wide.data);
  EXPECT_TRUE(d.load(1).labels.empty());
  EXPECT_EQ(d.labels->name(6), "person");
  EXPECT_TRUE(d.labels->is_dynamic(6));
  EXPECT_FALSE(d.labels->is_dynamic(1));
}

}  // namespace
