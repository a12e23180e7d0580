// Reader for KITTI velodyne scans with KITTI odometry poses (see kitti_sequence.hpp).
//
// Opening lists the scan files (a folder's *.bin in name order, one file, or
// the caller's list), parses the whole poses file (12 numbers per line, a
// few hundred KB for the longest sequences) and the calibration, and checks
// that every scan has its pose line. next() opens one .bin file, checks its
// size is a multiple of 16 bytes, reads it through a 1 MiB buffer and maps
// each point with the scan's combined pose (computed in double, rounded to
// float once). Cost: one pass over each file, O(points of one scan) memory.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "reader_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/kitti_sequence.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {
namespace {

using detail::ByteReader;
using detail::InputFile;
using detail::LineReader;
using detail::Pose;
using detail::quote;
using detail::Tokens;

constexpr std::size_t kPointBytes = 16;  // float32 x, y, z, reflectance

namespace fs = std::filesystem;

bool is_bin_file(const fs::path& path) { return detail::to_lower(path.extension().string()) == ".bin"; }

/// The number a scan file is named by ("000123.bin" -> 123), if it is one.
std::optional<std::uint64_t> scan_number(const fs::path& path) {
  const std::string stem = path.stem().string();
  if (stem.empty() || stem.size() > 18 ||
      !std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c) != 0; })) {
    return std::nullopt;
  }
  std::uint64_t number = 0;
  detail::parse_unsigned(stem, number);
  return number;
}

/// A 3x4 row-major matrix from 12 numbers on a line.
Pose pose_from_row(const double (&values)[12]) {
  Pose pose;
  for (std::size_t row = 0; row < 3; ++row) {
    for (std::size_t column = 0; column < 4; ++column) pose.m[row][column] = values[row * 4 + column];
  }
  return pose;
}

/// Below this |determinant| a pose's 3x3 part is refused: it would squash the scan onto a plane,
/// a line or a point (an all-zero row). A rotation has 1; an affine pose scaling by 1% has 1e-6.
constexpr double kMinPoseDeterminant = 1e-6;

/// Throws FormatError at `line` unless the pose keeps the scan three-dimensional.
void require_rotation(const Pose& pose, const std::string& file, std::uint64_t line, std::string_view text) {
  const double determinant = pose.determinant();
  if (std::abs(determinant) >= kMinPoseDeterminant) return;
  char value[32];
  std::snprintf(value, sizeof value, "%g", determinant);
  throw FormatError::at_line(file, line,
                             std::string("the 3x3 rotation part has determinant ") + value +
                                 " (a rotation has 1): every point would collapse onto a plane, a line or the "
                                 "translation; found " + quote(text));
}

/// Fills `values` from `tokens`; false if there are fewer or more numbers,
/// or one is not a finite number.
bool read_numbers(Tokens& tokens, std::span<double> values) {
  for (double& value : values) {
    const std::string_view token = tokens.next();
    if (!detail::parse_double(token, value) || !std::isfinite(value)) return false;
  }
  return tokens.at_end();
}

std::vector<Pose> read_poses(const fs::path& path) {
  InputFile file(path);
  LineReader lines(file, 0);
  std::vector<Pose> poses;
  std::string_view line;
  while (lines.next(line)) {
    Tokens tokens(line);
    if (tokens.at_end()) {
      // Blank lines are tolerated only at the end of the file.
      const std::uint64_t blank_line = lines.line_number();
      if (lines.next_non_blank(line)) {
        throw FormatError::at_line(file.name(), blank_line,
                                   "blank line inside the poses (the line number of a pose is its scan number)");
      }
      break;
    }
    double values[12];
    if (!read_numbers(tokens, values)) {
      throw FormatError::at_line(file.name(), lines.line_number(),
                                 "expected 12 finite numbers (a row-major 3x4 pose), found " + quote(line));
    }
    poses.push_back(pose_from_row(values));
    require_rotation(poses.back(), file.name(), lines.line_number(), line);
  }
  if (poses.empty()) throw FormatError(file.name(), "the poses file holds no poses");
  return poses;
}

