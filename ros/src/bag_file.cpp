// BagFile: see bag_file.hpp. Opening walks the records between the bag
// header and index_pos (chunks, each followed by its index data records),
// then those from index_pos to the end (connections, chunk infos); read()
// finds a message through its chunk (bag_chunk.cpp decompresses) and checks
// the record there (bag_record.cpp).
#include "umbra_ros/bag_file.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

#include "bag_chunk.hpp"
#include "bag_record.hpp"
#include "core/memory_budget.hpp"
#include "reader_support.hpp"

namespace umbra::ros_io {

using bag_detail::load_u32;
using bag_detail::Op;
using bag_detail::op_name;
using bag_detail::RecordFields;
using bag_detail::RecordSite;

namespace {

constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
/// Reads of at most this many bytes go through one buffer of the file.
constexpr std::uint64_t kWindowBytes = std::uint64_t{64} << 10;
/// Decompressed chunks read() keeps, in bytes (at least one chunk is always kept).
constexpr std::uint64_t kCacheBytes = std::uint64_t{256} << 20;
/// read() gives up when it has decompressed this many times the bytes of the distinct chunks it needed (plus
/// kCacheBytes): messages whose time order jumps between more chunks than the cache holds, over and over.
constexpr std::uint64_t kMaxRereads = 16;

struct Chunk {
  std::uint64_t byte = 0;       ///< start of the chunk record
  std::uint64_t data_byte = 0;  ///< start of its (compressed) data
  std::uint32_t data_size = 0;
  std::uint32_t size = 0;  ///< decompressed
  std::string compression;
};

/// A record read from the file: its fields and where its data is (not read).
struct FileRecord {
  std::uint64_t byte = 0;
  RecordFields fields;
  std::uint64_t data_byte = 0;
  std::uint32_t data_size = 0;
  [[nodiscard]] std::uint64_t end() const { return data_byte + data_size; }
};

/// An index data record, for errors found after the walk.
struct IndexRecord {
  std::uint64_t byte = 0;
  std::uint32_t connection_id = 0;
  std::size_t first = 0;  ///< its entries in State::index
  std::size_t count = 0;
};

struct CachedChunk {
  std::uint32_t chunk = 0;
  std::vector<std::uint8_t> bytes;
  std::uint64_t last_use = 0;
};

}  // namespace

struct BagFile::State {
  explicit State(const std::filesystem::path& path) : file(path, "ROS bag"), name(file.name()) {}

  detail::InputFile file;
  std::string name;
  std::vector<Chunk> chunks;
  std::vector<BagConnection> connections;
  std::vector<BagMessage> index;  ///< every message, in file order; `connection` is an index into connections
  std::vector<CachedChunk> cache;
  std::uint64_t uses = 0;
  std::uint64_t decompressed = 0;  ///< bytes decompressed by read(), all told
  std::uint64_t distinct = 0;      ///< bytes of the distinct chunks read() decompressed
  std::vector<bool> seen;          ///< per chunk: decompressed at least once
  std::vector<std::uint8_t> window;  ///< bytes of the file from window_byte on (see read_bytes)
  std::uint64_t window_byte = 0;

  [[nodiscard]] RecordSite site(std::uint64_t byte) const { return {&name, byte, 0, nullptr}; }

  std::vector<std::uint8_t> read_bytes(std::uint64_t byte, std::uint64_t size, const char* what) {
    if (size > memory_limit()) {
      detail::require_memory(name, std::string("reading ") + what + " at byte " + std::to_string(byte), size);
    }
    std::vector<std::uint8_t> bytes(size);
    if (size <= kWindowBytes) {
      // Record headers, lengths and index data: small reads near each other, served from one window.
      if (byte < window_byte || byte - window_byte + size > window.size()) {
        window.resize(static_cast<std::size_t>(std::min<std::uint64_t>(kWindowBytes, file.size() - std::min(byte, file.size()))));
        window.resize(file.read_at(byte, window.data(), window.size()));
        window_byte = byte;
      }
      if (byte - window_byte + size <= window.size()) {
        std::copy_n(window.begin() + static_cast<std::ptrdiff_t>(byte - window_byte), size, bytes.begin());
        return bytes;
      }
    } else if (file.read_at(byte, bytes.data(), bytes.size()) == bytes.size()) {
      return bytes;
    }
    throw site(byte).error(std::string("the file ends inside ") + what + " (it changed while being read?)");
  }

