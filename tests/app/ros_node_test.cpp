// gslam_ros, the ROS 1 node, against a real ROS graph: roscore on a free loopback port, the teddy
// frames played from ROS 1 bags by rosbag play (on simulated time, so that /tf stamps and their
// arrival compare), the node's /tf read by rostopic echo, and its ~save and ~reset services
// called with rosservice. Its run folder evaluates against the teddy ground truth. Without ROS
// the tests skip, unless GSLAM_REQUIRE_ROS_TESTS (CI) makes that a failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "app/run_gslam.h"
#include "datasets/dataset.h"
#include "io/trajectory.h"
#include "support/json_file.h"
#include "support/require_tool.h"
#include "support/ros_graph.h"
#include "support/teddy_recording.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

using gslam::test::kTeddyFolder;
using gslam::test::open_teddy;
using gslam::test::RosGraph;
using gslam::test::TempDir;

// Frames per bag: two bags, the map reset between them.
constexpr int kFramesPerBag = 40;
// A hung node is a failure, not a wait forever; a loaded machine gets far more than it needs, and
// the test still fails with its message well before ctest's limit (600 s) would stop it silently.
constexpr std::chrono::seconds kEventTimeout{240};

#ifdef GSLAM_ROS_BINARY
const std::string kNode = GSLAM_ROS_BINARY;
#else
const std::string kNode;
#endif

using gslam::test::read_json;

// One transform the node published on /tf, as rostopic echo -p wrote it.
struct PublishedPose {
  double received = 0, stamp = 0;  // seconds (simulated time)
  std::string parent, child;
  Eigen::Isometry3d T_parent_child = Eigen::Isometry3d::Identity();
};

// The node's transforms (parent "map") in rostopic echo -p's CSV (other lines are skipped).
std::vector<PublishedPose> published_poses(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::vector<PublishedPose> out;
  std::map<std::string, std::size_t> column;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    if (!cells.empty() && cells[0] == "%time") {
      for (std::size_t i = 0; i < cells.size(); ++i) column[cells[i]] = i;
      continue;
    }
    const std::string p = "field.transforms0.";
    if (column.empty() || cells.size() != column.size()) continue;
    auto at = [&](const std::string& name) { return cells.at(column.at(name)); };
    auto number = [&](const std::string& name) { return std::stod(at(p + name)); };
    PublishedPose pose;
    pose.received = std::stod(at("%time")) * 1e-9;
    pose.stamp = number("header.stamp") * 1e-9;
    pose.parent = at(p + "header.frame_id");
    pose.child = at(p + "child_frame_id");
    if (pose.parent != "map") continue;
    pose.T_parent_child.translation() = Eigen::Vector3d(number("transform.translation.x"), number("transform.translation.y"),
                                                        number("transform.translation.z"));
    pose.T_parent_child.linear() = Eigen::Quaterniond(number("transform.rotation.w"), number("transform.rotation.x"),
                                                      number("transform.rotation.y"), number("transform.rotation.z"))
                                       .normalized()
                                       .toRotationMatrix();
    out.push_back(pose);
  }
  return out;
}

// Polls `done` every 100 ms until it holds (true) or kEventTimeout has passed (false): the tests
// wait for the event they need, not a clock.
bool wait_until(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + kEventTimeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return true;
}

// Waits until the node has published `count` poses.
std::vector<PublishedPose> wait_for_poses(const std::filesystem::path& csv, std::size_t count) {
  std::vector<PublishedPose> poses;
  wait_until([&] { return (poses = published_poses(csv)).size() >= count; });
  return poses;
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())))];
}

#ifdef GSLAM_HAVE_ROS1
// Whether `info`, what `rosnode info` says of a publisher, lists an established connection of
// `topic` to `subscriber` (the publisher's own list: the master listing a subscriber says nothing
// of its TCP connection).
bool connected(const std::string& info, const std::string& topic, const std::string& subscriber) {
  const std::string block = " * topic: " + topic + "\n";
  for (std::size_t at = info.find(block); at != std::string::npos; at = info.find(block, at + 1)) {
    const std::size_t next = info.find(" * topic: ", at + block.size());
    const std::string connection =
        info.substr(at, next == std::string::npos ? std::string::npos : next - at);
    if (connection.find("* to: " + subscriber + "\n") != std::string::npos) return true;
  }
  return false;
}

// Waits until each of `topics` of `publisher` is connected to `subscriber`.
bool wait_until_connected(RosGraph& graph, const std::string& publisher,
                          const std::vector<std::string>& topics, const std::string& subscriber) {
  return wait_until([&] {
    const std::string info = graph.run("rosnode info " + publisher).output;
    return std::all_of(topics.begin(), topics.end(), [&](const std::string& topic) {
      return connected(info, topic, subscriber);
    });
  });
}

