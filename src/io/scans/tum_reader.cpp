// Reader for TUM RGB-D sequences (see tum_sequence.hpp).
//
// Opening reads the association file line by line (from_chars, errors with
// line numbers), keeps the rows whose two images exist, and converts their
// poses to matrices. next() decodes the frame's 16-bit depth PNG with
// libpng's low-level API (the simplified API would apply gamma handling to
// 16-bit data; here the samples arrive untouched, big-endian as stored),
// the color PNG with read_png, and back-projects every non-zero depth pixel
// with per-column and per-row factors computed once per image size. Cost
// per frame: decoding two 640x480 PNGs and one multiply-add pass; memory:
// one frame's images and points, reused from scan to scan.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <png.h>

#include "reader_support.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/png_writer.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/io/tum_sequence.hpp"

namespace umbra {
namespace {

namespace fs = std::filesystem;
using detail::InputFile;
using detail::LineReader;
using detail::Pose;
using detail::quote;
using detail::Tokens;

constexpr std::uint64_t kMaxDepthPixels = std::uint64_t{1} << 26;  // 64 Mpixel: no depth camera is larger
// The decoded 16-bit depth and RGB color images, their copy in the scan
// (ScanImage) and each point's pixel index.
constexpr std::uint64_t kImageBytesPerPixel = 2 + 3 + 2 + 3 + 4;

// --- 16-bit greyscale PNG decoding --------------------------------------------

/// libpng reports errors through a callback that must not return; it keeps
/// the message here and jumps back to the setjmp in the reading functions.
struct PngErrorState {
  char message[200] = {};
};

void on_png_error(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message);
  png_longjmp(png, 1);
}

void on_png_warning(png_structp, png_const_charp) {}

/// Owns a libpng read structure and its file.
class PngReadHandle {
 public:
  PngReadHandle(std::FILE* file, PngErrorState& state) : file_(file) {
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, on_png_error, on_png_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
  }
  PngReadHandle(const PngReadHandle&) = delete;
  PngReadHandle& operator=(const PngReadHandle&) = delete;
  ~PngReadHandle() {
    if (png_ != nullptr) png_destroy_read_struct(&png_, info_ != nullptr ? &info_ : nullptr, nullptr);
    std::fclose(file_);
  }
  [[nodiscard]] bool valid() const { return png_ != nullptr && info_ != nullptr; }
  [[nodiscard]] png_structp png() const { return png_; }
  [[nodiscard]] png_infop info() const { return info_; }
  [[nodiscard]] std::FILE* file() const { return file_; }

