#include "numpy_arrays.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace umbra::python {
namespace {

using Float64 = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string type_name(py::handle object) { return py::str(py::type::of(object).attr("__name__")); }

/// What `convert` (a numpy conversion) returns, its failure raised as an
/// error that names the argument: MemoryError when the copy did not fit
/// (numpy's message says how much it wanted), else TypeError with
/// `refusal`. The conversions run through pybind11's constructors, which
/// keep numpy's error (array_t::ensure would clear it).
template <typename Convert>
auto converted(const char* name, const std::string& refusal, const Convert& convert) -> decltype(convert()) {
  try {
    return convert();
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_MemoryError)) throw py::type_error(refusal);
    const std::string message =
        std::string(name) + ": not enough memory to convert it: " + std::string(py::str(e.value()));
    PyErr_SetString(PyExc_MemoryError, message.c_str());
    throw py::error_already_set();
  }
}

/// The object as a numpy array, converted only when it is not one already.
py::array any_array(py::handle object, const char* name, const std::string& refusal) {
  return converted(name, refusal, [&] { return py::array(py::reinterpret_borrow<py::object>(object)); });
}

/// The object as a C-contiguous array of T (a view when it already is one).
/// Numbers only: numpy would turn complex numbers into their real parts
/// (with a warning only) and strings into the numbers they spell.
template <typename Array>
Array as_array(py::handle object, const char* name) {
  const std::string refusal = std::string(name) + " must be an array of numbers, got " + type_name(object);
  const py::array any = any_array(object, name, refusal);
  const char kind = any.dtype().kind();
  if (kind == 'c') {
    throw py::type_error(std::string(name) + " must hold real numbers, got dtype " + std::string(py::str(any.dtype())));
  }
  if (kind != 'b' && kind != 'i' && kind != 'u' && kind != 'f' && kind != 'O') {
    throw py::type_error(std::string(name) + " must be an array of numbers, got dtype " +
                         std::string(py::str(any.dtype())));
  }
  return converted(name, refusal, [&] { return Array(any); });
}

/// Integer colors of any integer dtype as a new uint8 array, each checked
/// against [0, 255] as the integer it is (a uint64 above 2^63 is no
/// negative number).
template <typename Wide>
py::array_t<std::uint8_t, py::array::c_style> narrow_colors(const py::array& any, const char* name) {
  using WideArray = py::array_t<Wide, py::array::c_style | py::array::forcecast>;
  const WideArray wide = converted(name, std::string(name) + " must be an array of integers in [0, 255]",
                                   [&] { return WideArray(any); });
  py::array_t<std::uint8_t, py::array::c_style> narrow({wide.shape(0), py::ssize_t{3}});
  const Wide* in = wide.data();
  std::uint8_t* out = narrow.mutable_data();
  for (py::ssize_t i = 0; i < wide.size(); ++i) {
    bool negative = false;
    if constexpr (std::is_signed_v<Wide>) negative = in[i] < 0;
    if (negative || in[i] > 255) {
      throw py::value_error(std::string(name) + "[" + std::to_string(i / 3) + "] holds " + std::to_string(in[i]) +
                            ", outside [0, 255]");
    }
    out[i] = static_cast<std::uint8_t>(in[i]);
  }
  return narrow;
}

}  // namespace

std::string shape_text(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis) {
    if (axis > 0) text += ", ";
    text += std::to_string(array.shape(axis));
  }
  return text + (array.ndim() == 1 ? ",)" : ")");
}

Vec3d vec3_of(py::handle object, const char* name) {
  const auto array = as_array<Float64>(object, name);
  if (array.ndim() != 1 || array.shape(0) != 3) {
    throw py::value_error(std::string(name) + " must be three numbers (x, y, z), got shape " + shape_text(array));
  }
  return {array.at(0), array.at(1), array.at(2)};
}

py::tuple to_tuple(Vec3d v) { return py::make_tuple(v.x, v.y, v.z); }

PointArray::PointArray(py::handle object, const char* name) : array_(as_array<Float64>(object, name)) {
  if (array_.ndim() < 1 || array_.shape(array_.ndim() - 1) != 3) {
    throw py::value_error(std::string(name) + " must be an array of shape (..., 3), got shape " + shape_text(array_));
  }
  leading_shape_.assign(array_.shape(), array_.shape() + array_.ndim() - 1);
  count_ = static_cast<std::size_t>(array_.size() / 3);
  data_ = array_.data();
}