// roscore on simulated time, rostopic echo on /tf, and the node with the teddy bag's topics and
// `args`; returns once the node's /tf publication is connected to the echo. (The master listing
// the echo as a subscriber is not enough: /tf is not latched, so a pose published before the
// echo's TCP connection is up is lost, and a test waiting for every pose would wait in vain.)
struct NodeRun {
  std::unique_ptr<RosGraph> graph;
  pid_t node = -1;
  std::filesystem::path run, tf;
  std::filesystem::path bag;  // start_node_with_teddy_bag's
  std::string log() const { return gslam::test::read_text(graph->dir() / "node.log"); }
};
NodeRun start_node(const std::vector<std::string>& args, std::string& why_not) {
  NodeRun r;
  r.graph = RosGraph::start(why_not);
  if (!r.graph) return r;
  r.run = r.graph->dir() / "run";
  r.tf = r.graph->dir() / "tf.csv";
  EXPECT_EQ(r.graph->run("rosparam set /use_sim_time true").exit_code, 0);
  r.graph->spawn({"env", "PYTHONUNBUFFERED=1", "rostopic", "echo", "-p", "/tf", "__name:=tf_echo"}, "tf.csv");
  std::vector<std::string> command = {kNode, "rgb/image:=/camera/rgb/image_color", "depth/image:=/camera/depth/image",
                                      "rgb/camera_info:=/camera/rgb/camera_info", "_out:=" + r.run.string(),
                                      "_backend:=cpu"};
  command.insert(command.end(), args.begin(), args.end());
  r.node = r.graph->spawn(command, "node.log");
  if (!wait_until_connected(*r.graph, "/gslam", {"/tf"}, "/tf_echo")) {
    why_not = "the node's /tf never connected to rostopic echo";
    r.graph.reset();
  }
  return r;
}

// start_node, and the first kFramesPerBag teddy frames written as a bag in the graph's folder
// (NodeRun::bag).
NodeRun start_node_with_teddy_bag(const std::vector<std::string>& args, std::string& why_not) {
  NodeRun r = start_node(args, why_not);
  if (!r.graph) return r;
  r.bag = r.graph->dir() / "teddy.bag";
  gslam::test::write_teddy_bag(open_teddy(kFramesPerBag), 0, kFramesPerBag, r.bag);
  return r;
}

// rosbag play at the recording's rate, publishing the simulated clock; `topics` of the bag, its
// output in `log`. It starts paused and plays once each topic is connected to the node: a message
// published before then is lost (--wait-for-subscribers waits for any one subscriber, and /tf has
// the echo's too). It stays up past the bag's end (--keep-alive) until the test has seen what it
// waits for and stops it: a player that exits at the end can take its last messages with it,
// still queued for a subscriber that a loaded machine has not read them from yet.
pid_t start_player(RosGraph& graph, const std::filesystem::path& bag, const std::vector<std::string>& topics,
                   const std::string& log) {
  std::vector<std::string> args = {"rosbag",  "play",         "--clock", "--hz=1000",
                                   "--pause", "--keep-alive", "-q",      "--topics"};
  args.insert(args.end(), topics.begin(), topics.end());
  args.insert(args.end(), {"--bags", bag.string(), "__name:=player"});
  const pid_t player = graph.spawn(args, log);
  EXPECT_TRUE(wait_until_connected(graph, "/player", topics, "/gslam"))
      << "rosbag play never connected to the node";
  // The player takes the request only once paused ("Bag is already running." before then).
  EXPECT_TRUE(wait_until([&] {
    return graph.run("rosservice call /player/pause_playback false").output.find("success: True") !=
           std::string::npos;
  })) << "rosbag play never resumed: "
      << gslam::test::read_text(graph.dir() / log);
  return player;
}
const std::vector<std::string> kImageTopics = {"/camera/rgb/image_color", "/camera/depth/image",
                                               "/camera/rgb/camera_info"};
#endif

class RosNode : public ::testing::Test {
 protected:
  void SetUp() override {
    GSLAM_REQUIRE_TOOL(!kNode.empty(), "gslam_ros was not built (scripts/install_deps.sh installs ROS 1)");
  }
};

