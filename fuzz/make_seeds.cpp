// umbra_fuzz_seeds OUTDIR: writes the seed corpora of the fuzz targets.
//
// One folder per target (OUTDIR/octomap_bt, octomap_ot, umb, umb_body,
// graph, xyz, xyz_bz2, ply, pcd, kitti, query_lines, insert) with a handful of small, valid files made by
// umbra's own writers or spelled out here: empty maps, single voxels, a few
// random voxels, color, an unpruned tree, a coarse map of the simulated
// office; point clouds in every encoding each reader supports; `umbra query`
// input lines of every kind, good and bad. Nothing comes
// from ../shared/data. Every file is a few bytes to ~10 KB so that the
// fuzzers mutate quickly. Cost: well under a second.
// In builds with ROS also OUTDIR/rosbag: the tests' small bag in each compression.
#include <bzlib.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "umbra/io/map_file.hpp"
#include "umbra/io/octomap_files.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"
#ifdef UMBRA_FUZZ_ROSBAG_SEEDS
#include "bag_writer.hpp"
#endif

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using umbra::OccupancyMap;

void write(const fs::path& path, const Bytes& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

void write(const fs::path& path, const std::string& text) { write(path, Bytes(text.begin(), text.end())); }

template <typename T>
void append(Bytes& out, T value, bool big_endian = false) {
  const auto bits = std::bit_cast<std::array<std::uint8_t, sizeof(T)>>(value);  // the host is little-endian
  if (big_endian) {
    out.insert(out.end(), bits.rbegin(), bits.rend());
  } else {
    out.insert(out.end(), bits.begin(), bits.end());
  }
}

Bytes bytes_of(const std::string& text) { return Bytes(text.begin(), text.end()); }

/// Small maps to write in every map format.
std::vector<std::pair<std::string, OccupancyMap>> small_maps() {
  std::vector<std::pair<std::string, OccupancyMap>> maps;
  maps.emplace_back("empty", OccupancyMap(0.1));

  OccupancyMap single(0.05);
  single.update_hit(umbra::Vec3d{0.3, -0.2, 1.0});
  maps.emplace_back("single", std::move(single));

  umbra::MapConfig config;
  config.resolution = 0.2;
  config.color = true;
  OccupancyMap colored(config);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  for (int i = 0; i < 12; ++i) {
    const umbra::Vec3d p{coordinate(rng), coordinate(rng), coordinate(rng)};
    (i % 3 == 0 ? colored.update_miss(p) : colored.update_hit(p));
    colored.add_color(p, umbra::Rgb{static_cast<std::uint8_t>(20 * i), 100, static_cast<std::uint8_t>(255 - i)});
  }
  maps.emplace_back("colored", std::move(colored));

  OccupancyMap block(0.1);
  block.set_auto_prune(false);
  for (int x = 0; x < 2; ++x) {
    for (int y = 0; y < 2; ++y) {
      for (int z = 0; z < 2; ++z) block.update_miss(umbra::Vec3d{0.05 + 0.1 * x, 0.05 + 0.1 * y, 0.05 + 0.1 * z});
    }
  }
  maps.emplace_back("unpruned", std::move(block));

  // The simulated office, very coarse: a realistic shape in a few KB.
  OccupancyMap office(1.0);
  const umbra::sim::Scene scene = umbra::sim::make_demo_scene();
  umbra::sim::LidarModel lidar;
  lidar.rings = 4;
  lidar.azimuth_steps = 24;
  const umbra::sim::SensorPose pose = umbra::sim::demo_path()[0];
  office.insert_point_cloud(umbra::Vec3f(pose.position), umbra::sim::simulate_scan(scene, pose, lidar));
  maps.emplace_back("office", std::move(office));
  return maps;
}

void octomap_seeds(const fs::path& out) {
  for (const auto& [name, map] : small_maps()) {
    write(out / "octomap_bt" / (name + ".bt"), umbra::encode_octomap(map, umbra::OctoMapFormat::bt));
    write(out / "octomap_ot" / (name + ".ot"), umbra::encode_octomap(map, umbra::OctoMapFormat::ot));
  }
  // Header spellings liboctomap accepts.
  write(out / "octomap_bt" / "legacy-id-crlf.bt",
        std::string("# Octomap OcTree binary file\r\n#\r\nid 1\r\nsize 9\r\nres 0.1\r\nunknown keyword\r\ndata\r\n") +
            std::string("\x55\x55", 2));
  write(out / "octomap_ot" / "stamped-root-leaf.ot",
        std::string("# Octomap OcTree file\n# comment\nid OcTreeStamped\nsize 1\nres 0.25\ndata\n") +
            std::string("\x00\x00\x60\x40\x00", 5));
}

void umb_seeds(const fs::path& out) {
  for (const char* target : {"umb", "umb_body"}) {
    fs::create_directories(out / target);
    for (const auto& [name, map] : small_maps()) umbra::save_map(map, out / target / (name + ".umb"));
  }
}

void graph_seeds(const fs::path& out) {
  fs::create_directories(out / "graph");
  std::vector<umbra::Scan> scans(2);
  scans[0].origin = {0.0f, 0.0f, 1.0f};
  scans[1].origin = {1.5f, -0.5f, 1.2f};
  for (int i = 0; i < 12; ++i) {
    scans[0].points.push_back({1.0f + 0.1f * static_cast<float>(i), 2.0f, 0.5f});
    scans[1].points.push_back({-2.0f, 0.2f * static_cast<float>(i), 1.5f});
  }
  umbra::write_scan_graph(out / "graph" / "two-scans.graph", scans);
  umbra::write_scan_graph(out / "graph" / "empty.graph", {});
}

void xyz_seeds(const fs::path& out) {
  const std::string plain = "0 0 1\n1.5 -2 3e-1\n# a comment\n\n-1 2 nan\n4 5 6\n";
  const std::string colored = "1 2 3 255 0 10\n4 5 6 0 255 3\n-1e2 0.5 7 12 34 56\n";
  write(out / "xyz" / "plain.xyz", plain);
  write(out / "xyz" / "colored.xyz", colored);
  for (const auto& [name, text] : {std::pair{"plain", plain}, std::pair{"colored", colored}}) {
    std::vector<char> compressed(text.size() * 2 + 600);
    auto length = static_cast<unsigned>(compressed.size());
    std::string source = text;
    if (BZ2_bzBuffToBuffCompress(compressed.data(), &length, source.data(), static_cast<unsigned>(source.size()), 1, 0,
                                 30) != BZ_OK) {
      throw std::runtime_error("bz2 compression failed");
    }
    write(out / "xyz_bz2" / (std::string(name) + ".xyz.bz2"), Bytes(compressed.begin(), compressed.begin() + length));
  }
}

void ply_seeds(const fs::path& out) {
  write(out / "ply" / "ascii.ply",
        "ply\nformat ascii 1.0\ncomment made by umbra_fuzz_seeds\nelement vertex 3\nproperty float x\nproperty float "
        "y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\nproperty "
        "list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0.5 0 0 255\n3 0 1 2\n");
  Bytes little = bytes_of(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
      "z\nproperty ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n");
  for (int i = 0; i < 3; ++i) {
    for (const float v : {0.5f * static_cast<float>(i), 1.0f, -2.0f}) append(little, v);
    for (const std::uint16_t c : {std::uint16_t(1000), std::uint16_t(65535), std::uint16_t(0)}) append(little, c);
  }
  write(out / "ply" / "binary-little.ply", little);
  Bytes big = bytes_of(
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double "
      "z\nproperty float nx\nend_header\n");
  for (int i = 0; i < 2; ++i) {
    for (const double v : {1.0 * i, 2.0, 3.5}) append(big, v, true);
    append(big, 0.25f, true);
  }
  write(out / "ply" / "binary-big.ply", big);
}

void pcd_seeds(const fs::path& out) {
  const std::string fields = "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n";
  write(out / "pcd" / "ascii.pcd", fields + "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
                                            "0 0 1 16711680\n1 2 3 65280\nnan nan nan 255\n");
  Bytes binary = bytes_of(fields + "WIDTH 2\nHEIGHT 1\nVIEWPOINT 1 2 3 0.7071068 0 0 0.7071068\nPOINTS 2\nDATA binary\n");
  for (int i = 0; i < 2; ++i) {
    for (const float v : {1.0f, 0.5f * static_cast<float>(i), -1.0f}) append(binary, v);
    append(binary, std::uint32_t{0x00102030u});
  }
  write(out / "pcd" / "binary-viewpoint.pcd", binary);
  // binary_compressed: the fields column by column, LZF-coded as literal runs (control byte = length - 1).
  Bytes columns;
  for (int field = 0; field < 4; ++field) {
    for (int i = 0; i < 2; ++i) {
      if (field == 3) {
        append(columns, std::uint32_t{0x00ff00ffu});
      } else {
        append(columns, static_cast<float>(field + i));
      }
    }
  }
  Bytes lzf;
  for (std::size_t at = 0; at < columns.size(); at += 32) {
    const std::size_t run = std::min<std::size_t>(32, columns.size() - at);
    lzf.push_back(static_cast<std::uint8_t>(run - 1));
    lzf.insert(lzf.end(), columns.begin() + static_cast<std::ptrdiff_t>(at),
               columns.begin() + static_cast<std::ptrdiff_t>(at + run));
  }
  Bytes compressed = bytes_of(fields + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary_compressed\n");
  append(compressed, static_cast<std::uint32_t>(lzf.size()));
  append(compressed, static_cast<std::uint32_t>(columns.size()));
  compressed.insert(compressed.end(), lzf.begin(), lzf.end());
  write(out / "pcd" / "binary-compressed.pcd", compressed);
}

void kitti_seeds(const fs::path& out) {
  Bytes scan;
  for (int i = 0; i < 10; ++i) {
    for (const float v : {static_cast<float>(i), -1.0f, 0.25f, 0.5f}) append(scan, v);
  }
  write(out / "kitti" / "000000.bin", scan);
}

/// `umbra query` input lines: byte 0 holds the settings (fuzz_query_lines.cpp:
/// kind in bits 0-1, unknown-is-free bit 2, depth bits 3-4, radius bits 5-7),
/// then good lines of the kind, a comment, a blank line and a few bad ones.
/// rosbag: the tests' small bag (clouds, /tf, /tf_static, another type) in each compression the reader knows.
void rosbag_seeds(const fs::path& out) {
#ifdef UMBRA_FUZZ_ROSBAG_SEEDS
  for (const char* compression : {"none", "bz2", "lz4"}) {
    write(out / "rosbag" / (std::string("small-") + compression + ".bag"), umbra::test::small_bag(compression).bytes);
  }
#else
  (void)out;
#endif
}

void query_line_seeds(const fs::path& out) {
  const char* const lines[] = {
      "0.5 0.2 0.1 0.3\n1 1 1 0.05\n# comment\n\n-2,0,0.5,1\n0.1 0.2 nan 1\n500 0 0 0.1\n",       // sphere
      "0 0 0 0.5 0.5 0.5\n-1 -1 -1 1 1 1\n2 2 2 1 1 1\n0 0 0 1 1\n0 0 0 20 20 20\n",              // box
      "0 0 0 2 0 0\n0.5 0.2 0.1 0.5 0.2 4\n1e308 0 0 0 0 0\n0 0 0 0 0 0\n",                        // line
      "0.55 0.25 0.15 1 0 0 -1\n0.55 0.25 0.15 0 0 1 10\n0 0 0 0 0 0 5\n0 0 0 1 1 1 inf\n",      // raycast
  };
  fs::create_directories(out / "query_lines");
  for (unsigned kind = 0; kind < 4; ++kind) {
    for (const unsigned settings : {0u, 4u, 8u, 0x20u, 0x44u}) {
      std::string seed(1, static_cast<char>(kind | settings));
      seed += lines[kind];
      write(out / "query_lines" / ("q" + std::to_string(kind) + "-" + std::to_string(settings)), seed);
    }
  }
}

/// Point insertion (fuzz_insert.cpp): the inputs of issue 21 for every
/// integrator. A coordinate is a kind byte and a payload byte (kind 0: 0,
/// payload bit 7 the sign; 1: a tiny value; 2: a whole number of voxels,
/// payload & 63 minus 32; 8: the sensor's coordinate).
void insert_seeds(const fs::path& out) {
  const Bytes sensor_at_zero = {0, 0, 0, 0, 0, 0};
  const Bytes hair_point = {1, 0x80, 1, 0x00, 0, 0};     // (-1e-23, 1e-23, 0)
  const Bytes hair_point_29 = {1, 0x81, 1, 0x01, 0, 0};  // (-1e-29, 1e-29, 0)
  const Bytes axis_point = {8, 0, 8, 0, 2, 2};           // (0, 0, -30 voxels)
  const Bytes axis_points = {2, 62, 8, 0, 8, 0, 8, 0, 2, 2, 8, 0, 2, 7, 8, 0, 8, 0};  // +-x, -y: along edges
  fs::create_directories(out / "insert");
  for (const std::uint8_t integrator : {0, 1, 2}) {
    for (const std::uint8_t more : {0, 1 << 2 | 2, 5 << 2 | 1 << 5}) {  // fine steps / max range / resolution
      const std::string name = std::to_string(integrator) + "-" + std::to_string(more);
      const auto seed = [&](const char* what, std::uint8_t count, std::initializer_list<Bytes> points) {
        Bytes bytes = {integrator, more, 0};
        bytes.insert(bytes.end(), sensor_at_zero.begin(), sensor_at_zero.end());
        bytes.push_back(count);
        for (const Bytes& p : points) bytes.insert(bytes.end(), p.begin(), p.end());
        write(out / "insert" / (std::string(what) + "-" + name), bytes);
      };
      seed("hair", 0, {hair_point});
      seed("hair29", 1, {hair_point_29, axis_point});
      seed("axis", 0, {axis_point});
      seed("edges", 2, {Bytes(axis_points.begin(), axis_points.end())});
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return 2;
  }
  try {
    const fs::path out = argv[1];
    octomap_seeds(out);
    umb_seeds(out);
    graph_seeds(out);
    xyz_seeds(out);
    ply_seeds(out);
    pcd_seeds(out);
    kitti_seeds(out);
    rosbag_seeds(out);
    query_line_seeds(out);
    insert_seeds(out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "umbra_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
