// numpy arrays in and out of the bindings: the argument checks every
// vectorised function shares, and zero-copy views where the layouts agree.
//
// Conventions (the same for every function of the module):
//  - points are arrays whose last axis has length 3; a function answering
//    per point returns an array of the leading shape (points (H, W, 3) give
//    answers (H, W); a single point (3,) gives a 0-d array);
//  - the arguments of a batch of shapes are (N, 3) rows or one (3,) row
//    broadcast to all N, and (N,) values or one scalar; N is their common
//    count and the answers are (N,);
//  - anything real is accepted and converted to float64 (float32 for the
//    points of a scan); a float64 C-contiguous array is read in place.
// Bad shapes raise ValueError naming the argument and the shape found;
// non-numeric input (complex numbers and strings included) raises
// TypeError; a conversion whose copy does not fit in memory raises
// MemoryError naming the argument.
//
// Cost: a view is free when the dtype and layout already match, else one
// copy of the array (an (N, 3) float64 copy of 1,000,000 points takes a
// few milliseconds); nothing here runs per element except that copy.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "umbra/core/color.hpp"
#include "umbra/core/pose.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/integrate/depth_image.hpp"

namespace umbra::python {

namespace py = pybind11;

// The zero-copy views below read numpy rows of three numbers as these types.
static_assert(sizeof(Vec3d) == 3 * sizeof(double) && std::is_standard_layout_v<Vec3d>);
static_assert(sizeof(Vec3f) == 3 * sizeof(float) && std::is_standard_layout_v<Vec3f>);
static_assert(sizeof(Rgb) == 3 && std::is_standard_layout_v<Rgb>);

/// Points: an array (..., 3) of float64, read in place when it already is one.
class PointArray {
 public:
  /// Throws ValueError unless the last axis has length 3.
  PointArray(py::handle object, const char* name);
  [[nodiscard]] std::size_t size() const { return count_; }
  [[nodiscard]] Vec3d operator[](std::size_t i) const {
    const double* p = data_ + 3 * i;
    return {p[0], p[1], p[2]};
  }
  /// The shape of one answer per point: the points' shape without its last axis.
  [[nodiscard]] const std::vector<py::ssize_t>& leading_shape() const { return leading_shape_; }

 private:
  py::array_t<double, py::array::c_style | py::array::forcecast> array_;
  const double* data_ = nullptr;
  std::size_t count_ = 0;
  std::vector<py::ssize_t> leading_shape_;
};

/// One argument of a batch: N rows of kWidth values, or one row for all.
/// kWidth 3: points ((N, 3) rows, or one (3,) row); kWidth 1: values ((N,)
/// values, or one scalar).
template <int kWidth>
class BatchArgument {
 public:
  static_assert(kWidth == 1 || kWidth == 3);
  /// Throws ValueError unless the shape is one of the two above.
  BatchArgument(py::handle object, const char* name);
  /// N, or nothing for a broadcast row (it fits any count).
  [[nodiscard]] std::optional<std::size_t> count() const {
    return broadcast_ ? std::nullopt : std::optional(count_);
  }
  [[nodiscard]] const char* name() const { return name_; }
  /// Row i: a Vec3d for kWidth 3, a double for kWidth 1.
  [[nodiscard]] auto operator[](std::size_t i) const {
    const double* p = data_ + (broadcast_ ? 0 : kWidth * i);
    if constexpr (kWidth == 3) {
      return Vec3d{p[0], p[1], p[2]};
    } else {
      return *p;
    }
  }

 private:
  py::array_t<double, py::array::c_style | py::array::forcecast> array_;
  const double* data_ = nullptr;
  std::size_t count_ = 0;
  bool broadcast_ = false;
  const char* name_;
};

extern template class BatchArgument<1>;  // defined in numpy_arrays.cpp
extern template class BatchArgument<3>;
using RowArray = BatchArgument<3>;
using ValueArray = BatchArgument<1>;

/// The count N the arguments of one batch agree on (1 when all broadcast).
/// Throws ValueError naming two arguments whose counts differ.
std::size_t batch_count(std::initializer_list<std::pair<const char*, std::optional<std::size_t>>> counts);

/// The points of a scan, (N, 3) float32 as the integrator reads them
/// (converted once when given as another dtype).
class ScanPoints {
 public:
  ScanPoints(py::handle object, const char* name);
  [[nodiscard]] std::span<const Vec3f> span() const { return {data_, count_}; }

 private:
  py::array_t<float, py::array::c_style | py::array::forcecast> array_;
  const Vec3f* data_ = nullptr;
  std::size_t count_ = 0;
};

/// Colors, (N, 3) of integers in [0, 255] (uint8 is read in place).
/// Throws ValueError for another shape or a value out of range (named as
/// the integer it is, whatever its dtype), TypeError for a non-integer dtype.
class ColorArray {
 public:
  ColorArray(py::handle object, const char* name);
  [[nodiscard]] std::span<const Rgb> span() const { return {data_, count_}; }

 private:
  py::array_t<std::uint8_t, py::array::c_style> array_;
  const Rgb* data_ = nullptr;
  std::size_t count_ = 0;
};

/// A depth image (H, W): uint16 raw depths, `units_per_metre` per metre, read
/// in place; or float metres (float32 read in place, other float dtypes
/// converted to float32 once). Throws TypeError for another dtype, ValueError
/// for another shape, for no pixels, and for a units_per_metre that is
/// missing (uint16), given (float) or not finite and > 0; `scale_name` is
/// how the caller's argument for it is called.
class DepthArray {
 public:
  DepthArray(py::handle object, const char* name, std::optional<double> units_per_metre, const char* scale_name);
  [[nodiscard]] DepthImage view() const;
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }

 private:
  py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast> raw_;
  py::array_t<float, py::array::c_style | py::array::forcecast> metres_;
  double units_per_metre_ = 0.0;
  int width_ = 0;
  int height_ = 0;
};

/// Pinhole intrinsics: a umbra.PinholeCamera, or four numbers (fx, fy, cx,
/// cy) (ValueError for another shape, or intrinsics the library refuses).
PinholeCamera camera_of(py::handle object, const char* name);

/// A rigid or affine transform: a (4, 4) array whose last row is (0, 0, 0,
/// 1), or a (3, 4) array [R | t] (ValueError otherwise).
Pose pose_of(py::handle object, const char* name);

/// Colors of an image, (H, W, 3) of integers in [0, 255] as ColorArray
/// reads them, one per pixel of an image of `height` x `width` (ValueError
/// for another shape).
ColorArray image_colors(py::handle object, const char* name, int height, int width);

/// A new (N,) bool array and its bytes (numpy's bool is one byte, 0 or 1).
struct BoolArray {
  py::array_t<bool> array;
  std::uint8_t* bytes;
  explicit BoolArray(std::size_t n);
};

/// A shape as numpy prints it: "(4, 2)".
std::string shape_text(const py::array& array);

/// One point: a sequence or array of three numbers (ValueError otherwise).
Vec3d vec3_of(py::handle object, const char* name);

/// A tuple of three floats.
py::tuple to_tuple(Vec3d v);

}  // namespace umbra::python
