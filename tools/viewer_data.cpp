#include "viewer_data.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <sstream>
#include <stdexcept>

#include "report.hpp"
#include "umbra/io/render_cuts.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra::cli {

namespace {

constexpr std::array<ViewerState, 3> kStates{ViewerState::occupied, ViewerState::free, ViewerState::unknown};
constexpr std::uint8_t kUncoloredGrey = 150;

Predicate state_predicate(ViewerState state) {
  switch (state) {
    case ViewerState::occupied: return pred::occupied();
    case ViewerState::free: return pred::free();
    case ViewerState::unknown: break;
  }
  return pred::unknown();
}

/// Appends `value` as a varint: 7 bits a byte, low bits first, high bit = more follows.
void put_varint(std::vector<std::uint8_t>& out, std::uint64_t value) {
  while (value >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(value | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(value));
}

std::vector<std::uint8_t> deflate(const std::vector<std::uint8_t>& raw) {
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> out(size);
  // Level 9: a page is written once and read many times; it costs about a
  // second more than level 6 on a 4 mm TUM map and saves a few percent.
  if (compress2(out.data(), &size, raw.data(), static_cast<uLong>(raw.size()), 9) != Z_OK) {
    throw std::runtime_error("umbra view: zlib could not compress a layer of " + std::to_string(raw.size()) + " bytes");
  }
  out.resize(size);
  return out;
}

struct LayerNode {
  std::uint64_t code = 0;     ///< morton::encode(key >> layer depth)
  std::uint8_t depth = 0;     ///< node depth - layer depth
  std::array<std::uint8_t, 3> rgb565{};  ///< r >> 3, g >> 2, b >> 3
};

/// The nodes of one layer in the format of viewer_data.hpp, compressed.
std::vector<std::uint8_t> encode_layer(const OccupancyMap& map, const Predicate& predicate, int depth,
                                       std::size_t count, bool with_colors) {
  std::vector<LayerNode> nodes;
  nodes.reserve(count);
  for (const Node& node : map.query(predicate, depth)) {
    LayerNode entry;
    entry.code = morton::encode(node.key.at_depth(depth));
    entry.depth = static_cast<std::uint8_t>(node.depth - depth);
    if (with_colors) {
      const Rgb rgb = node.color.value_or(Rgb{kUncoloredGrey, kUncoloredGrey, kUncoloredGrey});
      entry.rgb565 = {static_cast<std::uint8_t>(rgb.r >> 3), static_cast<std::uint8_t>(rgb.g >> 2),
                      static_cast<std::uint8_t>(rgb.b >> 3)};
    }
    nodes.push_back(entry);
  }
  // A query yields leaves in Morton order already; sorting keeps the deltas
  // non-negative whatever the walk's order.
  auto by_code = [](const LayerNode& a, const LayerNode& b) { return a.code < b.code; };
  if (!std::is_sorted(nodes.begin(), nodes.end(), by_code)) std::sort(nodes.begin(), nodes.end(), by_code);

  std::vector<std::uint8_t> raw;
  raw.reserve(nodes.size() * (3 + (with_colors ? 3 : 0)));
  std::uint64_t previous = 0;
  for (const LayerNode& node : nodes) {
    put_varint(raw, node.code - previous);
    previous = node.code;
  }
  for (const LayerNode& node : nodes) raw.push_back(node.depth);
  if (with_colors) {
    for (std::size_t channel = 0; channel < 3; ++channel) {
      std::uint8_t last = 0;
      for (const LayerNode& node : nodes) {
        raw.push_back(static_cast<std::uint8_t>(node.rgb565[channel] - last));
        last = node.rgb565[channel];
      }
    }
  }
  return deflate(raw);
}

/// A JSON string literal that is also safe inside an HTML <script> element.
std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || c == '<' || c == '>' || c == '&') {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", u);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

const char* to_string(ViewerState state) {
  switch (state) {
    case ViewerState::occupied: return "occupied";
    case ViewerState::free: return "free";
    case ViewerState::unknown: break;
  }
  return "unknown";
}

ViewerData collect_viewer_data(const OccupancyMap& map, std::size_t budget) {
  if (budget == 0) throw std::invalid_argument("umbra view: the budget must be at least 1 node");
  ViewerData data;
  data.budget = budget;
  data.stats = compute_statistics(map);
  const Predicate occupied = pred::leaf() && pred::occupied();
  data.finest_depth_zero_count = map.count(occupied, 0);
  if (!data.stats.has_known_space) return data;

  const Grid& grid = map.grid();
  const double half = 0.5 * grid.resolution();
  const Vec3d inner_min = data.stats.known_min + Vec3d{half, half, half};
  const Vec3d inner_max = data.stats.known_max - Vec3d{half, half, half};
  data.origin_key = grid.key(inner_min);
  data.end_key = grid.key(inner_max);
  for (int axis = 0; axis < 3; ++axis) data.end_key[axis] += 1;
  // Box corners on voxel centres: a node meets this box exactly when it
  // overlaps the known space by a voxel or more (node faces lie between
  // voxel centres, so merely touching faces cannot count).
  const Predicate near_known = pred::intersects(Aabb{inner_min, inner_max});

  // Codes of keys >> d must fit kViewerCodeBitsPerAxis bits per axis.
  data.finest_depth = std::max(0, map.depth_levels() - kViewerCodeBitsPerAxis);
  std::size_t count = data.finest_depth == 0 ? data.finest_depth_zero_count : map.count(occupied, data.finest_depth);
  while (count > budget && data.finest_depth < map.depth_levels()) {
    ++data.finest_depth;
    count = map.count(occupied, data.finest_depth);
  }
  const int last_depth = std::min(map.depth_levels(), data.finest_depth + kViewerExtraDepths);
  for (int depth = data.finest_depth; depth <= last_depth; ++depth) {
    for (const ViewerState state : kStates) {
      Predicate predicate = pred::leaf() && state_predicate(state);
      if (state == ViewerState::unknown) predicate = predicate && near_known;
      ViewerLayer layer;
      layer.depth = depth;
      layer.state = state;
      layer.count = map.count(predicate, depth);
      layer.embedded = layer.count <= budget;
      if (layer.embedded) {
        const bool with_colors = state == ViewerState::occupied && map.has_color();
        layer.deflated = encode_layer(map, predicate, depth, layer.count, with_colors);
      }
      data.layers.push_back(std::move(layer));
    }
  }
  if (const auto ceiling = find_ceiling(map, data.finest_depth)) data.ceiling_cut = ceiling->max_z;
  return data;
}

std::string viewer_json(const OccupancyMap& map, const ViewerData& data, const std::string& title) {
  std::ostringstream json;
  json.precision(17);
  json << "{\"title\": " << json_string(title) << ", \"stats\": " << statistics_json(data.stats)
       << ", \"memory\": " << json_string(human_bytes(data.stats.memory_bytes))
       << ", \"hasColor\": " << (map.has_color() ? "true" : "false") << ", \"budget\": " << data.budget
       << ", \"finestDepth\": " << data.finest_depth << ", \"depthZeroOccupied\": " << data.finest_depth_zero_count
       << ", \"format\": 2, \"origin\": [" << data.origin_key.x << ", " << data.origin_key.y << ", "
       << data.origin_key.z << "], \"size\": [" << data.end_key.x - data.origin_key.x << ", "
       << data.end_key.y - data.origin_key.y << ", " << data.end_key.z - data.origin_key.z << "], \"ceilingCut\": ";
  if (data.ceiling_cut) {
    json << *data.ceiling_cut;
  } else {
    json << "null";
  }
  json << ", \"layers\": [";
  std::size_t id = 0;
  for (std::size_t i = 0; i < data.layers.size(); ++i) {
    const ViewerLayer& layer = data.layers[i];
    json << (i == 0 ? "" : ", ") << "{\"depth\": " << layer.depth << ", \"state\": \"" << to_string(layer.state)
         << "\", \"count\": " << layer.count;
    if (layer.embedded) json << ", \"id\": \"layer-" << id++ << "\"";
    json << "}";
  }
  json << "]}";
  return json.str();
}

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t(bytes[i]) << 16) | (std::uint32_t(bytes[i + 1]) << 8) | bytes[i + 2];
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const std::uint32_t v = (std::uint32_t(bytes[i]) << 16) | (two ? std::uint32_t(bytes[i + 1]) << 8 : 0);
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace umbra::cli