TEST_F(RosNode, PrintConfigTakesParametersByTheConfigsNamesWithoutAMaster) {
  const auto r = gslam::test::run_command(kNode + " --print-config _keyframe_every:=7 _tracking/color_weight:=0.25");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json printed = nlohmann::json::parse(r.output);
  EXPECT_EQ(printed.at("keyframe_every").get<int>(), 7);
  EXPECT_DOUBLE_EQ(printed.at("tracking").at("color_weight").get<double>(), 0.25);
  // The same JSON is a config file the node (and reconstruct) reads back.
  TempDir dir;
  std::ofstream(dir / "config.json") << r.output;
  const auto again = gslam::test::run_command(kNode + " --print-config _config:=" + (dir / "config.json").string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(again.output), printed);
}

TEST_F(RosNode, BadParametersAndNoMasterAreOneLineErrors) {
  const auto unknown = gslam::test::run_command(kNode + " --print-config _keyframe_evrey:=7");
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.output.find("~keyframe_evrey: unknown parameter"), std::string::npos) << unknown.output;
  const auto type = gslam::test::run_command(kNode + " --print-config _queue_size:=many");
  EXPECT_EQ(type.exit_code, 1);
  EXPECT_NE(type.output.find("~queue_size: expected an integer, got \"many\""), std::string::npos) << type.output;
  const auto setting = gslam::test::run_command(kNode + " --print-config _tracking/nonsense:=1");
  EXPECT_EQ(setting.exit_code, 1);
  EXPECT_NE(setting.output.find("tracking.nonsense"), std::string::npos) << setting.output;
  const int port = gslam::test::free_loopback_port();
  const auto alone = gslam::test::run_command("ROS_MASTER_URI=http://127.0.0.1:" + std::to_string(port) + " " + kNode);
  EXPECT_EQ(alone.exit_code, 1);
  EXPECT_NE(alone.output.find("gslam_ros: error: gslam_ros: no ROS master answers at http://127.0.0.1:" +
                              std::to_string(port)),
            std::string::npos)
      << alone.output;
}

// The build's ROS package folder (BUILD/ros/gslam): roslaunch finds the node there and remaps
// its topics to the launch file's arguments.
TEST_F(RosNode, LaunchFileStartsTheBuiltNodeWithItsRemappings) {
  GSLAM_REQUIRE_TOOL(gslam::test::program_available("roslaunch"), "roslaunch not installed (ros-core)");
  TempDir dir;
  const std::filesystem::path package = std::filesystem::path(kNode).parent_path();
  const auto r = gslam::test::run_command("ROS_PACKAGE_PATH=" + package.parent_path().string() + " ROS_HOME=" +
                                          dir.path().string() + " roslaunch --args /gslam gslam gslam.launch rviz:=false rgb:=/cam/colour");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(kNode + " rgb/image:=/cam/colour depth/image:=/camera/depth/image"), std::string::npos)
      << r.output;
}