/// The velodyne-to-camera transform of a KITTI calibration file.
Pose read_calibration(const fs::path& path) {
  InputFile file(path);
  LineReader lines(file, 0);
  std::optional<Pose> transform;
  std::optional<std::array<double, 9>> rotation;
  std::optional<std::array<double, 3>> translation;
  std::string_view line;
  while (lines.next(line)) {
    Tokens tokens(line);
    const std::string_view key = tokens.next();
    const auto bad = [&](const char* expected) {
      throw FormatError::at_line(file.name(), lines.line_number(),
                                 std::string("expected ") + expected + ", found " + quote(line));
    };
    if (key == "Tr:" || key == "Tr_velo_to_cam:" || key == "Tr_velo_cam:") {
      double values[12];
      if (!read_numbers(tokens, values)) bad("12 finite numbers after the key (the 3x4 velodyne-to-camera transform)");
      transform = pose_from_row(values);
      require_rotation(*transform, file.name(), lines.line_number(), line);
    } else if (key == "R:") {
      double values[9];
      if (!read_numbers(tokens, values)) bad("9 finite numbers after R: (row-major rotation)");
      rotation.emplace();
      std::copy(std::begin(values), std::end(values), rotation->begin());
      Pose check;
      for (std::size_t i = 0; i < 9; ++i) check.m[i / 3][i % 3] = values[i];
      require_rotation(check, file.name(), lines.line_number(), line);
    } else if (key == "T:") {
      double values[3];
      if (!read_numbers(tokens, values)) bad("3 finite numbers after T: (translation)");
      translation = {values[0], values[1], values[2]};
    }
  }
  if (transform) return *transform;
  if (rotation && translation) {
    Pose pose;
    for (std::size_t row = 0; row < 3; ++row) {
      for (std::size_t column = 0; column < 3; ++column) pose.m[row][column] = (*rotation)[row * 3 + column];
      pose.m[row][3] = (*translation)[row];
    }
    return pose;
  }
  throw FormatError(file.name(),
                    "no velodyne-to-camera transform: expected a line 'Tr: <12 numbers>' (odometry calib.txt), "
                    "'Tr_velo_to_cam: <12 numbers>', or 'R: <9 numbers>' and 'T: <3 numbers>' (calib_velo_to_cam.txt)");
}

struct ScanEntry {
  fs::path file;
  Pose pose;  // sensor to world
  std::optional<std::size_t> pose_line;
};

class KittiReader final : public ScanSource {
 public:
  KittiReader(std::vector<fs::path> files, const KittiOptions& options) : origin_(options.origin) {
    if (files.empty()) throw std::invalid_argument("open_kitti_scans: no scan files given");
    if (options.poses.empty() && files.size() > 1) {
      throw std::invalid_argument(
          "KITTI: " + std::to_string(files.size()) +
          " scans but no poses file (ScanSourceOptions::poses / KittiOptions::poses); without poses every scan "
          "would be placed at the same spot");
    }
    Pose calibration;
    if (!options.calibration.empty()) calibration = read_calibration(options.calibration);
    std::vector<Pose> poses;
    if (!options.poses.empty()) poses = read_poses(options.poses);

    const bool numbered = std::all_of(files.begin(), files.end(), [](const fs::path& file) { return scan_number(file).has_value(); });
    scans_.reserve(files.size());
    for (std::size_t index = 0; index < files.size(); ++index) {
      ScanEntry entry;
      entry.file = std::move(files[index]);
      if (!poses.empty()) {
        const std::uint64_t line = numbered ? *scan_number(entry.file) : index;
        if (line >= poses.size()) {
          throw FormatError(options.poses.string(),
                            "has " + std::to_string(poses.size()) + " poses, but scan " + entry.file.filename().string() +
                                " needs line " + std::to_string(line + 1) +
                                (numbered ? " (scans named by a number use the pose of that number)" : ""));
        }
        entry.pose = poses[static_cast<std::size_t>(line)] * calibration;
        entry.pose_line = static_cast<std::size_t>(line + 1);
      }
      scans_.push_back(std::move(entry));
    }
  }

