#!/usr/bin/env bash
# The teddy sequence (../shared/data) as a ROS 1 bag played at its recorded rate under a roscore
# of its own (loopback, temporary folder), through gslam_ros with its defaults (the newest frame
# only, as from a camera), beside `gslam live --headless` replaying the folder at the same rate.
# Prints frames tracked and dropped, the latency of each pose on /tf from its image's stamp
# (simulated time: rosbag play --clock), and both runs' ATE. Run after scripts/build.sh; needs
# Debian's ros-core, python3-sensor-msgs, python3-pil, python3-numpy (scripts/install_deps.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${GSLAM_BUILD_DIR:-build}
gslam=$build/app/gslam
node=$build/ros/gslam/gslam_ros
teddy=../shared/data/tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy
[ -x "$node" ] || { echo "ros_node_bench: $node not built (ROS 1 not installed?)"; exit 1; }
[ -d "$teddy" ] || { echo "ros_node_bench: $teddy not found"; exit 1; }
out=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT -- "-$p" 2> /dev/null || true; done; sleep 1; rm -rf "$out"; }
trap cleanup EXIT
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1 ROS_HOME=$out/home ROS_LOG_DIR=$out/log

/usr/bin/python3 - "$teddy" "$out/teddy.bag" <<'PY'
import os, sys, numpy as np, rosbag, rospy
from PIL import Image as PILImage
from sensor_msgs.msg import Image, CameraInfo
root, out = sys.argv[1], sys.argv[2]
def listed(name):  # the listed frames whose files are there
    rows = [l.split() for l in open(f"{root}/{name}") if l.strip() and not l.startswith("#")]
    return [(float(t), f) for t, f in rows if os.path.exists(f"{root}/{f}")]
rgb, depth = listed("rgb.txt"), listed("depth.txt")
with rosbag.Bag(out, "w") as bag:
    for i, (t, f) in enumerate(rgb):
        td, fd = min(depth, key=lambda d: abs(d[0] - t))
        if abs(td - t) > 0.02: continue
        stamp = rospy.Time.from_sec(t)
        if i == 0:
            info = CameraInfo(width=640, height=480, K=[535.4, 0, 320.1, 0, 539.2, 247.6, 0, 0, 1])
            info.header.stamp = stamp
            bag.write("/camera/rgb/camera_info", info, stamp)
        c = np.asarray(PILImage.open(f"{root}/{f}").convert("RGB"))
        m = Image(height=480, width=640, encoding="rgb8", step=640 * 3, data=c.tobytes()); m.header.stamp = stamp
        bag.write("/camera/rgb/image_color", m, stamp)
        d = (np.asarray(PILImage.open(f"{root}/{fd}"), dtype=np.float32) / 5000).astype(np.float32)
        m = Image(height=480, width=640, encoding="32FC1", step=640 * 4, data=d.tobytes())
        m.header.stamp = rospy.Time.from_sec(td)
        bag.write("/camera/depth/image", m, m.header.stamp)
PY

setsid roscore -p "$port" > "$out/roscore.log" 2>&1 & pids+=($!)
until rosnode list 2> /dev/null | grep -q /rosout; do sleep 0.2; done
rosparam set /use_sim_time true
PYTHONUNBUFFERED=1 setsid rostopic echo -p /tf > "$out/tf.csv" 2> /dev/null & pids+=($!)
setsid "$node" rgb/image:=/camera/rgb/image_color depth/image:=/camera/depth/image \
  rgb/camera_info:=/camera/rgb/camera_info _out:="$out/node" "$@" > "$out/node.log" 2>&1 & node_pid=$!
until rostopic info /tf 2> /dev/null | grep -q "/rostopic_"; do sleep 0.2; done  # the echo has subscribed
rosbag play --clock --hz=1000 --wait-for-subscribers -q "$out/teddy.bag"
sleep 2  # the last frames' tracking
kill -INT -- "-$node_pid"; wait "$node_pid" || { cat "$out/node.log"; exit 1; }
"$gslam" eval "$out/node" --dataset "$teddy" > /dev/null
"$gslam" live "$teddy" --out "$out/live" --headless "$@" > "$out/live.log" 2>&1 || { cat "$out/live.log"; exit 1; }
"$gslam" eval "$out/live" --dataset "$teddy" > /dev/null

/usr/bin/python3 - "$out" <<'PY'
import csv, json, sys
out = sys.argv[1]
lat = []
with open(f"{out}/tf.csv") as f:
    for row in csv.DictReader(f):
        if row.get("field.transforms0.header.frame_id") == "map":
            lat.append((int(row["%time"]) - int(row["field.transforms0.header.stamp"])) / 1e6)
lat.sort()
pct = lambda q: lat[min(len(lat) - 1, int(q * len(lat)))] if lat else float("nan")
print("| run | frames tracked | dropped | pose latency on /tf p50 / p95 ms | ATE cm |")
print("|---|---|---|---|---|")
for name in ("node", "live"):
    s, e = json.load(open(f"{out}/{name}/summary.json")), json.load(open(f"{out}/{name}/eval.json"))
    latency = f"{pct(0.5):.1f} / {pct(0.95):.1f}" if name == "node" else \
        f"(tracking {s['live']['tracking_latency_ms']['p50']:.0f} / {s['live']['tracking_latency_ms']['p95']:.0f})"
    print(f"| {'gslam_ros, bag at 1x' if name == 'node' else 'gslam live, folder at 1x'} | {s['frames']} | "
          f"{s['live']['frames_dropped']} | {latency} | {e['ate']['rmse_m'] * 100:.2f} |")
PY
