#include "umbra/io/png_writer.hpp"

#include "umbra/io/file_saving.hpp"
#include "core/memory_budget.hpp"

#include <png.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace umbra {

namespace {

// Largest picture read_png accepts (pixels), so that a corrupt header cannot
// make it allocate gigabytes: 2^28 pixels = 768 MiB of RGB.
constexpr std::uint64_t kMaxReadPixels = std::uint64_t{1} << 28;

std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

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

void Image::set(int column, int row, Rgb color) {
  if (column < 0 || column >= width || row < 0 || row >= height) {
    throw std::out_of_range("Image::set: pixel (" + std::to_string(column) + ", " +
                            std::to_string(row) + ") is outside the " + std::to_string(width) +
                            " x " + std::to_string(height) + " picture");
  }
  const std::size_t i = (std::size_t(row) * std::size_t(width) + std::size_t(column)) * 3;
  rgb[i] = color.r;
  rgb[i + 1] = color.g;
  rgb[i + 2] = color.b;
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

  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  // Encoded in memory (a top-down picture is a few hundred KiB at most), then
  // written like every other umbra file: temporary file, fsync, rename. The
  // simplified API keeps libpng's setjmp/longjmp inside libpng and reports
  // failure through its return value and png.message.
  png_alloc_size_t size = 0;
  std::vector<std::uint8_t> bytes;
  bool encoded = png_image_write_get_memory_size(png, size, 0, image.rgb.data(), 0, nullptr) != 0;
  if (encoded) {
    bytes.resize(size);
    encoded = png_image_write_to_memory(&png, bytes.data(), &size, 0, image.rgb.data(), 0, nullptr) != 0;
    bytes.resize(size);
  }
  const std::string reason = png.message;
  png_image_free(&png);
  if (!encoded) throw std::runtime_error("write_png: cannot encode " + quoted(path) + ": libpng: " + reason);
  write_file_atomically(path, {bytes}, "picture");
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
  try {
    detail::require_memory(path.string(), "decoding this picture (" + std::to_string(png.width) + " x " +
                                              std::to_string(png.height) + " pixels, 3 bytes each)",
                           pixels * 3);
  } catch (...) {
    png_image_free(&png);
    throw;
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