  bool next(Scan& scan) override {
    if (next_scan_ >= scans_.size()) return false;
    const ScanEntry& entry = scans_[next_scan_];
    InputFile file(entry.file);
    const std::uint64_t size = file.size();
    if (size % kPointBytes != 0) {
      throw FormatError::at_byte(file.name(), size - size % kPointBytes,
                                 "the file has " + std::to_string(size) +
                                     " bytes, not a multiple of 16 (float32 x y z reflectance per point): truncated?");
    }
    const std::uint64_t point_count = size / kPointBytes;
    detail::require_point_memory(file.name(), "reading its " + std::to_string(point_count) + " points", point_count,
                                    false);
    scan.points.clear();
    scan.colors.clear();
    scan.points.reserve(static_cast<std::size_t>(point_count));
    scan.stamp.reset();  // this format carries no times
    scan.name = entry.file.filename().string();
    if (entry.pose_line) scan.name += " (pose line " + std::to_string(*entry.pose_line) + ")";
    const bool posed = entry.pose_line.has_value();
    scan.origin = posed ? entry.pose.translation() : origin_;

    ByteReader reader(file, 0);
    for (std::uint64_t point = 0; point < point_count; ++point) {
      const unsigned char* record = reader.take(kPointBytes);
      if (record == nullptr) {
        throw FormatError::at_byte(file.name(), reader.offset(), "truncated file: it shrank while being read");
      }
      const Vec3f p{std::bit_cast<float>(static_cast<std::uint32_t>(detail::load_bits(record, 4, false))),
                    std::bit_cast<float>(static_cast<std::uint32_t>(detail::load_bits(record + 4, 4, false))),
                    std::bit_cast<float>(static_cast<std::uint32_t>(detail::load_bits(record + 8, 4, false)))};
      scan.points.push_back(posed ? entry.pose.apply(p) : p);
    }
    ++next_scan_;
    done_.store(next_scan_, std::memory_order_relaxed);
    return true;
  }

  [[nodiscard]] std::size_t scan_count() const override { return scans_.size(); }

  [[nodiscard]] std::vector<Vec3f> origins() const override {
    std::vector<Vec3f> result;
    result.reserve(scans_.size());
    for (const ScanEntry& entry : scans_) result.push_back(entry.pose_line ? entry.pose.translation() : origin_);
    return result;
  }

  [[nodiscard]] double progress() const override {
    return static_cast<double>(done_.load(std::memory_order_relaxed)) / static_cast<double>(scans_.size());
  }

 private:
  Vec3f origin_;
  std::vector<ScanEntry> scans_;
  std::size_t next_scan_ = 0;
  std::atomic<std::size_t> done_{0};
};

}  // namespace

std::unique_ptr<ScanSource> open_kitti_velodyne(const fs::path& folder_or_file, const KittiOptions& options) {
  std::error_code error;
  const fs::file_status status = fs::status(folder_or_file, error);
  if (error || !fs::exists(status)) {
    throw std::runtime_error("cannot open " + folder_or_file.string() + ": " +
                             (error ? error.message() : std::string("No such file or directory")));
  }
  if (!fs::is_directory(status)) return open_kitti_scans({folder_or_file}, options);
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder_or_file)) {
    if (is_bin_file(entry.path()) && entry.is_regular_file()) files.push_back(entry.path());
  }
  if (files.empty()) {
    throw std::runtime_error("cannot open " + folder_or_file.string() +
                             ": the folder holds no .bin files (KITTI velodyne scans)");
  }
  std::sort(files.begin(), files.end());
  return open_kitti_scans(std::move(files), options);
}

std::unique_ptr<ScanSource> open_kitti_scans(std::vector<fs::path> scan_files, const KittiOptions& options) {
  const fs::path first = scan_files.empty() ? fs::path() : scan_files.front();
  return detail::naming_bad_alloc(first, [&] { return std::make_unique<KittiReader>(std::move(scan_files), options); });
}

}  // namespace umbra
