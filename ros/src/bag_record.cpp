// The record layer of bag files: see bag_record.hpp.
#include "bag_record.hpp"

#include <cstdio>

#include "reader_support.hpp"

namespace umbra::ros_io::bag_detail {

std::string op_name(std::uint8_t op) {
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(op));
  switch (static_cast<Op>(op)) {
    case Op::message_definition: return std::string("message definition (op ") + hex + ")";
    case Op::message_data: return std::string("message data (op ") + hex + ")";
    case Op::bag_header: return std::string("bag header (op ") + hex + ")";
    case Op::index_data: return std::string("index data (op ") + hex + ")";
    case Op::chunk: return std::string("chunk (op ") + hex + ")";
    case Op::chunk_info: return std::string("chunk info (op ") + hex + ")";
    case Op::connection: return std::string("connection (op ") + hex + ")";
  }
  return std::string("unknown op ") + hex;
}

FormatError RecordSite::error(const std::string& what) const {
  const std::string& name = file != nullptr ? *file : std::string();
  if (compression == nullptr) return FormatError::at_byte(name, byte, what);
  return FormatError::at_byte(name, byte, "offset " + std::to_string(chunk_offset) + " of the " + *compression +
                                              " chunk's decompressed data: " + what);
}

std::uint32_t load_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}

std::uint64_t load_u64(const std::uint8_t* p) { return std::uint64_t{load_u32(p)} | std::uint64_t{load_u32(p + 4)} << 32; }

RecordFields::RecordFields(std::span<const std::uint8_t> bytes, const RecordSite& site) : site_(site) {
  std::size_t at = 0;
  while (at < bytes.size()) {
    const RecordSite here = site.advanced(at);
    if (bytes.size() - at < 4) {
      throw here.error("a header field needs a 4-byte length, but the header has " + std::to_string(bytes.size() - at) +
                       " bytes left");
    }
    const std::uint32_t length = load_u32(bytes.data() + at);
    at += 4;
    if (length > bytes.size() - at) {
      throw here.error("a header field of " + std::to_string(length) + " bytes runs past the header's end (" +
                       std::to_string(bytes.size() - at) + " bytes left)");
    }
    const std::string field(reinterpret_cast<const char*>(bytes.data() + at), length);
    at += length;
    const std::size_t equals = field.find('=');
    if (equals == std::string::npos) {
      throw here.error("a header field has no '=' (" + detail::quote(field) + ")");
    }
    const std::string name = field.substr(0, equals);
    if (!fields_.emplace(name, field.substr(equals + 1)).second) {
      throw here.error("the header field " + detail::quote(name) + " appears twice");
    }
  }
}

const std::string& RecordFields::raw(const std::string& name, std::size_t size) const {
  const auto found = fields_.find(name);
  if (found == fields_.end()) throw site_.error("the record header has no '" + name + "' field");
  if (size != 0 && found->second.size() != size) {
    throw site_.error("the record header's '" + name + "' field has " + std::to_string(found->second.size()) +
                      " bytes, not " + std::to_string(size));
  }
  return found->second;
}

std::uint8_t RecordFields::op() const { return static_cast<std::uint8_t>(raw("op", 1)[0]); }

std::uint32_t RecordFields::u32(const std::string& name) const {
  return load_u32(reinterpret_cast<const std::uint8_t*>(raw(name, 4).data()));
}

std::uint64_t RecordFields::u64(const std::string& name) const {
  return load_u64(reinterpret_cast<const std::uint8_t*>(raw(name, 8).data()));
}

const std::string& RecordFields::text(const std::string& name) const {
  const std::string& value = raw(name, 0);
  if (value.empty()) throw site_.error("the record header's '" + name + "' field is empty");
  return value;
}

std::string RecordFields::text_or(const std::string& name, const std::string& fallback) const {
  const auto found = fields_.find(name);
  return found == fields_.end() ? fallback : found->second;
}

RecordInMemory record_at(std::span<const std::uint8_t> buffer, std::uint64_t offset, const RecordSite& site) {
  const auto need = [&](std::uint64_t at, std::uint64_t bytes, const char* what) {
    if (at > buffer.size() || bytes > buffer.size() - at) {
      throw site.advanced(at - offset)
          .error(std::string(what) + " needs " + std::to_string(bytes) + " bytes, but the chunk has " +
                 std::to_string(at > buffer.size() ? 0 : buffer.size() - at) + " left");
    }
  };
  need(offset, 4, "a record's header length");
  const std::uint32_t header_length = load_u32(buffer.data() + offset);
  need(offset + 4, header_length, "the record header");
  RecordFields fields(buffer.subspan(offset + 4, header_length), site.advanced(4));
  const std::uint64_t data_length_at = offset + 4 + header_length;
  need(data_length_at, 4, "the record's data length");
  const std::uint32_t data_length = load_u32(buffer.data() + data_length_at);
  need(data_length_at + 4, data_length, "the record's data");
  return {std::move(fields), buffer.subspan(data_length_at + 4, data_length), data_length_at + 4 + data_length};
}

}  // namespace umbra::ros_io::bag_detail