  /// The record at `byte`, which must end by `limit`. Reads its header; the data stays in the file.
  FileRecord read_record(std::uint64_t byte, std::uint64_t limit, const char* region) {
    const auto need = [&](std::uint64_t at, std::uint64_t bytes, const std::string& what) {
      if (at > limit || bytes > limit - at) {
        throw site(byte).error("the record's " + what + " (" + std::to_string(bytes) + " bytes at byte " +
                               std::to_string(at) + ") runs past " + region + " at byte " + std::to_string(limit));
      }
    };
    need(byte, 4, "header length");
    const std::vector<std::uint8_t> length = read_bytes(byte, 4, "a record's header length");
    const std::uint32_t header_size = load_u32(length.data());
    need(byte + 4, header_size, "header");
    const std::vector<std::uint8_t> header = read_bytes(byte + 4, header_size, "a record header");
    RecordFields fields(header, site(byte + 4));
    const std::uint64_t data_length_byte = byte + 4 + header_size;
    need(data_length_byte, 4, "data length");
    const std::uint32_t data_size = load_u32(read_bytes(data_length_byte, 4, "a record's data length").data());
    need(data_length_byte + 4, data_size, "data");
    return {byte, std::move(fields), data_length_byte + 4, data_size};
  }

  void open() {
    const std::uint64_t size = file.size();
    const std::vector<std::uint8_t> magic = read_bytes(0, std::min<std::uint64_t>(size, kMagic.size()), "the first line");
    const std::string first(magic.begin(), magic.end());
    if (first != kMagic) {
      if (first.rfind("#ROSBAG V", 0) == 0) {
        throw site(0).error("ROS bag format " + detail::quote(first.substr(9, first.find('\n') - 9)) +
                            " is not read (only format 2.0, written by ROS since 2010)");
      }
      throw site(0).error("not a ROS bag: the file does not start with '#ROSBAG V2.0'");
    }
    const FileRecord header = read_record(kMagic.size(), size, "the end of the file");
    if (header.fields.op() != static_cast<std::uint8_t>(Op::bag_header)) {
      throw site(header.byte).error("the first record is a " + op_name(header.fields.op()) + ", not the bag header");
    }
    const std::string encryptor = header.fields.text_or("encryptor", "");
    if (!encryptor.empty() && encryptor != "rosbag/NoEncryptor") {
      throw site(header.byte).error("the bag is encrypted (" + detail::quote(encryptor) +
                                    "); decrypt it first (rosbag decrypt)");
    }
    const std::uint64_t index_byte = header.fields.u64("index_pos");
    const std::uint32_t connection_count = header.fields.u32("conn_count");
    const std::uint32_t chunk_count = header.fields.u32("chunk_count");
    if (index_byte == 0) {
      throw site(header.byte).error("the bag has no index (index_pos 0: its recording was not closed); run "
                                    "'rosbag reindex' on it first");
    }
    if (index_byte < header.end() || index_byte > size) {
      throw site(header.byte).error("the bag header's index_pos " + std::to_string(index_byte) +
                                    " lies outside the records (bytes " + std::to_string(header.end()) + " to " +
                                    std::to_string(size) + ")");
    }
    std::vector<IndexRecord> index_records;
    for (std::uint64_t at = header.end(); at < index_byte;) {
      const FileRecord record = read_record(at, index_byte, "index_pos");
      const std::uint8_t op = record.fields.op();
      if (op == static_cast<std::uint8_t>(Op::chunk)) {
        add_chunk(record);
      } else if (op == static_cast<std::uint8_t>(Op::index_data)) {
        index_records.push_back(add_index_data(record));
      } else {
        throw site(at).error("a " + op_name(op) + " record before index_pos " + std::to_string(index_byte) +
                             ", where only chunks and their index data belong");
      }
      at = record.end();
    }
    std::uint32_t chunk_infos = 0;
    for (std::uint64_t at = index_byte; at < size;) {
      const FileRecord record = read_record(at, size, "the end of the file");
      const std::uint8_t op = record.fields.op();
      if (op == static_cast<std::uint8_t>(Op::connection)) {
        add_connection(record);
      } else if (op == static_cast<std::uint8_t>(Op::chunk_info)) {
        check_chunk_info(record);
        ++chunk_infos;
      } else {
        throw site(at).error("a " + op_name(op) + " record after index_pos " + std::to_string(index_byte) +
                             ", where only connections and chunk infos belong");
      }
      at = record.end();
    }
    if (connections.size() != connection_count || chunks.size() != chunk_count || chunk_infos != chunk_count) {
      throw site(header.byte).error("the bag header counts " + std::to_string(connection_count) + " connections and " +
                                    std::to_string(chunk_count) + " chunks, but the file has " +
                                    std::to_string(connections.size()) + " connection records, " +
                                    std::to_string(chunks.size()) + " chunks and " + std::to_string(chunk_infos) +
                                    " chunk infos");
    }
    resolve_connections(index_records);
    seen.assign(chunks.size(), false);
  }