// The teddy frames played by rosbag at their own rate: every pair is tracked (a queue long
// enough that none is dropped, whatever the machine's load), each pose is on /tf stamped with its
// image, ~save writes a run folder, ~reset starts a new map for the second bag, and after Ctrl-C
// the run folder holds the second bag's trajectory, which evaluates against the ground truth.
TEST_F(RosNode, TracksBagsPlayedUnderRoscoreAndSavesAFolderThatEvaluates) {
  if (gslam::test::shared_data(kTeddyFolder).empty())
    GTEST_SKIP() << "shared data " << kTeddyFolder << " not found";
#ifndef GSLAM_HAVE_ROS1
  GSLAM_REQUIRE_TOOL(false, "gslam was built without ROS 1 (the test writes bags with rosbag)");
#else
  const app::Dataset teddy = open_teddy(2 * kFramesPerBag);
  std::string why_not;
  NodeRun r = start_node({"_queue_size:=1000"}, why_not);
  GSLAM_REQUIRE_TOOL(r.graph, why_not);
  RosGraph* graph = r.graph.get();
  const std::filesystem::path first = graph->dir() / "first.bag", second = graph->dir() / "second.bag", run = r.run,
                              tf = r.tf;
  const pid_t node = r.node;
  gslam::test::write_teddy_bag(teddy, 0, kFramesPerBag, first);
  gslam::test::write_teddy_bag(teddy, kFramesPerBag, kFramesPerBag, second);
  const pid_t first_player = start_player(*graph, first, kImageTopics, "play_first.log");
  const std::vector<PublishedPose> first_poses = wait_for_poses(tf, kFramesPerBag);
  graph->interrupt(first_player);
  ASSERT_EQ(first_poses.size(), std::size_t(kFramesPerBag))
      << gslam::test::read_text(graph->dir() / "node.log")
      << gslam::test::read_text(graph->dir() / "play_first.log");
  for (int i = 0; i < kFramesPerBag; ++i) {  // each pose carries its colour image's stamp
    EXPECT_NEAR(first_poses[std::size_t(i)].stamp, teddy.entries[std::size_t(i)].timestamp, 1e-6) << "frame " << i;
    EXPECT_EQ(first_poses[std::size_t(i)].child, "camera") << "the bag's images have no frame_id";
  }
  // For RViz: the map's centres in `map`, and the map seen from the camera, while subscribed.
  const std::string within = "timeout " + std::to_string(kEventTimeout.count()) + " ";
  const auto cloud = graph->run(within + "rostopic echo -n 1 --noarr /gslam/map_cloud");
  EXPECT_NE(cloud.output.find("frame_id: \"map\""), std::string::npos) << cloud.output;
  EXPECT_NE(cloud.output.find("point_step: 16"), std::string::npos) << cloud.output;
  EXPECT_EQ(cloud.output.find("width: 0\n"), std::string::npos) << cloud.output;
  const auto render = graph->run(within + "rostopic echo -n 1 --noarr /gslam/render");
  EXPECT_NE(render.output.find("height: 240\nwidth: 320\nencoding: \"rgb8\""), std::string::npos) << render.output;
  const auto save = graph->run("rosservice call /gslam/save");
  EXPECT_NE(save.output.find("success: True"), std::string::npos) << save.output;
  EXPECT_EQ(app::read_tum_trajectory(run / "trajectory.txt").size(), std::size_t(kFramesPerBag));
  const auto reset = graph->run("rosservice call /gslam/reset");
  EXPECT_NE(reset.output.find("success: True"), std::string::npos) << reset.output;

  const pid_t second_player = start_player(*graph, second, kImageTopics, "play_second.log");
  const std::vector<PublishedPose> poses = wait_for_poses(tf, 2 * kFramesPerBag);
  graph->interrupt(second_player);
  ASSERT_EQ(poses.size(), std::size_t(2 * kFramesPerBag))
      << gslam::test::read_text(graph->dir() / "node.log")
      << gslam::test::read_text(graph->dir() / "play_second.log");
  EXPECT_EQ(graph->interrupt(node), 0) << gslam::test::read_text(graph->dir() / "node.log");

  // The run folder is the second bag's run, complete as `gslam live` writes it.
  const nlohmann::json summary = read_json(run / "summary.json");
  EXPECT_EQ(summary.at("input").at("format"), "ros");
  EXPECT_EQ(summary.at("live").at("frames_dropped").get<int>(), 0);
  const auto trajectory = app::read_tum_trajectory(run / "trajectory.txt");
  ASSERT_EQ(trajectory.size(), std::size_t(kFramesPerBag));
  const auto eval = run_gslam("eval " + run.string() + " --dataset " +
                              gslam::test::shared_data(kTeddyFolder).string());
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json e = read_json(run / "eval.json");
  EXPECT_EQ(e.at("ate").at("matched_frames").get<int>(), kFramesPerBag);
  EXPECT_LT(e.at("ate").at("rmse_m").get<double>(), 0.02) << "teddy tracks to a centimetre or better";

  // /tf holds the poses as tracked; trajectory.txt has them as mapping corrected them since. The
  // map frame is the first camera's, turned from optical (z forward) to body (z up) axes.
  Eigen::Isometry3d body_from_optical = Eigen::Isometry3d::Identity();
  body_from_optical.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  std::vector<double> differences, latencies;
  for (int i = 0; i < kFramesPerBag; ++i) {
    const PublishedPose& p = poses[std::size_t(kFramesPerBag + i)];
    EXPECT_NEAR(p.stamp, trajectory[std::size_t(i)].timestamp, 1e-4);
    const Eigen::Isometry3d T_world_cam = body_from_optical.inverse() * p.T_parent_child;
    differences.push_back((T_world_cam.translation() - trajectory[std::size_t(i)].T_world_cam.translation()).norm());
    latencies.push_back(p.received - p.stamp);
  }
  EXPECT_LT(percentile(differences, 0.5), 0.005);
  EXPECT_TRUE(poses.front().T_parent_child.translation().norm() < 1e-9 &&
              poses[kFramesPerBag].T_parent_child.translation().norm() < 1e-9)
      << "each map starts at its first camera";
  RecordProperty("tf_latency_p50_ms", std::to_string(1000 * percentile(latencies, 0.5)));
  RecordProperty("tf_latency_p95_ms", std::to_string(1000 * percentile(latencies, 0.95)));
  std::printf("tf latency from the image stamp: p50 %.1f ms, p95 %.1f ms (simulated time; load-dependent)\n",
              1000 * percentile(latencies, 0.5), 1000 * percentile(latencies, 0.95));
#endif
}


