// Spill files of a moving window: the pieces written are the pieces the
// window handed out (load_spill adds them up as merging them by hand does);
// an append that fails leaves the file as it was; a damaged file gets an
// error naming the file, the piece and the byte offset.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "support/query_oracle.hpp"
#include "support/test_support.hpp"
#include "umbra/io/spill_file.hpp"

namespace umbra {
namespace {

std::vector<char> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void write_bytes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// A short drive with a window spilling to `path` and into `pieces`.
OccupancyMap drive(const std::filesystem::path& path, std::vector<OccupancyMap>& pieces) {
  OccupancyMap map(0.2, 5);  // small, so that the dense comparisons stay quick
  MovingWindow window;
  window.half_extent = 0.5;
  window.step_depth = 1;
  const auto to_file = spill_to_file(path);
  window.spill = [&](const OccupancyMap& piece) {
    to_file(piece);
    pieces.push_back(piece);
  };
  map.set_moving_window(window);
  std::mt19937 random(4);
  std::uniform_real_distribution<double> offset(-0.45, 0.45);
  for (int i = 0; i < 20; ++i) {
    const Vec3d robot{-2.0 + 0.2 * i, 0.1 * (i % 3), 0.0};
    std::vector<Vec3f> points;
    for (int p = 0; p < 50; ++p) {
      points.push_back(Vec3f(Vec3d{robot.x + offset(random), robot.y + offset(random), robot.z + offset(random)}));
    }
    map.insert_point_cloud(Vec3f(robot), points);
  }
  return map;
}

void expect_same(const OccupancyMap& a, const OccupancyMap& b) {
  const test::DenseValues got(a);
  const test::DenseValues want(b);
  ASSERT_EQ(got.size(), want.size());
  for (std::uint32_t z = 0; z < got.size(); ++z) {
    for (std::uint32_t y = 0; y < got.size(); ++y) {
      for (std::uint32_t x = 0; x < got.size(); ++x) ASSERT_EQ(got.at({x, y, z}), want.at({x, y, z}));
    }
  }
}

TEST(SpillFile, HoldsThePiecesTheWindowHandedOut) {
  const auto path = test::scratch_dir() / "run.umbs";
  std::vector<OccupancyMap> pieces;
  (void)drive(path, pieces);
  ASSERT_GT(pieces.size(), 5u);
  std::size_t index = 0;
  const std::size_t count = for_each_spill_piece(path, [&](OccupancyMap&& piece) {
    ASSERT_LT(index, pieces.size());
    expect_same(piece, pieces[index++]);
  });
  EXPECT_EQ(count, pieces.size());
  OccupancyMap by_hand = pieces.front();
  for (std::size_t i = 1; i < pieces.size(); ++i) by_hand.merge(pieces[i]);
  expect_same(load_spill(path), by_hand);
}

TEST(SpillFile, AFailedAppendLeavesTheFileAsItWas) {
  const auto path = test::scratch_dir() / "run.umbs";
  std::vector<OccupancyMap> pieces;
  (void)drive(path, pieces);
  const std::vector<char> before = read_bytes(path);
  // A file size limit just past the file: the write stops part way (EFBIG).
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit limit = old_limit;
  limit.rlim_cur = before.size() + 40;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  std::string message;
  try {
    append_spill_piece(path, pieces.back());
  } catch (const std::runtime_error& error) {
    message = error.what();
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("the file is as before"), std::string::npos) << message;
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_EQ(for_each_spill_piece(path, [](OccupancyMap&&) {}), pieces.size());
}

std::string load_error(const std::filesystem::path& path) {
  try {
    (void)load_spill(path);
  } catch (const FormatError& error) {
    return error.what();
  }
  return "no error";
}

/// The bytes of a spill file of a short drive (in `folder`), its pieces in `pieces`.
std::vector<char> driven_spill_bytes(const std::filesystem::path& folder, std::vector<OccupancyMap>& pieces) {
  const auto path = folder / "run.umbs";
  (void)drive(path, pieces);
  return read_bytes(path);
}

/// The size N in the header of the piece that starts at byte `at`.
std::uint64_t piece_size_at(const std::vector<char>& bytes, std::uint64_t at) {
  std::uint64_t size = 0;
  for (int i = 0; i < 8; ++i) size |= std::uint64_t{static_cast<unsigned char>(bytes[at + 8 + i])} << (8 * i);
  return size;
}

TEST(SpillFile, ADamagedFileIsNamedWithTheByteOffset) {
  const auto folder = test::scratch_dir();
  std::vector<OccupancyMap> pieces;
  const std::vector<char> good = driven_spill_bytes(folder, pieces);
  const std::uint64_t second = 16 + piece_size_at(good, 0);

  const auto truncated = folder / "truncated.umbs";
  write_bytes(truncated, std::vector<char>(good.begin(), good.end() - 10));
  EXPECT_NE(load_error(truncated).find("truncated"), std::string::npos) << load_error(truncated);
  EXPECT_NE(load_error(truncated).find(truncated.string() + ": byte "), std::string::npos) << load_error(truncated);

  const auto bad_magic = folder / "bad_magic.umbs";
  std::vector<char> bytes = good;
  bytes[second] = 'X';
  write_bytes(bad_magic, bytes);
  EXPECT_NE(load_error(bad_magic).find("byte " + std::to_string(second) + ": piece 2: magic"), std::string::npos)
      << load_error(bad_magic);

  const auto corrupt = folder / "corrupt.umbs";
  bytes = good;
  bytes[second + 16 + 126] ^= 0x5a;  // inside the second piece's map file, just past its header
  write_bytes(corrupt, bytes);
  EXPECT_NE(load_error(corrupt).find("piece 2, its map file starting at byte " + std::to_string(second + 16)),
            std::string::npos)
      << load_error(corrupt);

  const auto empty = folder / "empty.umbs";
  write_bytes(empty, {});
  EXPECT_NE(load_error(empty).find("holds no pieces"), std::string::npos) << load_error(empty);
}

TEST(SpillFile, ALastPieceCutShortNamesWhereTheWholePiecesEnd) {
  // A crash in the middle of an append leaves part of the last piece at the
  // end (pieces are only appended): the error says where the whole ones end,
  // and the file cut there holds them all.
  const auto folder = test::scratch_dir();
  std::vector<OccupancyMap> pieces;
  const std::vector<char> good = driven_spill_bytes(folder, pieces);
  std::uint64_t last = 0;  // where the last piece starts
  for (std::uint64_t at = 0; at < good.size(); at += 16 + piece_size_at(good, at)) last = at;
  for (const std::uint64_t cut : {last + 5, last + 20, static_cast<std::uint64_t>(good.size() - 1)}) {
    const auto torn = folder / "torn.umbs";
    write_bytes(torn, std::vector<char>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(cut)));
    const std::string message = load_error(torn);
    EXPECT_NE(message.find("the " + std::to_string(pieces.size() - 1) + " whole piece(s) before it end at byte " +
                           std::to_string(last) + ": cut the file to " + std::to_string(last) + " bytes"),
              std::string::npos)
        << "cut at " << cut << ": " << message;
    std::filesystem::resize_file(torn, last);
    EXPECT_EQ(for_each_spill_piece(torn, [](OccupancyMap&&) {}), pieces.size() - 1) << "cut at " << cut;
  }
}

}  // namespace
}  // namespace umbra
