#include "umbra/io/png_writer.hpp"

#include <fcntl.h>
#include <png.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

namespace umbra {

namespace {

// Largest picture read_png accepts (pixels), so that a corrupt header cannot
// make it allocate gigabytes: 2^28 pixels = 768 MiB of RGB.
constexpr std::uint64_t kMaxReadPixels = std::uint64_t{1} << 28;

std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

std::string errno_text(int error) {
  return std::error_code(error, std::generic_category()).message();
}

/// Removes the temporary file unless the write was committed.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path path) : path_(std::move(path)) {}
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (!committed_) {
      std::error_code ignored;
      std::filesystem::remove(path_, ignored);
    }
  }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  void commit() { committed_ = true; }

 private:
  std::filesystem::path path_;
  bool committed_ = false;
};

/// Closes the stream if still open (on error paths).
class StreamCloser {
 public:
  explicit StreamCloser(std::FILE* stream) : stream_(stream) {}
  StreamCloser(const StreamCloser&) = delete;
  StreamCloser& operator=(const StreamCloser&) = delete;
  ~StreamCloser() {
    if (stream_ != nullptr) std::fclose(stream_);
  }
  /// Closes now; returns 0 or the errno of the failure.
  int close() {
    std::FILE* stream = stream_;
    stream_ = nullptr;
    errno = 0;
    return std::fclose(stream) == 0 ? 0 : (errno != 0 ? errno : EIO);
  }

 private:
  std::FILE* stream_;
};

/// Creates a new, uniquely named file next to `target` (never opening an
/// existing one); returns its descriptor and sets `temporary`.
int create_temporary(const std::filesystem::path& target, std::filesystem::path& temporary) {
  static std::atomic<std::uint64_t> counter{0};
  std::random_device entropy;
  const std::filesystem::path folder =
      target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  int error = 0;
  for (int attempt = 0; attempt < 16; ++attempt) {
    std::ostringstream name;
    name << '.' << target.filename().string() << ".tmp-" << ::getpid() << '-' << counter++ << '-'
         << std::hex << entropy();
    temporary = folder / name.str();
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) return fd;
    error = errno;
    if (error != EEXIST) break;
  }
  throw std::runtime_error("write_png: cannot create a temporary file in " + quoted(folder) +
                           " to write " + quoted(target) + ": " + errno_text(error));
}

}  // namespace

Image::Image(int width_pixels, int height_pixels, Rgb fill)
    : width(width_pixels), height(height_pixels) {
  if (width_pixels <= 0 || height_pixels <= 0) {
    throw std::invalid_argument("Image: width and height must be > 0, got " +
                                std::to_string(width_pixels) + " x " +
                                std::to_string(height_pixels));
  }
  const std::size_t pixels = std::size_t(width_pixels) * std::size_t(height_pixels);
  rgb.resize(pixels * 3);
  for (std::size_t i = 0; i < pixels; ++i) {
    rgb[3 * i] = fill.r;
    rgb[3 * i + 1] = fill.g;
    rgb[3 * i + 2] = fill.b;
  }
}