// With ~odom_frame the node publishes map -> odom, the map being the odometry frame as it was at
// the first frame. The bag's motion capture plays the robot's odometry here (world -> kinect, TUM's
// pose of the colour camera): where tracking agrees with it, map -> odom stays at the identity.
TEST_F(RosNode, WithAnOdometryFramePublishesMapToOdomThatStaysPut) {
  if (gslam::test::shared_data(kTeddyFolder).empty())
    GTEST_SKIP() << "shared data " << kTeddyFolder << " not found";
#ifndef GSLAM_HAVE_ROS1
  GSLAM_REQUIRE_TOOL(false, "gslam was built without ROS 1 (the test writes bags with rosbag)");
#else
  std::string why_not;
  NodeRun r = start_node_with_teddy_bag({"_queue_size:=1000", "_odom_frame:=world", "_camera_frame:=kinect"}, why_not);
  GSLAM_REQUIRE_TOOL(r.graph, why_not);
  std::vector<std::string> topics = kImageTopics;
  topics.insert(topics.end(), {"/tf", "/tf_static"});
  const pid_t player = start_player(*r.graph, r.bag, topics, "play.log");
  // Every frame is tracked (as ~save writes the run folder, between frames); a pose goes on /tf
  // where odometry covers its stamp.
  const auto deadline = std::chrono::steady_clock::now() + kEventTimeout;
  std::size_t tracked = 0;
  while (tracked < std::size_t(kFramesPerBag) && std::chrono::steady_clock::now() < deadline) {
    if (r.graph->run("rosservice call /gslam/save").output.find("success: True") != std::string::npos)
      tracked = app::read_tum_trajectory(r.run / "trajectory.txt").size();
  }
  r.graph->interrupt(player);
  EXPECT_EQ(tracked, std::size_t(kFramesPerBag))
      << r.log() << gslam::test::read_text(r.graph->dir() / "play.log");
  EXPECT_EQ(r.graph->interrupt(r.node), 0) << r.log();
  const std::vector<PublishedPose> poses = published_poses(r.tf);
  EXPECT_GT(poses.size(), std::size_t(kFramesPerBag / 2)) << r.log();
  // map -> odom is the tracked pose's difference from the motion capture, both anchored at the
  // first frame (no alignment as ATE makes): 2-2.5 cm at most here; a wrong convention (an
  // optical frame taken as a body one, the map anchored elsewhere) is off by metres and radians.
  for (const PublishedPose& p : poses) {
    EXPECT_EQ(p.child, "world");
    EXPECT_LT(p.T_parent_child.translation().norm(), 0.05) << "at " << p.stamp;
    EXPECT_LT(Eigen::AngleAxisd(p.T_parent_child.linear()).angle(), 3 * M_PI / 180) << "at " << p.stamp;
  }
#endif
}


// Ctrl-C while the camera goes on publishing (a looping bag): the node stops taking frames, writes
// its run folder and exits cleanly, whatever arrives meanwhile.
TEST_F(RosNode, CtrlCWhileTheCameraKeepsPublishingWritesTheRunFolder) {
  if (gslam::test::shared_data(kTeddyFolder).empty())
    GTEST_SKIP() << "shared data " << kTeddyFolder << " not found";
#ifndef GSLAM_HAVE_ROS1
  GSLAM_REQUIRE_TOOL(false, "gslam was built without ROS 1 (the test writes bags with rosbag)");
#else
  std::string why_not;
  NodeRun r = start_node_with_teddy_bag({}, why_not);
  GSLAM_REQUIRE_TOOL(r.graph, why_not);
  std::vector<std::string> play = {"rosbag", "play", "--clock", "--loop", "-q", "--topics"};
  play.insert(play.end(), kImageTopics.begin(), kImageTopics.end());
  play.insert(play.end(), {"--bags", r.bag.string()});
  r.graph->spawn(play, "play.log");  // stopped by the graph
  EXPECT_GE(wait_for_poses(r.tf, 10).size(), 10u) << r.log();
  EXPECT_EQ(r.graph->interrupt(r.node), 0) << r.log();
  const nlohmann::json summary = read_json(r.run / "summary.json");
  EXPECT_TRUE(summary.at("live").at("interrupted").get<bool>());
  EXPECT_GE(app::read_tum_trajectory(r.run / "trajectory.txt").size(), 10u);
#endif
}

}  // namespace
