// Writes an MCAP file the way `ros2 bag record` does, with the MCAP project's reference writer
// (@mcap/core) and ROS 2 CDR serialization (@foxglove/rosmsg2-serialization), from frames a
// test prepared as raw files. gslam's own MCAP reader is checked against what this writes.
// Usage: node write_mcap.mjs TOOLS_DIR MANIFEST.json OUT.mcap
// MANIFEST: {compression: "zstd" | "lz4" | "", chunk_size, use_chunks (default true: messages in
//   chunks, as rosbag2 writes them; false: at the top level), width, height, k: [9 numbers],
//   d: [5] (default zeros), p: [12] (default from k), info_width, info_height (default width, height),
//   colour_topic, colour_encoding (rgb8, bgr8, ...; "png" makes CompressedImage), depth_topic,
//   depth_encoding (16UC1 | 32FC1), info_topic (depth_topic, info_topic null: none written),
//   frames: [{colour: FILE, colour_stamp: [sec, nsec], depth: FILE, depth_stamp: [sec, nsec]}],
//   tf, tf_static (optional): [{stamp: [sec, nsec], parent, child, t: [x, y, z], q: [x, y, z, w]}]}
// Colour files hold [H, W, 3] rows in the topic's encoding (or the PNG file), depth files the
// [H, W] values in the encoding's type, little-endian. lz4 chunks come from the lz4 command (the
// LZ4 project's frame compressor); zstd from @foxglove/wasm-zstd.
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";

const [toolsDir, manifestPath, outPath] = process.argv.slice(2);
const require = createRequire(path.join(path.resolve(toolsDir), "node_modules", "index.js"));
const { McapWriter } = require("@mcap/core");
const { MessageWriter } = require("@foxglove/rosmsg2-serialization");
const { parse } = require("@foxglove/rosmsg");
const zstd = require("@foxglove/wasm-zstd");

const manifest = JSON.parse(fs.readFileSync(manifestPath, "utf8"));
const base = path.dirname(manifestPath);

const separator = "\n================================================================================\n";
const header = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id" + separator +
  "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
const definitions = {
  "sensor_msgs/msg/Image": "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n" +
    "uint8 is_bigendian\nuint32 step\nuint8[] data" + separator + header,
  "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data" + separator + header,
  "sensor_msgs/msg/CameraInfo": "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n" +
    "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n" +
    "sensor_msgs/RegionOfInterest roi" + separator + header + separator +
    "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify",
  "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms" + separator +
    "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform" +
    separator + "MSG: geometry_msgs/Transform\ngeometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation" +
    separator + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z" + separator +
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w" + separator + header,
};

let compressChunk;
if (manifest.compression === "zstd") {
  await zstd.isLoaded;
  compressChunk = (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) });
} else if (manifest.compression === "lz4") {
  compressChunk = (data) => ({
    compression: "lz4",
    compressedData: new Uint8Array(execFileSync("lz4", ["-c", "-q"], { input: data, maxBuffer: 1 << 30 })),
  });
}

const fd = fs.openSync(outPath, "w");
let position = 0n;
const writable = {
  write: async (buffer) => {
    fs.writeSync(fd, buffer);
    position += BigInt(buffer.byteLength);
  },
  position: () => position,
};
const writer = new McapWriter({
  writable, useChunks: manifest.use_chunks ?? true, chunkSize: manifest.chunk_size ?? 1 << 20, compressChunk,
});
await writer.start({ profile: "ros2", library: "gslam tests/interop/write_mcap.mjs" });

const serializers = {};
const channels = {};
async function channel(topic, type) {
  if (!(type in serializers)) {
    serializers[type] = {
      writer: new MessageWriter(parse(definitions[type], { ros2: true })),
      schema: await writer.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode(definitions[type]) }),
    };
  }
  channels[topic] = {
    id: await writer.registerChannel({ topic, schemaId: serializers[type].schema, messageEncoding: "cdr", metadata: new Map() }),
    serializer: serializers[type].writer,
    sequence: 0,
  };
}
async function publish(topic, stamp, message) {
  const c = channels[topic];
  const time = BigInt(stamp[0]) * 1000000000n + BigInt(stamp[1]);
  await writer.addMessage({ channelId: c.id, sequence: c.sequence++, logTime: time, publishTime: time, data: c.serializer.writeMessage(message) });
}

const compressed = manifest.colour_encoding === "png";
await channel(manifest.colour_topic, compressed ? "sensor_msgs/msg/CompressedImage" : "sensor_msgs/msg/Image");
if (manifest.depth_topic) await channel(manifest.depth_topic, "sensor_msgs/msg/Image");
if (manifest.info_topic) await channel(manifest.info_topic, "sensor_msgs/msg/CameraInfo");
const headerOf = (stamp, frame) => ({ stamp: { sec: stamp[0], nanosec: stamp[1], nsec: stamp[1] }, frame_id: frame });
const { width, height } = manifest;
const bytesPer = { rgb8: 3, bgr8: 3, mono8: 1, rgba8: 4, bgra8: 4, "16UC1": 2, "32FC1": 4 };

for (const [i, f] of manifest.frames.entries()) {
  if (manifest.info_topic && i === 0) {
    const k = manifest.k;
    await publish(manifest.info_topic, f.colour_stamp, {
      header: headerOf(f.colour_stamp, "rgb"), height: manifest.info_height ?? height,
      width: manifest.info_width ?? width, distortion_model: "plumb_bob",
      d: manifest.d ?? [0, 0, 0, 0, 0], k, r: [1, 0, 0, 0, 1, 0, 0, 0, 1],
      p: manifest.p ?? [k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1, 0], binning_x: 0, binning_y: 0,
      roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false },
    });
  }
  const colour = new Uint8Array(fs.readFileSync(path.join(base, f.colour)));
  if (compressed) {
    await publish(manifest.colour_topic, f.colour_stamp, { header: headerOf(f.colour_stamp, "rgb"), format: "png", data: colour });
  } else {
    const step = width * (bytesPer[manifest.colour_encoding] ?? 3);
    await publish(manifest.colour_topic, f.colour_stamp, {
      header: headerOf(f.colour_stamp, "rgb"), height, width, encoding: manifest.colour_encoding, is_bigendian: 0, step, data: colour,
    });
  }
  if (!manifest.depth_topic) continue;
  const depth = new Uint8Array(fs.readFileSync(path.join(base, f.depth)));
  await publish(manifest.depth_topic, f.depth_stamp, {
    header: headerOf(f.depth_stamp, "depth"), height, width, encoding: manifest.depth_encoding, is_bigendian: 0,
    step: width * bytesPer[manifest.depth_encoding], data: depth,
  });
}
// Motion capture on /tf (one transform a message, as a mocap driver publishes), fixed mounts on
// /tf_static.
for (const topic of ["tf", "tf_static"]) {
  if (!manifest[topic]) continue;
  await channel("/" + topic, "tf2_msgs/msg/TFMessage");
  for (const tf of manifest[topic]) {
    await publish("/" + topic, tf.stamp, {
      transforms: [{
        header: headerOf(tf.stamp, tf.parent), child_frame_id: tf.child,
        transform: { translation: { x: tf.t[0], y: tf.t[1], z: tf.t[2] }, rotation: { x: tf.q[0], y: tf.q[1], z: tf.q[2], w: tf.q[3] } },
      }],
    });
  }
}
await writer.end();
fs.closeSync(fd);