  void add_chunk(const FileRecord& record) {
    Chunk chunk{record.byte, record.data_byte, record.data_size, record.fields.u32("size"),
                record.fields.text("compression")};
    if (chunk.compression != "none" && chunk.compression != "bz2" && chunk.compression != "lz4") {
      throw site(record.byte).error("the chunk's compression " + detail::quote(chunk.compression) +
                                    " is none of none, bz2, lz4");
    }
    if (chunk.compression == "none" && chunk.size != chunk.data_size) {
      throw site(record.byte).error("the uncompressed chunk declares " + std::to_string(chunk.size) +
                                    " bytes but holds " + std::to_string(chunk.data_size));
    }
    if (chunks.size() >= UINT32_MAX) throw site(record.byte).error("more than 2^32 chunks");
    chunks.push_back(std::move(chunk));
  }

  IndexRecord add_index_data(const FileRecord& record) {
    if (chunks.empty()) throw site(record.byte).error("index data before the first chunk");
    const std::uint32_t version = record.fields.u32("ver");
    if (version != 1) {
      throw site(record.byte).error("index data version " + std::to_string(version) + " (only version 1 is read)");
    }
    const std::uint32_t count = record.fields.u32("count");
    if (std::uint64_t{count} * 12 != record.data_size) {
      throw site(record.byte).error("index data of " + std::to_string(count) + " entries needs " +
                                    std::to_string(std::uint64_t{count} * 12) + " bytes of data, but has " +
                                    std::to_string(record.data_size));
    }
    const auto chunk_number = static_cast<std::uint32_t>(chunks.size() - 1);
    const Chunk& chunk = chunks.back();
    const std::vector<std::uint8_t> data = read_bytes(record.data_byte, record.data_size, "index data");
    IndexRecord result{record.byte, record.fields.u32("conn"), index.size(), count};
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint8_t* entry = data.data() + std::size_t{12} * i;
      BagMessage message{{load_u32(entry), load_u32(entry + 4)}, 0, chunk_number, load_u32(entry + 8)};
      if (message.offset >= chunk.size) {
        throw site(record.data_byte + std::uint64_t{12} * i + 8)
            .error("index entry " + std::to_string(i) + " of connection " + std::to_string(result.connection_id) +
                   " points at offset " + std::to_string(message.offset) + ", past the end of its chunk (byte " +
                   std::to_string(chunk.byte) + ", " + std::to_string(chunk.size) + " bytes)");
      }
      index.push_back(message);
    }
    return result;
  }

