// The memory limit (umbra/core/memory_limit.hpp) against every loader and
// reader: small files that need a lot of memory are refused before the
// memory is allocated, with a message naming the file, the need and the
// limit; a std::bad_alloc that happens anyway comes out naming the file.
//
// The needs are checked against numbers worked out here from what the files
// hold (node counts of full trees, point counts) and against the maps that
// load once the limit allows them. Cost: about a second; the largest file
// is a full tree of 6 depth levels (262,144 voxels).
#include <bzlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.hpp"
#include "umbra/core/memory_limit.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/octomap_files.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/map_statistics.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// The message of the MemoryLimitError `action` throws (a test failure if it throws nothing or something else).
template <typename Action>
std::string memory_error_of(Action&& action) {
  try {
    action();
  } catch (const MemoryLimitError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "expected MemoryLimitError, got: " << error.what();
    return "";
  }
  ADD_FAILURE() << "expected MemoryLimitError, nothing was thrown";
  return "";
}

/// " (N bytes)" as the messages write sizes.
std::string bytes(std::uint64_t n) { return "(" + std::to_string(n) + " bytes)"; }

/// Every voxel of a map of `depth_levels` levels set to one value, with
/// auto-pruning off: the file is tiny (zstd), the tree is full.
OccupancyMap full_unpruned_map(int depth_levels, bool color) {
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = depth_levels;
  config.color = color;
  OccupancyMap map(config);
  map.set_auto_prune(false);
  const std::uint32_t side = 1u << depth_levels;
  for (std::uint32_t x = 0; x < side; ++x) {
    for (std::uint32_t y = 0; y < side; ++y) {
      for (std::uint32_t z = 0; z < side; ++z) {
        map.set_log_odds(Key{x, y, z}, 1.0f);
        if (color) map.set_color(Key{x, y, z}, Rgb{10, 20, 30});
      }
    }
  }
  return map;
}

/// 8^0 + 8^1 + ... + 8^(n-1).
std::uint64_t sum_of_powers_of_eight(int n) {
  std::uint64_t total = 0;
  for (int k = 0, power = 1; k < n; ++k, power *= 8) total += static_cast<std::uint64_t>(power);
  return total;
}

TEST(MemoryLimit, DefaultIsHalfOfWhatTheMachineAllowsAndCanBeChanged) {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const std::uint64_t physical = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(::sysconf(_SC_PAGE_SIZE));
  EXPECT_LE(default_memory_limit(), std::max<std::uint64_t>(physical / 2, std::uint64_t{64} << 20));
  EXPECT_GE(default_memory_limit(), std::uint64_t{64} << 20);
  {
    const test::MemoryLimitScope scope(12345);
    EXPECT_EQ(memory_limit(), 12345u);
    set_memory_limit(0);
    EXPECT_EQ(memory_limit(), default_memory_limit());
  }
}