template <int kWidth>
BatchArgument<kWidth>::BatchArgument(py::handle object, const char* name)
    : array_(as_array<Float64>(object, name)), name_(name) {
  if constexpr (kWidth == 3) {
    const bool rows = array_.ndim() == 2 && array_.shape(1) == 3;
    broadcast_ = array_.ndim() == 1 && array_.shape(0) == 3;
    if (!rows && !broadcast_) {
      throw py::value_error(std::string(name) + " must be an array of shape (N, 3) or (3,), got shape " +
                            shape_text(array_));
    }
  } else {
    if (array_.ndim() > 1) {
      throw py::value_error(std::string(name) + " must be a number or an array of shape (N,), got shape " +
                            shape_text(array_));
    }
    broadcast_ = array_.ndim() == 0;
  }
  count_ = broadcast_ ? 1 : static_cast<std::size_t>(array_.shape(0));
  data_ = array_.data();
}

template class BatchArgument<1>;
template class BatchArgument<3>;

std::size_t batch_count(std::initializer_list<std::pair<const char*, std::optional<std::size_t>>> counts) {
  const char* first_name = nullptr;
  std::size_t first = 1;  // all broadcast: one
  for (const auto& [name, count] : counts) {
    if (!count) continue;  // broadcast
    if (first_name == nullptr) {
      first_name = name;
      first = *count;
    } else if (*count != first) {
      throw py::value_error(std::string(first_name) + " has " + std::to_string(first) + " rows but " + name +
                            " has " + std::to_string(*count));
    }
  }
  return first;
}

ScanPoints::ScanPoints(py::handle object, const char* name)
    : array_(as_array<py::array_t<float, py::array::c_style | py::array::forcecast>>(object, name)) {
  if (array_.ndim() != 2 || array_.shape(1) != 3) {
    throw py::value_error(std::string(name) + " must be an array of shape (N, 3), got shape " + shape_text(array_));
  }
  count_ = static_cast<std::size_t>(array_.shape(0));
  data_ = reinterpret_cast<const Vec3f*>(array_.data());
}

ColorArray::ColorArray(py::handle object, const char* name) {
  const py::array any = any_array(object, name, std::string(name) + " must be an array of integers in [0, 255]");
  const char kind = any.dtype().kind();
  if (kind != 'u' && kind != 'i') {
    throw py::type_error(std::string(name) + " must hold integers in [0, 255] (uint8), got dtype " +
                         std::string(py::str(any.dtype())));
  }
  if (any.ndim() != 2 || any.shape(1) != 3) {
    throw py::value_error(std::string(name) + " must be an array of shape (N, 3), got shape " + shape_text(any));
  }
  if (any.dtype().is(py::dtype::of<std::uint8_t>())) {
    using Bytes = py::array_t<std::uint8_t, py::array::c_style>;
    array_ = converted(name, std::string(name) + " must be an array of integers in [0, 255]",
                       [&] { return Bytes(any); });
  } else {
    array_ = kind == 'u' ? narrow_colors<std::uint64_t>(any, name) : narrow_colors<std::int64_t>(any, name);
  }
  count_ = static_cast<std::size_t>(array_.shape(0));
  data_ = reinterpret_cast<const Rgb*>(array_.data());
}

