// The occupied voxels of a map as a PLY file (ply_export.hpp).
#include "ply_export.hpp"

#include <array>
#include <bit>
#include <cstdio>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "umbra/io/file_saving.hpp"
#include "umbra/core/memory_limit.hpp"

namespace umbra::cli {
namespace {

/// Corners of a cube by index: bit 0 x, bit 1 y, bit 2 z (0: low, 1: high).
/// Its faces as quads, counter-clockwise seen from outside, each drawn as
/// two triangles (a, b, c) and (a, c, d).
constexpr std::array<std::array<std::uint32_t, 4>, 6> kCubeFaces{{
    {0, 4, 6, 2},  // -x
    {1, 3, 7, 5},  // +x
    {0, 1, 5, 4},  // -y
    {2, 6, 7, 3},  // +y
    {0, 2, 3, 1},  // -z
    {4, 5, 7, 6},  // +z
}};
constexpr std::uint64_t kTrianglesPerCube = 12;
constexpr std::uint64_t kFaceBytes = 1 + 3 * 4;  // uchar count 3, three int indices

/// Appends little-endian bytes to a buffer reserved to its final size.
class LittleEndianWriter {
 public:
  explicit LittleEndianWriter(std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}

  void f32(float value) { u32(std::bit_cast<std::uint32_t>(value)); }
  void u32(std::uint32_t value) {
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
  void u8(std::uint8_t value) { bytes_.push_back(value); }

 private:
  std::vector<std::uint8_t>& bytes_;
};

/// The header; `faces` 0: none declared.
std::string ply_header(std::uint64_t vertices, std::uint64_t faces, bool color, double resolution, bool mesh) {
  char resolution_text[32];
  std::snprintf(resolution_text, sizeof resolution_text, "%g", resolution);
  std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment umbra export: the occupied voxels of a map of " + std::string(resolution_text) + " m voxels, " +
      (mesh ? "one cube per occupied node\n" : "one point per occupied voxel, at its centre\n") +
      "element vertex " + std::to_string(vertices) + "\n"
      "property float x\n"
      "property float y\n"
      "property float z\n";
  if (color) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (mesh) header += "element face " + std::to_string(faces) + "\nproperty list uchar int vertex_indices\n";
  header += "end_header\n";
  return header;
}

}  // namespace

PlyExportSummary export_ply(const OccupancyMap& map, const std::filesystem::path& path,
                            const PlyExportOptions& options) {
  if (options.color && !map.has_color()) {
    throw std::invalid_argument("the map has no colors (it was built without --color): export it without --color");
  }
  // Pass 1: how much there is.
  std::uint64_t voxels = 0;
  std::uint64_t cubes = 0;
  map.for_each_leaf([&](const Node& node) {
    if (node.state != OccupancyState::occupied) return;
    voxels += std::uint64_t{1} << (3 * node.depth);
    ++cubes;
  });
  PlyExportSummary summary;
  summary.vertices = options.mesh ? 8 * cubes : voxels;
  summary.faces = options.mesh ? kTrianglesPerCube * cubes : 0;
  const std::uint64_t vertex_bytes = 12 + (options.color ? 3 : 0);
  const std::string header = ply_header(summary.vertices, summary.faces, options.color, map.resolution(), options.mesh);
  // In long double: 8^21 voxels of 15 bytes would overflow 64 bits.
  const long double body_bytes = static_cast<long double>(summary.vertices) * vertex_bytes +
                                 static_cast<long double>(summary.faces) * kFaceBytes;
  if (body_bytes > static_cast<long double>(memory_limit())) {
    throw MemoryLimitError("cannot export to " + path.string() + ": its " + std::to_string(summary.vertices) +
                           " vertices need " + std::to_string(static_cast<unsigned long long>(body_bytes)) +
                           " bytes, more than the memory limit of " + std::to_string(memory_limit()) +
                           " bytes (--max-memory; a --mesh of a large map is smaller than its points when "
                           "occupied nodes are pruned)");
  }
  if (options.mesh && summary.vertices > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::invalid_argument("cannot export to " + path.string() + ": " + std::to_string(summary.vertices) +
                                " vertices are more than a PLY face's int indices can address");
  }

  // Pass 2: the vertices (and faces).
  std::vector<std::uint8_t> body;
  body.reserve(static_cast<std::size_t>(body_bytes));
  LittleEndianWriter out(body);
  const Grid& grid = map.grid();
  const auto put_color = [&](const Node& node) {
    if (!options.color) return;
    const Rgb rgb = node.color.value_or(kNoColor);
    out.u8(rgb.r);
    out.u8(rgb.g);
    out.u8(rgb.b);
  };
  map.for_each_leaf([&](const Node& node) {
    if (node.state != OccupancyState::occupied) return;
    const std::uint64_t node_voxels = std::uint64_t{1} << (3 * node.depth);
    if (options.color && !node.color) summary.uncolored += node_voxels;
    if (options.mesh) {
      const Vec3d low = node.min_corner();
      const Vec3d high = node.max_corner();
      for (unsigned corner = 0; corner < 8; ++corner) {
        out.f32(static_cast<float>((corner & 1u) != 0 ? high.x : low.x));
        out.f32(static_cast<float>((corner & 2u) != 0 ? high.y : low.y));
        out.f32(static_cast<float>((corner & 4u) != 0 ? high.z : low.z));
        put_color(node);
      }
      return;
    }
    const std::uint32_t side = 1u << node.depth;
    for (std::uint32_t dz = 0; dz < side; ++dz) {
      for (std::uint32_t dy = 0; dy < side; ++dy) {
        for (std::uint32_t dx = 0; dx < side; ++dx) {
          const Vec3f centre = grid.center_f(Key{node.key.x + dx, node.key.y + dy, node.key.z + dz});
          out.f32(centre.x);
          out.f32(centre.y);
          out.f32(centre.z);
          put_color(node);
        }
      }
    }
  });
  if (options.mesh) {
    for (std::uint64_t cube = 0; cube < cubes; ++cube) {
      const auto first = static_cast<std::uint32_t>(8 * cube);
      for (const auto& quad : kCubeFaces) {
        for (const std::array<std::uint32_t, 3> triangle :
             {std::array{quad[0], quad[1], quad[2]}, std::array{quad[0], quad[2], quad[3]}}) {
          out.u8(3);
          for (const std::uint32_t corner : triangle) out.u32(first + corner);
        }
      }
    }
  }
  const auto* header_bytes = reinterpret_cast<const std::uint8_t*>(header.data());
  write_file_atomically(path, {std::span(header_bytes, header.size()), std::span<const std::uint8_t>(body)},
                                "PLY file");
  summary.bytes = header.size() + body.size();
  return summary;
}

}  // namespace umbra::cli