Rgb Image::at(int column, int row) const {
  if (column < 0 || column >= width || row < 0 || row >= height) {
    throw std::out_of_range("Image::at: pixel (" + std::to_string(column) + ", " +
                            std::to_string(row) + ") is outside the " + std::to_string(width) +
                            " x " + std::to_string(height) + " picture");
  }
  const std::size_t i = (std::size_t(row) * std::size_t(width) + std::size_t(column)) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void Image::set(int column, int row, Rgb colour) {
  if (column < 0 || column >= width || row < 0 || row >= height) {
    throw std::out_of_range("Image::set: pixel (" + std::to_string(column) + ", " +
                            std::to_string(row) + ") is outside the " + std::to_string(width) +
                            " x " + std::to_string(height) + " picture");
  }
  const std::size_t i = (std::size_t(row) * std::size_t(width) + std::size_t(column)) * 3;
  rgb[i] = colour.r;
  rgb[i + 1] = colour.g;
  rgb[i + 2] = colour.b;
}

void Image::validate() const {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("Image: width and height must be > 0, got " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  const std::size_t expected = std::size_t(width) * std::size_t(height) * 3;
  if (rgb.size() != expected) {
    throw std::invalid_argument("Image: rgb holds " + std::to_string(rgb.size()) +
                                " bytes, but a " + std::to_string(width) + " x " +
                                std::to_string(height) + " picture needs " +
                                std::to_string(expected));
  }
}

void write_png(const Image& image, const std::filesystem::path& path) {
  image.validate();
  if (std::int64_t(image.width) * 3 > std::numeric_limits<png_int_32>::max()) {
    throw std::invalid_argument("write_png: a row of " + std::to_string(image.width) +
                                " pixels is too wide for libpng");
  }
  if (path.filename().empty()) {
    throw std::runtime_error("write_png: " + quoted(path) + " does not name a file");
  }

  std::filesystem::path temporary_path;
  const int fd = create_temporary(path, temporary_path);
  TemporaryFile temporary(temporary_path);
  std::FILE* stream = ::fdopen(fd, "wb");
  if (stream == nullptr) {
    const int error = errno;
    ::close(fd);
    throw std::runtime_error("write_png: cannot open a stream on " + quoted(temporary.path()) +
                             " to write " + quoted(path) + ": " + errno_text(error));
  }
  StreamCloser closer(stream);

  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  // The simplified API keeps libpng's setjmp/longjmp inside libpng and
  // reports failure through its return value and png.message.
  errno = 0;
  const int written = png_image_write_to_stdio(&png, stream, 0, image.rgb.data(), 0, nullptr);
  if (written == 0) {
    const int error = errno;  // set when the failure came from the file system
    std::string reason = std::string("libpng: ") + png.message;
    if (error != 0) reason += " (" + errno_text(error) + ")";
    png_image_free(&png);
    throw std::runtime_error("write_png: cannot write " + quoted(path) + ": " + reason);
  }
  png_image_free(&png);

  // Flush and sync before the rename, so a crash cannot leave an empty file
  // under the real name.
  if (std::fflush(stream) != 0 || ::fsync(::fileno(stream)) != 0) {
    throw std::runtime_error("write_png: cannot write " + quoted(path) + ": " + errno_text(errno));
  }
  if (const int error = closer.close(); error != 0) {
    throw std::runtime_error("write_png: cannot write " + quoted(path) + ": " + errno_text(error));
  }
  std::error_code rename_error;
  std::filesystem::rename(temporary.path(), path, rename_error);
  if (rename_error) {
    throw std::runtime_error("write_png: cannot move the finished picture to " + quoted(path) +
                             ": " + rename_error.message());
  }
  temporary.commit();
}

Image read_png(const std::filesystem::path& path) {
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    const std::string reason = png.message;
    png_image_free(&png);
    throw std::runtime_error("read_png: cannot read " + quoted(path) + ": " + reason);
  }
  const std::uint64_t pixels = std::uint64_t(png.width) * png.height;
  if (png.width == 0 || png.height == 0 ||
      png.width > std::uint32_t(std::numeric_limits<int>::max() / 3) ||
      png.height > std::uint32_t(std::numeric_limits<int>::max()) || pixels > kMaxReadPixels) {
    const std::string size = std::to_string(png.width) + " x " + std::to_string(png.height);
    png_image_free(&png);
    throw std::runtime_error("read_png: " + quoted(path) + " is " + size +
                             " pixels, more than read_png accepts (" +
                             std::to_string(kMaxReadPixels) + " pixels)");
  }
  png.format = PNG_FORMAT_RGB;
  Image image(static_cast<int>(png.width),
              static_cast<int>(png.height));  // black: alpha background
  if (png_image_finish_read(&png, nullptr, image.rgb.data(), 0, nullptr) == 0) {
    const std::string reason = png.message;
    png_image_free(&png);
    throw std::runtime_error("read_png: cannot read " + quoted(path) + ": " + reason);
  }
  png_image_free(&png);
  return image;
}

}  // namespace umbra