 private:
  std::FILE* file_;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

struct PngHeader {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int bit_depth = 0;
  int color_type = 0;
};

// The two functions below hold only trivially destructible locals between
// setjmp and any longjmp, and read nothing they changed after a jump.
bool read_png_header(png_structp png, png_infop info, std::FILE* file, PngHeader& header) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_init_io(png, file);
  png_read_info(png, info);
  png_get_IHDR(png, info, &header.width, &header.height, &header.bit_depth, &header.color_type, nullptr, nullptr,
               nullptr);
  return true;
}

bool read_png_rows(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

/// A 16-bit greyscale image as stored (2 bytes per pixel, big-endian).
struct PngDepth {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<unsigned char> samples;
  std::vector<png_bytep> rows;

  [[nodiscard]] std::uint32_t at(std::size_t index) const {
    return (static_cast<std::uint32_t>(samples[2 * index]) << 8) | samples[2 * index + 1];
  }
};

void read_depth_png(const fs::path& path, PngDepth& image) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw std::runtime_error("cannot open " + path.string() + ": " + detail::errno_text(errno));
  PngErrorState state;
  PngReadHandle handle(file, state);
  if (!handle.valid()) throw std::runtime_error("cannot read " + path.string() + ": libpng initialisation failed");
  unsigned char signature[8] = {};
  if (std::fread(signature, 1, sizeof signature, file) != sizeof signature ||
      png_sig_cmp(signature, 0, sizeof signature) != 0) {
    throw FormatError(path.string(), "not a PNG file (no PNG signature at the start)");
  }
  png_set_sig_bytes(handle.png(), sizeof signature);
  PngHeader header;
  if (!read_png_header(handle.png(), handle.info(), file, header)) {
    throw FormatError(path.string(), std::string("corrupt PNG header (libpng: ") + state.message + ")");
  }
  if (header.bit_depth != 16 || header.color_type != PNG_COLOR_TYPE_GRAY) {
    throw FormatError(path.string(), "expected a 16-bit greyscale depth image, found " +
                                         std::to_string(header.bit_depth) + "-bit samples of PNG color type " +
                                         std::to_string(header.color_type) + " (0 is greyscale)");
  }
  const std::uint64_t pixels = std::uint64_t{header.width} * header.height;
  if (pixels == 0 || pixels > kMaxDepthPixels) {
    throw FormatError(path.string(), "a depth image of " + std::to_string(header.width) + " x " +
                                         std::to_string(header.height) + " pixels is implausible");
  }
  detail::require_point_memory(path.string(),
                                  "a frame of " + std::to_string(header.width) + " x " +
                                      std::to_string(header.height) +
                                      " pixels (both images, the scan's copy of them and its points)",
                                  pixels, true, pixels * kImageBytesPerPixel);
  image.width = header.width;
  image.height = header.height;
  image.samples.resize(static_cast<std::size_t>(pixels * 2));
  image.rows.resize(header.height);
  for (std::size_t row = 0; row < header.height; ++row) {
    image.rows[row] = image.samples.data() + row * std::size_t{header.width} * 2;
  }
  if (!read_png_rows(handle.png(), handle.info(), image.rows.data())) {
    throw FormatError(path.string(), std::string("corrupt PNG data (libpng: ") + state.message + ")");
  }
}

// --- the association file -----------------------------------------------------

struct Frame {
  fs::path depth;
  fs::path color;
  std::string depth_text;  // as written in the association file
  std::optional<double> stamp;  // the depth file name's stem, when it is a number (TUM's timestamps)
  std::uint64_t line = 0;
  Pose pose;  // camera (optical frame) to world
};

/// TUM names each image by the time it was taken ("1311877812.987032.png");
/// other names give no stamp.
std::optional<double> stamp_of(const fs::path& image) {
  const std::string stem = image.stem().string();
  double seconds = 0.0;
  if (detail::parse_double(stem, seconds) && std::isfinite(seconds)) return seconds;
  return std::nullopt;
}

bool file_exists(const fs::path& path) {
  std::error_code ignored;
  return fs::is_regular_file(path, ignored);
}

void check_camera(const DepthCamera& camera) {
  const auto positive = [](double value) { return std::isfinite(value) && value > 0.0; };
  if (!positive(camera.fx) || !positive(camera.fy) || !positive(camera.depth_scale) || !std::isfinite(camera.cx) ||
      !std::isfinite(camera.cy)) {
    throw std::invalid_argument("DepthCamera: fx, fy and depth_scale must be finite and > 0 and cx, cy finite; got fx " +
                                std::to_string(camera.fx) + ", fy " + std::to_string(camera.fy) + ", cx " +
                                std::to_string(camera.cx) + ", cy " + std::to_string(camera.cy) + ", depth_scale " +
                                std::to_string(camera.depth_scale));
  }
}

class TumReader final : public ScanSource {
 public:
  TumReader(const fs::path& association, const DepthCamera& camera) : camera_(camera) {
    check_camera(camera);
    InputFile file(association);
    association_name_ = association.filename().string();
    const fs::path folder = association.parent_path();
    LineReader lines(file, 0);
    std::string_view line;
    while (lines.next(line)) {
      Tokens tokens(line);
      const std::string_view first = tokens.next();
      if (first.empty() || first.front() == '#') continue;
      const std::string_view second = tokens.next();
      double values[7];
      std::size_t count = 0;
      bool numbers_ok = true;
      for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
        if (count < 7 && !(detail::parse_double(token, values[count]) && std::isfinite(values[count]))) {
          numbers_ok = false;
        }
        ++count;
      }
      if (second.empty() || count != 7 || !numbers_ok) {
        throw FormatError::at_line(file.name(), lines.line_number(),
                                   "expected 'rgb_path depth_path tx ty tz qx qy qz qw' (2 paths, 7 finite numbers), "
                                   "found " + quote(line));
      }
      Frame frame;
      frame.color = folder / fs::path(std::string(first));
      frame.depth = folder / fs::path(std::string(second));
      frame.depth_text = std::string(second);
      frame.stamp = stamp_of(frame.depth);
      frame.line = lines.line_number();
      try {
        // TUM order: tx ty tz qx qy qz qw.
        frame.pose = Pose::from_translation_quaternion(values[0], values[1], values[2], values[6], values[3], values[4],
                                                       values[5]);
      } catch (const std::invalid_argument& error) {
        throw FormatError::at_line(file.name(), lines.line_number(), std::string("bad pose: ") + error.what());
      }
      if (file_exists(frame.depth) && file_exists(frame.color)) {
        frames_.push_back(std::move(frame));
      } else {
        note_missing(frame, file.name());
      }
    }
    if (frames_.empty()) {
      throw FormatError(file.name(), missing_rows_ == 0
                                         ? "the association file lists no frames (rows 'rgb_path depth_path tx ty "
                                           "tz qx qy qz qw')"
                                         : "none of its " + std::to_string(missing_rows_) +
                                               " rows has both images on disk (" + first_missing_ + ")");
    }
  }

  [[nodiscard]] std::vector<std::string> warnings() const override {
    if (missing_rows_ == 0) return {};
    return {association_name_ + ": " + std::to_string(missing_rows_) + " of its " +
            std::to_string(missing_rows_ + frames_.size()) + " rows were skipped because their images are missing (" +
            first_missing_ + ")"};
  }

