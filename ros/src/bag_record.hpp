// The record layer of the ROS bag 2.0 format (wiki.ros.org/Bags/Format/2.0),
// internal to bag_file.cpp: where a record is, its header fields, and the
// little-endian values inside them.
//
// A record is <header_len u32><header><data_len u32><data>; a header is a
// run of fields <field_len u32><name>=<value>, the value raw bytes. Nothing
// here trusts a length: every one is checked against the bytes that hold it
// before anything is read or allocated, and every failure is a
// umbra::FormatError naming the file and the byte offset (RecordSite).
//
// Cost: parsing a header copies its field values (headers are tens of bytes;
// connection records carry their message definition, a few kB, in the data).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>

#include "umbra/io/format_error.hpp"

namespace umbra::ros_io::bag_detail {

/// Record ops of bag format 2.0.
enum class Op : std::uint8_t {
  message_definition = 0x01,  ///< format 1.2 only; skipped inside chunks as librosbag does
  message_data = 0x02,
  bag_header = 0x03,
  index_data = 0x04,
  chunk = 0x05,
  chunk_info = 0x06,
  connection = 0x07,
};

/// "chunk (op 0x05)", or "unknown op 0x2a".
std::string op_name(std::uint8_t op);

/// Where bytes lie, for error messages: a byte of the file, or an offset into
/// the decompressed data of the (compressed) chunk that starts at a byte of the file.
struct RecordSite {
  const std::string* file = nullptr;
  std::uint64_t byte = 0;                 ///< file offset (of the chunk record, when `compression` is set)
  std::uint64_t chunk_offset = 0;         ///< offset into the chunk's decompressed data
  const std::string* compression = nullptr;  ///< null: `byte` is exact

  /// The same place `bytes` further on.
  [[nodiscard]] RecordSite advanced(std::uint64_t bytes) const {
    RecordSite site = *this;
    (compression != nullptr ? site.chunk_offset : site.byte) += bytes;
    return site;
  }
  /// "FILE: byte N: WHAT", or "FILE: byte N: offset M of the bz2 chunk's data: WHAT".
  [[nodiscard]] FormatError error(const std::string& what) const;
};

/// The fields of a record header (or of a connection record's data, which
/// has the same layout), by name.
class RecordFields {
 public:
  /// Parses `bytes`, the header that starts at `site`. Throws FormatError for
  /// a field that runs past the header, has no '=' or repeats a name.
  RecordFields(std::span<const std::uint8_t> bytes, const RecordSite& site);

  [[nodiscard]] bool has(const std::string& name) const { return fields_.count(name) != 0; }
  /// The op field (every record header has one).
  [[nodiscard]] std::uint8_t op() const;
  [[nodiscard]] std::uint32_t u32(const std::string& name) const;
  [[nodiscard]] std::uint64_t u64(const std::string& name) const;
  /// A time field: seconds and nanoseconds, both u32.
  [[nodiscard]] std::uint64_t time(const std::string& name) const { return u64(name); }
  /// A text field (any bytes, non-empty).
  [[nodiscard]] const std::string& text(const std::string& name) const;
  /// A text field, or `fallback` when absent.
  [[nodiscard]] std::string text_or(const std::string& name, const std::string& fallback) const;
  /// The place of the header, for the caller's own errors.
  [[nodiscard]] const RecordSite& site() const { return site_; }

 private:
  const std::string& raw(const std::string& name, std::size_t size) const;

  RecordSite site_;
  std::map<std::string, std::string> fields_;
};

/// Little-endian u32 / u64 at `p`.
std::uint32_t load_u32(const std::uint8_t* p);
std::uint64_t load_u64(const std::uint8_t* p);

/// A record held in memory (inside a decompressed chunk): its fields and data.
struct RecordInMemory {
  RecordFields fields;
  std::span<const std::uint8_t> data;
  std::uint64_t end = 0;  ///< offset just past the record in the buffer
};

/// Parses the record at `offset` of `buffer`; `site` is where buffer[offset] is.
/// Throws FormatError when a length runs past the buffer.
RecordInMemory record_at(std::span<const std::uint8_t> buffer, std::uint64_t offset, const RecordSite& site);

}  // namespace umbra::ros_io::bag_detail
