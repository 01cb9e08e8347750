#include "datasets/mcap_reader.h"

#include <fcntl.h>
#include <lz4frame.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <span>

#include "datasets/bag_reader.h"
#include "io/file_error.h"
#include "splat/error.h"

namespace app {
namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kDataEnd = 0x0F,
};
constexpr std::uint64_t kNoChunk = ~std::uint64_t(0);
// Image and CompressedImage headers (stamp, frame id, size, encoding) are read from this much of
// a message outside a chunk, so the index never reads pixels.
constexpr std::uint64_t kImageHeaderBytes = 64 << 10;

// A parse error inside one record or message; the reader adds the file and the place.
struct Malformed {
  std::string what;
};

// Little-endian fields of MCAP records.
class RecordCursor {
 public:
  explicit RecordCursor(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::span<const std::uint8_t> take(std::uint64_t n, const char* field) {
    if (n > bytes_.size() - pos_)
      throw Malformed{std::string(field) + " runs past the end of its record"};
    const auto out = bytes_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return out;
  }
  template <typename T>
  T number(const char* field) {
    T v;
    std::memcpy(&v, take(sizeof(T), field).data(), sizeof(T));
    return v;
  }
  std::string string(const char* field) {
    const auto n = number<std::uint32_t>(field);
    const auto s = take(n, field);
    return {s.begin(), s.end()};
  }
  std::size_t pos() const { return pos_; }
  std::span<const std::uint8_t> rest() const { return bytes_.subspan(pos_); }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

// A serialized ROS message: CDR as ROS 2 writes it (a 4-byte encapsulation header, then fields
// aligned to their size relative to its end, strings with their terminating NUL), or ROS 1's
// serialization (packed, little-endian, strings without NUL, a sequence number in Header).
class MessageCursor {
 public:
  MessageCursor(std::span<const std::uint8_t> bytes, bool ros1) : bytes_(bytes), ros1_(ros1) {
    if (ros1_) return;
    if (bytes_.size() < 4) throw Malformed{"shorter than its CDR encapsulation header"};
    // 0x0000 CDR big-endian, 0x0001 CDR little-endian; parameter lists and XCDR2 are not ROS 2's.
    if (bytes_[0] != 0 || bytes_[1] > 1) {
      throw Malformed{"CDR encapsulation " + std::to_string(bytes_[0]) + "," +
                      std::to_string(bytes_[1]) + " (expected plain CDR, 0,1 or 0,0)"};
    }
    big_endian_ = bytes_[1] == 0;
    pos_ = base_ = 4;
  }
  bool big_endian() const { return big_endian_; }
  std::size_t pos() const { return pos_; }
  std::span<const std::uint8_t> take(std::uint64_t n, const char* field) {
    if (n > bytes_.size() - pos_)
      throw Malformed{std::string(field) + " runs past the end of the message"};
    const auto out = bytes_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return out;
  }
  template <typename T>
  T number(const char* field) {
    if (!ros1_) {  // CDR: aligned to the type's size, from the end of the encapsulation header
      const std::size_t misalign = (pos_ - base_) % sizeof(T);
      if (misalign) take(sizeof(T) - misalign, field);
    }
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, take(sizeof(T), field).data(), sizeof(T));
    if (big_endian_) std::reverse(raw, raw + sizeof(T));
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
  }
  std::string string(const char* field) {
    const auto n = number<std::uint32_t>(field);
    const auto s = take(n, field);
    std::size_t len = s.size();
    if (!ros1_ && len > 0 && s[len - 1] == 0) --len;  // CDR counts the NUL
    return {s.begin(), s.begin() + static_cast<std::ptrdiff_t>(len)};
  }
  // std_msgs/Header: the stamp in seconds (frame_id skipped).
  double header_stamp() {
    if (ros1_) number<std::uint32_t>("header.seq");
    const double sec = ros1_ ? double(number<std::uint32_t>("header.stamp.sec"))
                             : double(number<std::int32_t>("header.stamp.sec"));
    const double nsec = double(number<std::uint32_t>("header.stamp.nanosec"));
    string("header.frame_id");
    return sec + nsec / 1e9;
  }

 private:
  std::span<const std::uint8_t> bytes_;
  bool ros1_;
  bool big_endian_ = false;
  std::size_t pos_ = 0, base_ = 0;
};

enum class Kind { kOther, kImage, kCompressedImage, kCameraInfo, kTf };

// Image or CompressedImage up to its pixels; with_data copies them, otherwise only their size
// is checked against the message's (`data_bytes`).
RosImage parse_image(std::span<const std::uint8_t> bytes, bool ros1, Kind kind, bool with_data,
                     std::uint64_t message_bytes) {
  MessageCursor c(bytes, ros1);
  RosImage image;
  image.stamp = c.header_stamp();
  image.compressed = kind == Kind::kCompressedImage;
  if (image.compressed) {
    image.encoding = c.string("format");
  } else {
    image.height = c.number<std::uint32_t>("height");
    image.width = c.number<std::uint32_t>("width");
    image.encoding = c.string("encoding");
    image.big_endian = c.number<std::uint8_t>("is_bigendian") != 0;
    image.step = c.number<std::uint32_t>("step");
  }
  const std::uint32_t n = c.number<std::uint32_t>("data length");
  if (std::uint64_t(c.pos()) + n > message_bytes) {
    throw Malformed{"image data of " + std::to_string(n) +
                    " bytes runs past the end of the message (" + std::to_string(message_bytes) +
                    " bytes)"};
  }
  if (with_data) {
    const auto data = c.take(n, "data");
    image.data.assign(data.begin(), data.end());
  }
  return image;
}

RosCameraInfo parse_camera_info(std::span<const std::uint8_t> bytes, bool ros1) {
  MessageCursor c(bytes, ros1);
  c.header_stamp();
  RosCameraInfo info;
  info.height = c.number<std::uint32_t>("height");
  info.width = c.number<std::uint32_t>("width");
  info.distortion_model = c.string("distortion_model");
  const std::uint32_t d = c.number<std::uint32_t>("d length");
  if (d > 64)
    throw Malformed{"d has " + std::to_string(d) + " distortion coefficients (at most 64)"};
  for (std::uint32_t i = 0; i < d; ++i) info.d.push_back(c.number<double>("d"));
  for (double& k : info.k) k = c.number<double>("k");
  for (int i = 0; i < 9; ++i) c.number<double>("r");
  for (double& p : info.p) p = c.number<double>("p");
  return info;
}

// tf2_msgs/TFMessage: geometry_msgs/TransformStamped[] (header, child_frame_id, translation
// x y z, rotation x y z w, all float64).
std::vector<RosTransform> parse_tf(std::span<const std::uint8_t> bytes, bool ros1, bool is_static) {
  MessageCursor c(bytes, ros1);
  const std::uint32_t n = c.number<std::uint32_t>("transforms length");
  // Each transform takes at least 56 bytes of float64s: a count beyond that is malformed.
  if (std::uint64_t(n) * 56 > bytes.size())
    throw Malformed{"transforms length " + std::to_string(n) + " exceeds the message"};
  const auto frame = [](std::string id) { return id.empty() || id[0] != '/' ? id : id.substr(1); };
  std::vector<RosTransform> out(n);
  for (RosTransform& t : out) {
    if (ros1) c.number<std::uint32_t>("header.seq");
    const double sec = ros1 ? double(c.number<std::uint32_t>("header.stamp.sec"))
                            : double(c.number<std::int32_t>("header.stamp.sec"));
    t.stamp = sec + double(c.number<std::uint32_t>("header.stamp.nanosec")) / 1e9;
    t.parent = frame(c.string("header.frame_id"));
    t.child = frame(c.string("child_frame_id"));
    for (double& v : t.translation) v = c.number<double>("translation");
    for (double& v : t.rotation) v = c.number<double>("rotation");
    t.is_static = is_static;
  }
  return out;
}

// ROS 1 spelling of a type name: "sensor_msgs/msg/Image" -> "sensor_msgs/Image".
std::string ros1_type(std::string name) {
  const auto at = name.find("/msg/");
  if (at != std::string::npos) name.erase(at, 4);
  return name;
}

Kind kind_of(const std::string& type) {
  if (type == "sensor_msgs/Image") return Kind::kImage;
  if (type == "sensor_msgs/CompressedImage") return Kind::kCompressedImage;
  if (type == "sensor_msgs/CameraInfo") return Kind::kCameraInfo;
  if (type == "tf2_msgs/TFMessage" || type == "tf/tfMessage") return Kind::kTf;
  return Kind::kOther;
}

class File {
 public:
  explicit File(const std::filesystem::path& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) fail(path, "cannot open file");
    const off_t end = ::lseek(fd_, 0, SEEK_END);
    if (end < 0) fail(path, "cannot read file");
    size_ = static_cast<std::uint64_t>(end);
  }
  ~File() { ::close(fd_); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  std::uint64_t size() const { return size_; }
  // Bytes [offset, offset + n), n checked against the file size by the caller. pread: no shared
  // position, so threads may read at once.
  std::vector<std::uint8_t> read(std::uint64_t offset, std::uint64_t n) const {
    if (offset > size_ || n > size_ - offset)
      fail(path_, "read past the end of the file at byte " + std::to_string(offset));
    std::vector<std::uint8_t> out(static_cast<std::size_t>(n));
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t got =
          ::pread(fd_, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
      if (got <= 0)
        fail(path_,
             "cannot read " + std::to_string(n) + " bytes at byte " + std::to_string(offset));
      done += static_cast<std::size_t>(got);
    }
    return out;
  }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

class McapReader final : public BagReader {
 public:
  explicit McapReader(const std::filesystem::path& path) : path_(path), file_(path) { index(); }

  const std::filesystem::path& path() const override { return path_; }

  std::vector<BagTopic> topics() const override {
    std::map<std::string, BagTopic> by_name;
    for (const auto& [id, ch] : channels_) {
      BagTopic& t = by_name[ch.topic];
      t.name = ch.topic;
      t.type = ch.type;
      t.messages += ch.messages;
    }
    std::vector<BagTopic> out;
    for (auto& [name, t] : by_name) out.push_back(t);
    return out;
  }

  std::vector<RosImage> image_index(const std::string& topic) const override {
    std::vector<RosImage> out;
    const auto it = images_.find(topic);
    if (it == images_.end()) return out;
    for (const auto& m : it->second) out.push_back(m.header);
    return out;
  }

  RosImage read_image(const std::string& topic, std::size_t k) const override {
    const Indexed& m = images_.at(topic).at(k);
    const auto parse = [&](std::span<const std::uint8_t> bytes) {
      try {
        return parse_image(bytes, m.ros1, m.kind, true, bytes.size());
      } catch (const Malformed& e) {
        fail(path_, "message " + std::to_string(k) + " on " + topic + ": " + e.what);
      }
    };
    if (m.chunk == kNoChunk) return parse(file_.read(m.offset, m.length));
    // Parsed in place: the pixels are copied once, out of the chunk.
    std::lock_guard lock(chunk_mutex_);
    return parse(chunk_message(m));
  }

  std::optional<RosCameraInfo> camera_info(const std::string& topic) const override {
    const auto it = camera_infos_.find(topic);
    if (it == camera_infos_.end()) return std::nullopt;
    return it->second;
  }

  std::vector<RosTransform> transforms() const override { return transforms_; }

 private:
  struct Channel {
    std::string topic, type, encoding;
    Kind kind = Kind::kOther;
    std::size_t messages = 0;
  };
  struct Indexed {
    RosImage header;
    Kind kind;
    bool ros1;
    std::uint64_t chunk;           // file offset of the Chunk record, or kNoChunk
    std::uint64_t offset, length;  // of the message data: in the file, or in the chunk's records
  };

  [[noreturn]] void malformed(std::uint64_t offset, const std::string& what) const {
    fail(path_, "record at byte " + std::to_string(offset) + ": " + what);
  }

  void index() {
    const std::uint64_t size = file_.size();
    if (size < 8 || std::memcmp(file_.read(0, 8).data(), kMagic, 8) != 0) {
      fail(path_, "not an MCAP file (it does not start with the MCAP magic)");
    }
    if (size < 16 || std::memcmp(file_.read(size - 8, 8).data(), kMagic, 8) != 0) {
      fail(path_,
           "truncated MCAP file (it does not end with the MCAP magic; still being recorded, or cut "
           "off)");
    }
    std::uint64_t pos = 8;
    while (true) {
      if (size - 8 - pos < 9)
        malformed(pos, "truncated: no room for a record header before the closing magic");
      const std::vector<std::uint8_t> head = file_.read(pos, 9);
      const std::uint8_t opcode = head[0];
      std::uint64_t length;
      std::memcpy(&length, head.data() + 1, 8);
      const std::uint64_t body = pos + 9;
      if (length > size - 8 - body) {
        malformed(pos, "truncated: opcode " + std::to_string(opcode) + " record of " +
                           std::to_string(length) + " bytes runs past the end of the file (" +
                           std::to_string(size) + " bytes)");
      }
      if (opcode == kFooter || opcode == kDataEnd)
        break;  // the summary repeats what the data section had
      try {
        record(opcode, body, length);
      } catch (const Malformed& e) {
        malformed(pos, e.what);
      }
      pos = body + length;
    }
  }

  std::vector<std::uint8_t> read_small(std::uint64_t offset, std::uint64_t length) const {
    if (length > kMaxMcapSmallRecordBytes) {
      throw Malformed{"record of " + std::to_string(length) + " bytes, more than the " +
                      std::to_string(kMaxMcapSmallRecordBytes) +
                      " a schema, channel or camera info may have"};
    }
    return file_.read(offset, length);
  }

  // One record of the data section, its content at file offset `body`.
  void record(std::uint8_t opcode, std::uint64_t body, std::uint64_t length) {
    switch (opcode) {
      case kSchema:
      case kChannel: {
        const std::vector<std::uint8_t> bytes = read_small(body, length);
        definition(opcode, bytes);
        break;
      }
      case kMessage: {
        // Only the fields, unless the channel's messages are read: its id is the first two bytes.
        std::uint64_t wanted = 22;
        if (length >= 2) {
          std::uint16_t id;
          std::memcpy(&id, file_.read(body, 2).data(), 2);
          const auto ch = channels_.find(id);
          if (ch != channels_.end() && ch->second.kind != Kind::kOther) wanted += kImageHeaderBytes;
        }
        message(file_.read(body, std::min(length, wanted)), length, kNoChunk, body);
        break;
      }
      case kChunk:
        chunk(body, length);
        break;
      default:  // header, indexes, attachments, metadata: nothing gslam needs
        break;
    }
  }

  void definition(std::uint8_t opcode, std::span<const std::uint8_t> bytes) {
    RecordCursor c(bytes);
    if (opcode == kSchema) {
      const auto id = c.number<std::uint16_t>("schema id");
      schemas_[id] = ros1_type(c.string("schema name"));
      return;
    }
    const auto id = c.number<std::uint16_t>("channel id");
    const auto schema = c.number<std::uint16_t>("channel schema id");
    Channel ch;
    ch.topic = c.string("channel topic");
    ch.encoding = c.string("channel message encoding");
    if (schema != 0) {
      const auto s = schemas_.find(schema);
      if (s == schemas_.end())
        throw Malformed{"channel " + ch.topic + " names schema " + std::to_string(schema) +
                        ", not defined before it"};
      ch.type = s->second;
    }
    ch.kind = kind_of(ch.type);
    if (ch.kind != Kind::kOther && ch.encoding != "cdr" && ch.encoding != "ros1") {
      ch.kind = Kind::kOther;  // listed by topics(), its messages not read
      ch.type += " (" + ch.encoding + " encoded, not read)";
    }
    channels_[id] = std::move(ch);
  }

  // A Message record: `bytes` holds at least its fields and the start of its data (all of it in
  // a chunk); `length` is the whole record's.
  void message(std::span<const std::uint8_t> bytes, std::uint64_t length, std::uint64_t chunk,
               std::uint64_t body) {
    RecordCursor c(bytes);
    const auto channel_id = c.number<std::uint16_t>("message channel id");
    c.number<std::uint32_t>("message sequence");
    const auto log_time = c.number<std::uint64_t>("message log time");
    c.number<std::uint64_t>("message publish time");
    const auto ch = channels_.find(channel_id);
    if (ch == channels_.end())
      throw Malformed{"message on channel " + std::to_string(channel_id) +
                      ", not defined before it"};
    Channel& channel = ch->second;
    ++channel.messages;
    const bool ros1 = channel.encoding == "ros1";
    const std::uint64_t data_length = length - c.pos();
    try {
      if (channel.kind == Kind::kImage || channel.kind == Kind::kCompressedImage) {
        Indexed m{parse_image(c.rest(), ros1, channel.kind, false, data_length),
                  channel.kind,
                  ros1,
                  chunk,
                  body + c.pos(),
                  data_length};
        if (m.header.stamp == 0) m.header.stamp = double(log_time) / 1e9;
        images_[channel.topic].push_back(std::move(m));
      } else if ((channel.kind == Kind::kCameraInfo && !camera_infos_.count(channel.topic)) ||
                 channel.kind == Kind::kTf) {
        std::vector<std::uint8_t> whole;
        std::span<const std::uint8_t> data = c.rest();
        if (data.size() < data_length) {  // outside a chunk only the start was read
          whole = read_small(body + c.pos(), data_length);
          data = whole;
        }
        if (channel.kind == Kind::kCameraInfo) {
          camera_infos_[channel.topic] = parse_camera_info(data, ros1);
        } else {
          const auto tf =
              parse_tf(data, ros1, channel.topic == "/tf_static" || channel.topic == "tf_static");
          transforms_.insert(transforms_.end(), tf.begin(), tf.end());
        }
      }
    } catch (const Malformed& e) {
      throw Malformed{"message " + std::to_string(channel.messages - 1) + " on " + channel.topic +
                      ": " + e.what};
    }
  }

  // The records of the Chunk record whose content starts at `body`, decompressed.
  std::vector<std::uint8_t> chunk_records(std::uint64_t body, std::uint64_t length) const {
    std::vector<std::uint8_t> fields = file_.read(body, std::min<std::uint64_t>(length, 4096));
    RecordCursor c(fields);
    c.number<std::uint64_t>("chunk start time");
    c.number<std::uint64_t>("chunk end time");
    const auto uncompressed = c.number<std::uint64_t>("chunk uncompressed size");
    c.number<std::uint32_t>("chunk crc");
    const std::string compression = c.string("chunk compression");
    const auto compressed = c.number<std::uint64_t>("chunk records length");
    const std::uint64_t start = body + c.pos();
    if (compressed > length - c.pos()) {
      throw Malformed{"chunk records of " + std::to_string(compressed) +
                      " bytes run past the chunk (" + std::to_string(length) + " bytes)"};
    }
    if (uncompressed > kMaxMcapChunkBytes) {
      throw Malformed{"chunk of " + std::to_string(uncompressed) +
                      " bytes uncompressed, more than the " + std::to_string(kMaxMcapChunkBytes) +
                      " gslam reads"};
    }
    if (compression != "" && compression != "zstd" && compression != "lz4") {
      throw Malformed{"chunk compression '" + compression + "' (gslam reads none, zstd, lz4)"};
    }
    if (compression.empty() && uncompressed != compressed) {
      throw Malformed{"uncompressed chunk of " + std::to_string(compressed) + " bytes says " +
                      std::to_string(uncompressed)};
    }
    std::vector<std::uint8_t> in = file_.read(start, compressed);
    if (compression.empty()) return in;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(uncompressed));
    if (compression == "zstd") {
      const std::size_t got = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
      if (ZSTD_isError(got))
        throw Malformed{std::string("zstd chunk does not decompress: ") + ZSTD_getErrorName(got)};
      if (got != out.size()) {
        throw Malformed{"zstd chunk decompresses to " + std::to_string(got) + " bytes, expected " +
                        std::to_string(out.size())};
      }
      return out;
    }
    LZ4F_dctx* dctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&dctx, LZ4F_VERSION)))
      throw Malformed{"lz4: out of memory"};
    std::size_t in_pos = 0, out_pos = 0;
    std::size_t status = 1;
    while (status != 0 && in_pos < in.size()) {
      std::size_t in_n = in.size() - in_pos, out_n = out.size() - out_pos;
      status =
          LZ4F_decompress(dctx, out.data() + out_pos, &out_n, in.data() + in_pos, &in_n, nullptr);
      if (LZ4F_isError(status)) {
        LZ4F_freeDecompressionContext(dctx);
        throw Malformed{std::string("lz4 chunk does not decompress: ") + LZ4F_getErrorName(status)};
      }
      in_pos += in_n;
      out_pos += out_n;
      if (in_n == 0 && out_n == 0) break;  // output full with input left: more than it said
    }
    LZ4F_freeDecompressionContext(dctx);
    if (status != 0 || out_pos != out.size()) {
      throw Malformed{"lz4 chunk decompresses to " + std::to_string(out_pos) +
                      "+ bytes, expected " + std::to_string(out.size())};
    }
    return out;
  }

  void chunk(std::uint64_t body, std::uint64_t length) {
    const std::vector<std::uint8_t> records = chunk_records(body, length);
    std::uint64_t pos = 0;
    while (pos < records.size()) {
      if (records.size() - pos < 9) throw Malformed{"chunk ends inside a record header"};
      const std::uint8_t opcode = records[pos];
      std::uint64_t n;
      std::memcpy(&n, records.data() + pos + 1, 8);
      if (n > records.size() - pos - 9) {
        throw Malformed{"chunk record at offset " + std::to_string(pos) + " of " +
                        std::to_string(n) + " bytes runs past the chunk"};
      }
      const std::span<const std::uint8_t> content(records.data() + pos + 9,
                                                  static_cast<std::size_t>(n));
      if (opcode == kSchema || opcode == kChannel) definition(opcode, content);
      if (opcode == kMessage) message(content, n, body, pos + 9);
      pos += 9 + n;
    }
  }

  // The data of a message in a chunk, inside the cached chunk (decompressed now unless it is the
  // last one read). Called with chunk_mutex_ held; valid while it is.
  std::span<const std::uint8_t> chunk_message(const Indexed& m) const {
    if (cached_chunk_ != m.chunk) {
      std::vector<std::uint8_t>().swap(cached_);  // freed before the next one is allocated
      cached_chunk_ = kNoChunk;
      const std::vector<std::uint8_t> head = file_.read(m.chunk - 9, 9);
      std::uint64_t length;
      std::memcpy(&length, head.data() + 1, 8);
      try {
        cached_ = chunk_records(m.chunk, length);
      } catch (const Malformed& e) {
        malformed(m.chunk - 9, e.what);
      }
      cached_chunk_ = m.chunk;
    }
    if (m.offset > cached_.size() || m.length > cached_.size() - m.offset)
      malformed(m.chunk - 9, "chunk changed since it was indexed");
    return std::span<const std::uint8_t>(cached_).subspan(static_cast<std::size_t>(m.offset),
                                                          static_cast<std::size_t>(m.length));
  }

  std::filesystem::path path_;
  File file_;
  std::map<std::uint16_t, std::string> schemas_;  // id -> type (ROS 1 spelling)
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::string, std::vector<Indexed>> images_;
  std::map<std::string, RosCameraInfo> camera_infos_;
  std::vector<RosTransform> transforms_;
  // The last chunk a message was read from: colour and depth of one frame are usually in one.
  mutable std::mutex chunk_mutex_;
  mutable std::uint64_t cached_chunk_ = kNoChunk;
  mutable std::vector<std::uint8_t> cached_;
};

}  // namespace

std::unique_ptr<BagReader> open_mcap(const std::filesystem::path& path) {
  return std::make_unique<McapReader>(path);
}

}  // namespace app