  [[nodiscard]] std::vector<Vec3f> origins() const override {
    std::vector<Vec3f> result;
    result.reserve(frames_.size());
    for (const Frame& frame : frames_) result.push_back(frame.pose.translation());
    return result;
  }

  bool next(Scan& scan) override {
    if (next_frame_ >= frames_.size()) return false;
    const Frame& frame = frames_[next_frame_];
    read_depth_png(frame.depth, depth_);
    Image color;
    try {
      color = read_png(frame.color);
    } catch (const std::runtime_error& error) {
      throw FormatError(frame.color.string(), std::string("cannot decode the color image: ") + error.what());
    }
    if (static_cast<std::uint32_t>(color.width) != depth_.width ||
        static_cast<std::uint32_t>(color.height) != depth_.height) {
      throw FormatError(frame.color.string(), "the color image is " + std::to_string(color.width) + " x " +
                                                   std::to_string(color.height) + " pixels but the depth image " +
                                                   frame.depth.string() + " is " + std::to_string(depth_.width) +
                                                   " x " + std::to_string(depth_.height));
    }
    scan.origin = frame.pose.translation();
    scan.stamp = frame.stamp;
    scan.name = association_name_ + " frame " + std::to_string(next_frame_ + 1) + " of " +
                std::to_string(frames_.size()) + " (line " + std::to_string(frame.line) + ", " + frame.depth_text + ")";
    // The image is kept with the scan (the projective integrator reads it),
    // and the points are made from it by the library's back_project, so
    // that inserting either gives the same points.
    ScanImage& image = scan.image ? *scan.image : scan.image.emplace();
    image.width = static_cast<int>(depth_.width);
    image.height = static_cast<int>(depth_.height);
    image.units_per_metre = camera_.depth_scale;
    image.camera = PinholeCamera{camera_.fx, camera_.fy, camera_.cx, camera_.cy};
    image.pose = frame.pose;
    const std::size_t pixels = std::size_t{depth_.width} * depth_.height;
    image.raw.resize(pixels);
    image.colors.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
      image.raw[i] = static_cast<std::uint16_t>(depth_.at(i));
      image.colors[i] = {color.rgb[3 * i], color.rgb[3 * i + 1], color.rgb[3 * i + 2]};
    }
    back_project(image.view(), image.camera, image.pose, scan.points, &pixels_);
    scan.colors.resize(pixels_.size());
    for (std::size_t i = 0; i < pixels_.size(); ++i) scan.colors[i] = image.colors[pixels_[i]];
    ++next_frame_;
    done_.store(next_frame_, std::memory_order_relaxed);
    return true;
  }

  [[nodiscard]] std::size_t scan_count() const override { return frames_.size(); }

  [[nodiscard]] double progress() const override {
    if (frames_.empty()) return 1.0;
    return static_cast<double>(done_.load(std::memory_order_relaxed)) / static_cast<double>(frames_.size());
  }

 private:
  /// Counts a row whose images are not both on disk; the first one is named in messages.
  void note_missing(const Frame& frame, const std::string& file) {
    if (missing_rows_++ > 0) return;
    const fs::path& missing = file_exists(frame.depth) ? frame.color : frame.depth;
    first_missing_ = "the first is line " + std::to_string(frame.line) + " of " + file + ": " + missing.string() +
                     " does not exist";
  }

  DepthCamera camera_;
  std::string association_name_;
  std::size_t missing_rows_ = 0;
  std::string first_missing_;
  std::vector<Frame> frames_;
  std::size_t next_frame_ = 0;
  std::atomic<std::size_t> done_{0};
  PngDepth depth_;
  std::vector<std::uint32_t> pixels_;  // pixel of each point of the current scan
};

}  // namespace

std::unique_ptr<ScanSource> open_tum_sequence(const fs::path& association_file, const DepthCamera& camera) {
  return detail::naming_bad_alloc(association_file,
                                     [&] { return std::make_unique<TumReader>(association_file, camera); });
}

fs::path find_tum_association(const fs::path& folder, const fs::path& association) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) {
    throw std::runtime_error("cannot open " + folder.string() + ": " +
                             (fs::exists(folder, error) ? std::string("not a folder") : "No such file or directory"));
  }
  if (!association.empty()) return association.is_absolute() ? association : folder / association;
  std::vector<fs::path> candidates;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string name = detail::to_lower(entry.path().filename().string());
    if (name.find("assoc") != std::string::npos && name.ends_with(".txt") && entry.is_regular_file()) {
      candidates.push_back(entry.path());
    }
  }
  if (candidates.size() == 1) return candidates.front();
  std::string message = "cannot open the TUM RGB-D sequence " + folder.string() + ": ";
  if (candidates.empty()) {
    message += "no association file (*assoc*.txt) in it";
  } else {
    std::sort(candidates.begin(), candidates.end());
    message += "several association files (";
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      message += (i == 0 ? "" : ", ") + candidates[i].filename().string();
    }
    message += ")";
  }
  throw std::runtime_error(message + "; name one with ScanSourceOptions::association, or open the file itself "
                                     "with the format \"tum\"");
}

}  // namespace umbra