// The issue's .umb bomb, scaled down: a full unpruned tree compresses to a
// few kilobytes, but every inner node costs a group of children.
TEST(MemoryLimit, UmbLoadStatesTheTreesNeedAndRefusesItBeforeAllocating) {
  const fs::path dir = test::scratch_dir();
  for (const bool color : {false, true}) {
    SCOPED_TRACE(color ? "color" : "no color");
    const int depth_levels = color ? 5 : 6;
    const fs::path path = dir / (color ? "full_color.umb" : "full.umb");
    const OccupancyMap saved = full_unpruned_map(depth_levels, color);
    save_map(saved, path);
    const std::uint64_t file_bytes = fs::file_size(path);
    EXPECT_LT(file_bytes, 16'000u) << "the point of the test is a small file";
    // Inner nodes at depths >= 2 have 68-byte groups of children, those at depth 1 32-byte ones; color adds 32.
    const std::uint64_t above_finest = sum_of_powers_of_eight(depth_levels - 1);
    const std::uint64_t at_finest = std::uint64_t{1} << (3 * (depth_levels - 1));
    const std::uint64_t tree = above_finest * (68 + (color ? 32 : 0)) + at_finest * (32 + (color ? 32 : 0));
    const std::uint64_t need = tree + file_bytes;
    {
      const test::MemoryLimitScope limit(need - 1);
      const std::string message = memory_error_of([&] { (void)load_map(path); });
      EXPECT_TRUE(contains(message, path.string() + ": loading this map (" + std::to_string(above_finest + at_finest) +
                                        " nodes with children) needs ")) << message;
      EXPECT_TRUE(contains(message, bytes(need) + ", more than the memory limit of ")) << message;
      EXPECT_TRUE(contains(message, bytes(need - 1))) << message;
      EXPECT_TRUE(contains(message, "--max-memory")) << message;
    }
    const test::MemoryLimitScope limit(need);
    const OccupancyMap loaded = load_map(path);
    EXPECT_EQ(loaded.node_counts().inner, above_finest + at_finest);
    // The need is what the tree really takes (the pools round up to blocks, never down).
    EXPECT_GE(loaded.memory_bytes(), tree);
    EXPECT_LE(loaded.memory_bytes(), 2 * tree);
  }
}

// OctoMap files: .bt says its nodes with children by its length (2 bytes
// each); .ot needs its child masks counted when the size alone would allow
// more than the limit.
TEST(MemoryLimit, OctoMapLoadsStateTheTreesNeed) {
  const fs::path dir = test::scratch_dir();
  MapConfig config;
  config.resolution = 0.05;
  config.color = true;
  OccupancyMap map(config);
  for (int i = 0; i < 3000; ++i) {
    const double x = 0.05 * (i % 40);
    const double y = 0.05 * ((i / 40) % 40);
    const double z = 0.05 * (i / 1600);
    map.set_log_odds(Vec3d{x, y, z}, (i % 3 == 0) ? -1.0f : 1.5f);
    map.set_color(map.key({x, y, z}), Rgb{static_cast<std::uint8_t>(i % 200), 5, 6});
  }
  for (const OctoMapFormat format : {OctoMapFormat::bt, OctoMapFormat::ot}) {
    SCOPED_TRACE(to_string(format));
    const fs::path path = dir / (format == OctoMapFormat::bt ? "map.bt" : "map.ot");
    save_octomap(map, path, format);
    const OctoMapFileInfo info = read_octomap_info(path);
    std::uint64_t parents = 0;
    {
      const test::MemoryLimitScope unlimited(UINT64_MAX);
      parents = load_octomap(path).node_counts().inner;
    }
    if (format == OctoMapFormat::bt) {
      EXPECT_EQ(parents, (info.file_bytes - info.data_offset) / 2);
    }
    const std::uint64_t need = parents * (68 + (format == OctoMapFormat::ot ? 32 : 0));
    {
      const test::MemoryLimitScope limit(need - 1);
      const std::string message = memory_error_of([&] { (void)load_octomap(path); });
      EXPECT_TRUE(contains(message, path.string() + ": loading this OctoMap tree (" + std::to_string(info.nodes) +
                                        " nodes, " + std::to_string(parents) + " with children) needs ")) << message;
      EXPECT_TRUE(contains(message, bytes(need) + ", more than the memory limit of ")) << message;
    }
    const test::MemoryLimitScope limit(need);
    EXPECT_EQ(load_octomap(path).node_counts().inner, parents);
  }
}

// A bad_alloc that happens anyway names the file. The file is written by a
// child process so that this process has no freed heap the load could reuse
// under the address-space cap.
TEST(MemoryLimit, RunningOutOfMemoryWhileLoadingNamesTheFile) {
  const test::AddressSpaceCap probe(std::uint64_t{1} << 40);
  if (!probe.active()) GTEST_SKIP() << "no address-space limit here (AddressSanitizer): cannot make memory run out";
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "full.umb";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      save_map(full_unpruned_map(7, false), path);
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  const test::MemoryLimitScope unlimited(UINT64_MAX);
  std::string message;
  {
    const test::AddressSpaceCap cap(std::uint64_t{2} << 20);  // the map needs about 11 MiB
    message = memory_error_of([&] { (void)load_map(path); });
  }
  EXPECT_TRUE(contains(message, path.string() + ": out of memory while loading the map (it needs about ")) << message;
}

/// `copies` x 100,000 lines "1 2 3" as bz2: one compressed stream repeated
/// (bzip2 files may be concatenated streams), so that making it is quick.
std::string repeated_point_bz2(int copies) {
  std::string text;
  for (int i = 0; i < 100'000; ++i) text += "1 2 3\n";
  std::string stream(16 * 1024, '\0');
  auto size = static_cast<unsigned>(stream.size());
  EXPECT_EQ(BZ2_bzBuffToBuffCompress(stream.data(), &size, text.data(), static_cast<unsigned>(text.size()), 9, 0, 0),
            BZ_OK);
  stream.resize(size);
  std::string file;
  for (int i = 0; i < copies; ++i) file += stream;
  return file;
}

// The issue's .xyz.bz2 bomb, scaled down: a million copies of one point in a
// few hundred bytes. The format has no count, so the points are checked as
// their buffer grows, and refused long before the file is read.
TEST(MemoryLimit, XyzPointsAreCheckedAsTheyArrive) {
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "same.xyz.bz2";
  test::write_file(path, repeated_point_bz2(10));
  EXPECT_LT(fs::file_size(path), 2000u);
  const test::MemoryLimitScope limit(std::uint64_t{4} << 20);
  const auto source = open_scan_source(path);
  Scan scan;
  const std::string message = memory_error_of([&] { source->next(scan); });
  // 4 MiB holds 349,525 points: the buffer is refused when it would grow from 262,144 to 524,288.
  EXPECT_TRUE(contains(message, path.string() + ": making room for 524288 points (262144 read so far; the file does "
                                "not say how many follow) needs 6.0 MiB (6291456 bytes), more than the memory limit "
                                "of 4.0 MiB (4194304 bytes)")) << message;
  const test::MemoryLimitScope enough(std::uint64_t{16} << 20);
  EXPECT_EQ(test::read_all(path).front().points.size(), 1'000'000u);
}

// Formats that declare their count are refused when they are opened, before
// any point is read (so `umbra build` refuses them before inserting anything).
TEST(MemoryLimit, DeclaredPointCountsAreCheckedWhenOpening) {
  const fs::path dir = test::scratch_dir();
  constexpr std::size_t kPoints = 100'000;
  const std::uint64_t need = kPoints * 12;
  // PLY, binary: the file is as large as the points.
  {
    std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(kPoints) +
                      "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    ply.append(kPoints * 12, '\0');
    test::write_file(dir / "big.ply", ply);
  }
  // PCD, ascii.
  {
    std::string pcd = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " + std::to_string(kPoints) +
                      "\nHEIGHT 1\nPOINTS " + std::to_string(kPoints) + "\nDATA ascii\n";
    for (std::size_t i = 0; i < kPoints; ++i) pcd += "1 2 3\n";
    test::write_file(dir / "big.pcd", pcd);
  }
  // ScanGraph: a small scan, then the big one.
  {
    Scan small;
    small.points = {{1, 2, 3}};
    Scan big;
    big.points.assign(kPoints, Vec3f{1, 2, 3});
    write_scan_graph(dir / "big.graph", {small, big});
  }
  const test::MemoryLimitScope limit(need - 1);
  for (const auto& [file, what] : {std::pair{"big.ply", "reading its 100000 vertices"},
                                   std::pair{"big.pcd", "reading its 100000 points"},
                                   std::pair{"big.graph", "reading scan 1 (100000 points)"}}) {
    const std::string message = memory_error_of([&] { (void)open_scan_source(dir / file); });
    EXPECT_TRUE(contains(message, (dir / file).string() + ": " + what + " needs 1.1 MiB " + bytes(need) +
                                      ", more than the memory limit of 1.1 MiB " + bytes(need - 1)))
        << message;
  }
  const test::MemoryLimitScope enough(need);
  for (const char* file : {"big.ply", "big.pcd", "big.graph"}) {
    EXPECT_EQ(test::read_all(dir / file).back().points.size(), kPoints) << file;
  }
}

// KITTI scans have no header: the file size gives the count before reading.
TEST(MemoryLimit, KittiScansAreCheckedByTheirSize) {
  const fs::path dir = test::scratch_dir();
  constexpr std::size_t kPoints = 100'000;
  test::write_file(dir / "000000.bin", std::string(kPoints * 16, '\0'));
  const test::MemoryLimitScope limit(kPoints * 12 - 1);
  const auto source = open_scan_source(dir / "000000.bin");
  Scan scan;
  const std::string message = memory_error_of([&] { source->next(scan); });
  EXPECT_TRUE(contains(message, (dir / "000000.bin").string() + ": reading its 100000 points needs 1.1 MiB " +
                                    bytes(kPoints * 12))) << message;
  EXPECT_EQ(scan.points.capacity(), 0u);
}

// A bad_alloc while reading a scan names the file and the points read.
TEST(MemoryLimit, RunningOutOfMemoryWhileReadingNamesTheFile) {
  const fs::path dir = test::scratch_dir();
  const fs::path path = dir / "many.xyz.bz2";
  test::write_file(path, repeated_point_bz2(20));
  const test::MemoryLimitScope unlimited(UINT64_MAX);
  const auto source = open_scan_source(path);
  Scan scan;
  std::string message;
  {
    const test::AddressSpaceCap cap(std::uint64_t{8} << 20);  // the points need 24 MiB
    if (!cap.active()) GTEST_SKIP() << "no address-space limit here (AddressSanitizer): cannot make memory run out";
    message = memory_error_of([&] { source->next(scan); });
  }
  EXPECT_TRUE(contains(message, path.string() + ": out of memory while reading a scan (")) << message;
  EXPECT_TRUE(contains(message, " points so far)")) << message;
}

}  // namespace
}  // namespace umbra