DepthArray::DepthArray(py::handle object, const char* name, std::optional<double> units_per_metre,
                       const char* scale_name) {
  const py::array any = any_array(object, name, std::string(name) + " must be an array of depths, got " + type_name(object));
  const char kind = any.dtype().kind();
  const bool raw = kind == 'u' && any.dtype().itemsize() == 2;  // uint16, in either byte order
  if (!raw && kind != 'f') {
    throw py::type_error(std::string(name) + " must hold uint16 raw depths (with " + scale_name +
                         ") or float metres, got dtype " + std::string(py::str(any.dtype())));
  }
  if (any.ndim() != 2) {
    throw py::value_error(std::string(name) + " must be an image of shape (H, W), got shape " + shape_text(any));
  }
  if (any.shape(0) == 0 || any.shape(1) == 0) {
    throw py::value_error(std::string(name) + " has no pixels: shape " + shape_text(any));
  }
  if (any.shape(0) > std::numeric_limits<int>::max() || any.shape(1) > std::numeric_limits<int>::max()) {
    throw py::value_error(std::string(name) + " is too large: shape " + shape_text(any));
  }
  height_ = static_cast<int>(any.shape(0));
  width_ = static_cast<int>(any.shape(1));
  if (raw) {
    if (!units_per_metre) {
      throw py::value_error(std::string(scale_name) + " is needed for uint16 " + name +
                            ": raw units per metre (1000 for millimetres, 5000 for TUM RGB-D)");
    }
    if (!(std::isfinite(*units_per_metre) && *units_per_metre > 0.0)) {
      throw py::value_error(std::string(scale_name) + " must be finite and > 0 (raw units per metre), got " +
                            std::to_string(*units_per_metre));
    }
    units_per_metre_ = *units_per_metre;
    raw_ = converted(name, std::string(name) + " must be an array of depths", [&] { return decltype(raw_)(any); });
  } else {
    if (units_per_metre) {
      throw py::value_error(std::string(scale_name) + " is for uint16 raw depths; " + name + " holds " +
                            std::string(py::str(any.dtype())) + " metres already");
    }
    metres_ = converted(name, std::string(name) + " must be an array of depths", [&] { return decltype(metres_)(any); });
  }
}

DepthImage DepthArray::view() const {
  const std::size_t pixels = std::size_t(width_) * std::size_t(height_);
  if (units_per_metre_ > 0.0) return DepthImage::raw({raw_.data(), pixels}, width_, height_, units_per_metre_);
  return DepthImage::metres({metres_.data(), pixels}, width_, height_);
}

PinholeCamera camera_of(py::handle object, const char* name) {
  PinholeCamera camera;
  if (py::isinstance<PinholeCamera>(object)) {
    camera = object.cast<PinholeCamera>();
  } else {
    const auto numbers = as_array<Float64>(object, name);
    if (numbers.ndim() != 1 || numbers.shape(0) != 4) {
      throw py::value_error(std::string(name) + " must be a PinholeCamera or four numbers (fx, fy, cx, cy), got shape " +
                            shape_text(numbers));
    }
    camera = PinholeCamera{numbers.at(0), numbers.at(1), numbers.at(2), numbers.at(3)};
  }
  try {
    camera.validate();
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string(name) + ": " + e.what());
  }
  return camera;
}

Pose pose_of(py::handle object, const char* name) {
  const auto array = as_array<Float64>(object, name);
  const bool square = array.ndim() == 2 && array.shape(0) == 4 && array.shape(1) == 4;
  if (!square && !(array.ndim() == 2 && array.shape(0) == 3 && array.shape(1) == 4)) {
    throw py::value_error(std::string(name) + " must be an array of shape (4, 4) or (3, 4), got shape " +
                          shape_text(array));
  }
  if (square && !(array.at(3, 0) == 0.0 && array.at(3, 1) == 0.0 && array.at(3, 2) == 0.0 && array.at(3, 3) == 1.0)) {
    throw py::value_error(std::string(name) + "'s last row must be (0, 0, 0, 1), got (" +
                          std::string(py::repr(py::float_(array.at(3, 0)))) + ", " +
                          std::string(py::repr(py::float_(array.at(3, 1)))) + ", " +
                          std::string(py::repr(py::float_(array.at(3, 2)))) + ", " +
                          std::string(py::repr(py::float_(array.at(3, 3)))) + ")");
  }
  Pose pose;
  for (py::ssize_t row = 0; row < 3; ++row) {
    for (py::ssize_t column = 0; column < 4; ++column) {
      pose.m[static_cast<std::size_t>(row)][static_cast<std::size_t>(column)] = array.at(row, column);
    }
  }
  return pose;
}

ColorArray image_colors(py::handle object, const char* name, int height, int width) {
  py::array any = any_array(object, name, std::string(name) + " must be an array of integers in [0, 255]");
  if (any.ndim() != 3 || any.shape(0) != height || any.shape(1) != width || any.shape(2) != 3) {
    throw py::value_error(std::string(name) + " must be an array of shape (" + std::to_string(height) + ", " +
                          std::to_string(width) + ", 3), one color per pixel, got shape " + shape_text(any));
  }
  return ColorArray(any.reshape({py::ssize_t(height) * width, py::ssize_t{3}}), name);
}

BoolArray::BoolArray(std::size_t n) : array(static_cast<py::ssize_t>(n)) {
  bytes = reinterpret_cast<std::uint8_t*>(array.mutable_data());
}

}  // namespace umbra::python
