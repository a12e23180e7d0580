// BagFile: umbra's own reader of ROS bag files, format 2.0
// (wiki.ros.org/Bags/Format/2.0), plain C++ (no ROS needed).
//
// Why not librosbag: it trusts every length and offset in the file (record
// and header lengths, index offsets into chunks, chunk sizes), so a corrupt
// bag crashes it or makes it allocate gigabytes (docs/ros.md has the
// evidence). Guarding it would mean a pre-pass that parses and decompresses
// the whole bag the way librosbag then does again; reading the format here is
// smaller and safe by construction.
//
// Opening reads the structure without decompressing anything: the bag
// header, every chunk record and the index data records that follow it
// (the time and chunk offset of each message), up to index_pos, and from
// there to the end the connection records (topic, type, md5sum) and chunk
// info records. Every length is checked against the bytes that hold it and
// every offset against the file (or the chunk's declared decompressed size)
// before it is used; index entries must name a known connection and be
// unique. read() then decompresses the message's chunk (bz2, lz4 or none;
// the last few chunks are kept) and checks the message record at the
// index's offset: a message data record of the index's connection whose
// data lies inside the chunk.
//
// Not read: format 1.2 bags (before 2010), unindexed bags (a recording that
// was not closed: `rosbag reindex` them) and encrypted bags (`rosbag
// decrypt`); each is a FormatError saying so.
//
// Errors: umbra::FormatError "FILE: byte N: what is wrong" (for records
// inside a compressed chunk: "FILE: byte N: offset M of the bz2 chunk's
// decompressed data: ..."), std::runtime_error for a file that cannot be
// opened; MemoryLimitError when a chunk needs more than memory_limit().
//
// Cost: opening reads every record header and the index (12 bytes per
// message), small reads through one 64 KiB window of the file; read()
// decompresses each chunk about once when messages are read in time order
// (up to 256 MiB of decompressed chunks are kept for chunks that overlap in
// time; reading that would decompress the same chunks over and over, 16
// times their size, is refused with a FormatError rather than left to run).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "umbra/io/format_error.hpp"

namespace umbra::ros_io {

/// A bag's time stamp: seconds and nanoseconds as ROS 1 stores them.
struct BagTime {
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  [[nodiscard]] std::uint64_t packed() const { return (std::uint64_t{sec} << 32) | nsec; }
  friend bool operator==(BagTime a, BagTime b) { return a.packed() == b.packed(); }
  friend bool operator<(BagTime a, BagTime b) { return a.packed() < b.packed(); }
};

/// One connection: a topic and the message type written on it.
struct BagConnection {
  std::uint32_t id = 0;  ///< the bag's connection id
  std::string topic;
  std::string type;    ///< e.g. "sensor_msgs/PointCloud2"
  std::string md5sum;  ///< of the message definition, or "*"
  std::uint64_t byte = 0;  ///< file offset of its connection record (for messages)
};

/// One message as the index gives it.
struct BagMessage {
  BagTime time;
  std::uint32_t connection = 0;  ///< index into BagFile::connections()
  std::uint32_t chunk = 0;       ///< index into the bag's chunks
  std::uint32_t offset = 0;      ///< of the message record in the chunk's decompressed data
};

class BagFile {
 public:
  /// Opens `path` and reads its structure (see the file comment).
  explicit BagFile(const std::filesystem::path& path);
  BagFile(const BagFile&) = delete;
  BagFile& operator=(const BagFile&) = delete;
  ~BagFile();

  [[nodiscard]] const std::string& name() const;
  [[nodiscard]] const std::vector<BagConnection>& connections() const;

  /// The messages on the connections `wanted` accepts, in time order (equal times in file order).
  [[nodiscard]] std::vector<BagMessage> messages(const std::function<bool(const BagConnection&)>& wanted) const;

  /// The serialized message, valid until the next read(). Throws FormatError
  /// (naming the message's place) for a chunk or record that is not what the index says.
  std::span<const std::uint8_t> read(const BagMessage& message);

  /// FormatError "FILE: byte N: WHAT" at the message's record (inside a
  /// compressed chunk: "FILE: byte N: offset M of the lz4 chunk's decompressed data: WHAT").
  [[nodiscard]] FormatError error(const BagMessage& message, const std::string& what) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace umbra::ros_io
