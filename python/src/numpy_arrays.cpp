#include "numpy_arrays.hpp"

#include <algorithm>
#include <utility>

namespace umbra::python {
namespace {

using Float64 = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// The object as a C-contiguous array of T (a view when it already is one).
template <typename Array>
Array as_array(py::handle object, const char* name) {
  Array array = Array::ensure(object);
  if (!array) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + " must be an array of numbers, got " +
                         std::string(py::str(py::type::of(object).attr("__name__"))));
  }
  return array;
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
  py::array any = py::array::ensure(object);
  if (!any) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + " must be an array of integers in [0, 255]");
  }
  const char kind = any.dtype().kind();
  if (kind != 'u' && kind != 'i') {
    throw py::type_error(std::string(name) + " must hold integers in [0, 255] (uint8), got dtype " +
                         std::string(py::str(any.dtype())));
  }
  if (any.ndim() != 2 || any.shape(1) != 3) {
    throw py::value_error(std::string(name) + " must be an array of shape (N, 3), got shape " + shape_text(any));
  }
  if (any.dtype().is(py::dtype::of<std::uint8_t>())) {
    array_ = py::array_t<std::uint8_t, py::array::c_style>::ensure(any);
  } else {
    const auto wide = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(any);
    array_ = py::array_t<std::uint8_t, py::array::c_style>({wide.shape(0), py::ssize_t{3}});
    const std::int64_t* in = wide.data();
    std::uint8_t* out = array_.mutable_data();
    for (py::ssize_t i = 0; i < wide.size(); ++i) {
      if (in[i] < 0 || in[i] > 255) {
        throw py::value_error(std::string(name) + "[" + std::to_string(i / 3) + "] holds " + std::to_string(in[i]) +
                              ", outside [0, 255]");
      }
      out[i] = static_cast<std::uint8_t>(in[i]);
    }
  }
  count_ = static_cast<std::size_t>(array_.shape(0));
  data_ = reinterpret_cast<const Rgb*>(array_.data());
}

BoolArray::BoolArray(std::size_t n) : array(static_cast<py::ssize_t>(n)) {
  bytes = reinterpret_cast<std::uint8_t*>(array.mutable_data());
}

}  // namespace umbra::python