  void add_connection(const FileRecord& record) {
    BagConnection connection;
    connection.id = record.fields.u32("conn");
    connection.topic = record.fields.text("topic");
    connection.byte = record.byte;
    const std::vector<std::uint8_t> data = read_bytes(record.data_byte, record.data_size, "a connection header");
    const RecordFields header(data, site(record.data_byte));
    connection.type = header.text("type");
    connection.md5sum = header.text("md5sum");
    for (const BagConnection& other : connections) {
      if (other.id == connection.id) {
        throw site(record.byte).error("connection " + std::to_string(connection.id) +
                                      " is defined twice (first at byte " + std::to_string(other.byte) + ")");
      }
    }
    connections.push_back(std::move(connection));
  }

  void check_chunk_info(const FileRecord& record) {
    const std::uint32_t version = record.fields.u32("ver");
    if (version != 1) {
      throw site(record.byte).error("chunk info version " + std::to_string(version) + " (only version 1 is read)");
    }
    const std::uint64_t chunk_byte = record.fields.u64("chunk_pos");
    const bool found = std::ranges::binary_search(chunks, chunk_byte, {}, &Chunk::byte);  // chunks are in file order
    if (!found) {
      throw site(record.byte).error("the chunk info names a chunk at byte " + std::to_string(chunk_byte) +
                                    ", where no chunk record starts");
    }
    const std::uint32_t count = record.fields.u32("count");
    if (std::uint64_t{count} * 8 != record.data_size) {
      throw site(record.byte).error("a chunk info of " + std::to_string(count) + " connections needs " +
                                    std::to_string(std::uint64_t{count} * 8) + " bytes of data, but has " +
                                    std::to_string(record.data_size));
    }
  }

  void resolve_connections(const std::vector<IndexRecord>& index_records) {
    std::map<std::uint32_t, std::uint32_t> by_id;
    for (std::size_t i = 0; i < connections.size(); ++i) by_id[connections[i].id] = static_cast<std::uint32_t>(i);
    for (const IndexRecord& record : index_records) {
      const auto found = by_id.find(record.connection_id);
      if (found == by_id.end()) {
        throw site(record.byte).error("index data for connection " + std::to_string(record.connection_id) +
                                      ", which no connection record defines");
      }
      for (std::size_t i = record.first; i < record.first + record.count; ++i) index[i].connection = found->second;
    }
    // Each message is indexed once: a repeated entry would make read() return the same record again.
    std::vector<std::uint64_t> places(index.size());
    for (std::size_t i = 0; i < index.size(); ++i) places[i] = std::uint64_t{index[i].chunk} << 32 | index[i].offset;
    std::sort(places.begin(), places.end());
    const auto repeated = std::adjacent_find(places.begin(), places.end());
    if (repeated != places.end()) {
      const Chunk& chunk = chunks[*repeated >> 32];
      throw site(chunk.byte).error("two index entries point at the same message (offset " +
                                   std::to_string(*repeated & 0xffffffffu) + " of this chunk)");
    }
  }

  /// The decompressed bytes of chunk `number`, from the cache or the file.
  const std::vector<std::uint8_t>& chunk_bytes(std::uint32_t number) {
    ++uses;
    for (CachedChunk& cached : cache) {
      if (cached.chunk == number) {
        cached.last_use = uses;
        return cached.bytes;
      }
    }
    const Chunk& chunk = chunks[number];
    if (!seen[number]) {
      seen[number] = true;
      distinct += chunk.size;
    }
    decompressed += chunk.size;
    if (decompressed > kMaxRereads * distinct + kCacheBytes) {
      throw site(chunk.byte).error("the messages' time order jumps between chunks so often that reading it would "
                                   "decompress the same chunks over and over (" + std::to_string(decompressed) +
                                   " bytes so far for " + std::to_string(distinct) + " bytes of chunks)");
    }
    // Make room: drop the least recently used chunks beyond the budget (the newest one always stays).
    std::uint64_t held = chunk.size;
    for (const CachedChunk& cached : cache) held += cached.bytes.size();
    while (!cache.empty() && held > kCacheBytes) {
      const auto oldest = std::min_element(cache.begin(), cache.end(),
                                           [](const CachedChunk& a, const CachedChunk& b) { return a.last_use < b.last_use; });
      held -= oldest->bytes.size();
      cache.erase(oldest);
    }
    CachedChunk entry{number, {}, uses};
    if (chunk.compression == "none") {
      entry.bytes = read_bytes(chunk.data_byte, chunk.data_size, "a chunk");
    } else {
      const std::vector<std::uint8_t> compressed = read_bytes(chunk.data_byte, chunk.data_size, "a chunk");
      bag_detail::decompress_chunk(chunk.compression, compressed, chunk.size, entry.bytes, site(chunk.byte));
    }
    cache.push_back(std::move(entry));
    return cache.back().bytes;
  }

  /// Where offset `offset` of chunk `number`'s decompressed data is.
  [[nodiscard]] RecordSite chunk_site(std::uint32_t number, std::uint64_t offset) const {
    const Chunk& chunk = chunks[number];
    if (chunk.compression == "none") return site(chunk.data_byte + offset);
    return {&name, chunk.byte, offset, &chunk.compression};
  }
};

BagFile::BagFile(const std::filesystem::path& path) : state_(std::make_unique<State>(path)) { state_->open(); }

BagFile::~BagFile() = default;

const std::string& BagFile::name() const { return state_->name; }

const std::vector<BagConnection>& BagFile::connections() const { return state_->connections; }

std::vector<BagMessage> BagFile::messages(const std::function<bool(const BagConnection&)>& wanted) const {
  std::vector<bool> chosen(state_->connections.size());
  for (std::size_t i = 0; i < chosen.size(); ++i) chosen[i] = wanted(state_->connections[i]);
  std::vector<BagMessage> result;
  for (const BagMessage& message : state_->index) {
    if (chosen[message.connection]) result.push_back(message);
  }
  std::stable_sort(result.begin(), result.end(), [](const BagMessage& a, const BagMessage& b) { return a.time < b.time; });
  return result;
}

std::span<const std::uint8_t> BagFile::read(const BagMessage& message) {
  State& state = *state_;
  if (message.chunk >= state.chunks.size() || message.connection >= state.connections.size()) {
    throw std::invalid_argument("BagFile::read: a message of another bag");
  }
  const std::vector<std::uint8_t>& bytes = state.chunk_bytes(message.chunk);
  const std::uint32_t connection = state.connections[message.connection].id;
  // As librosbag, skip the connection (and old message definition) records that may precede the message.
  for (std::uint64_t offset = message.offset;;) {
    const RecordSite site = state.chunk_site(message.chunk, offset);
    const bag_detail::RecordInMemory record = bag_detail::record_at(bytes, offset, site);
    const std::uint8_t op = record.fields.op();
    if (op == static_cast<std::uint8_t>(Op::connection) || op == static_cast<std::uint8_t>(Op::message_definition)) {
      offset = record.end;
      continue;
    }
    if (op != static_cast<std::uint8_t>(Op::message_data)) {
      throw site.error("the index points at a " + op_name(op) + " record, not message data");
    }
    const std::uint32_t record_connection = record.fields.u32("conn");
    if (record_connection != connection) {
      throw site.error("the index lists this message under connection " + std::to_string(connection) +
                       ", but the record belongs to connection " + std::to_string(record_connection));
    }
    return record.data;
  }
}

FormatError BagFile::error(const BagMessage& message, const std::string& what) const {
  return state_->chunk_site(message.chunk, message.offset).error(what);
}

}  // namespace umbra::ros_io
