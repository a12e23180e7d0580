// Lets Debian 12's roscpp serialise messages in C++20.
//
// ros/serialization.h (roscpp_core 0.7.2) names ContainerAllocator::rebind<T>
// in its three vector serializers; C++20 removed std::allocator<T>::rebind,
// so those class templates cannot be instantiated for the std::vector<T>
// fields of every message. The three partial specialisations below, for
// exactly std::allocator<T>, are more specialised than roscpp's (same
// conditions, a fixed allocator) and so chosen instead. They keep the ROS 1
// wire format: a uint32 element count, then the elements (one memcpy for
// plain types). CMake adds this header in front of every translation unit of
// umbra's ROS code (-include), so it is seen before any message is used.
#pragma once

#include <ros/serialization.h>

#include <cstring>
#include <memory>
#include <vector>

namespace ros::serialization {

/// Writing and reading element by element: a count, then each element.
template <typename T>
struct ElementwiseVector {
  template <typename Stream>
  static void write(Stream& stream, const std::vector<T>& v) {
    stream.next(static_cast<uint32_t>(v.size()));
    for (const T& item : v) stream.next(item);
  }
  template <typename Stream>
  static void read(Stream& stream, std::vector<T>& v) {
    uint32_t count = 0;
    stream.next(count);
    v.resize(count);
    for (T& item : v) stream.next(item);
  }
};

/// Elements of variable size (strings, nested messages with arrays): one by one.
template <typename T>
struct VectorSerializer<T, std::allocator<T>, typename boost::disable_if<mt::IsFixedSize<T> >::type>
    : ElementwiseVector<T> {
  static uint32_t serializedLength(const std::vector<T>& v) {
    uint32_t bytes = 4;
    for (const T& item : v) bytes += serializationLength(item);
    return bytes;
  }
};

/// Plain types (numbers, fixed messages of plain fields): the bytes as they are.
template <typename T>
struct VectorSerializer<T, std::allocator<T>, typename boost::enable_if<mt::IsSimple<T> >::type> {
  template <typename Stream>
  static void write(Stream& stream, const std::vector<T>& v) {
    const auto count = static_cast<uint32_t>(v.size());
    stream.next(count);
    if (count > 0) std::memcpy(stream.advance(count * static_cast<uint32_t>(sizeof(T))), v.data(), count * sizeof(T));
  }
  template <typename Stream>
  static void read(Stream& stream, std::vector<T>& v) {
    uint32_t count = 0;
    stream.next(count);
    v.resize(count);
    if (count > 0) {
      std::memcpy(static_cast<void*>(v.data()), stream.advance(count * static_cast<uint32_t>(sizeof(T))),
                  count * sizeof(T));
    }
  }
  static uint32_t serializedLength(const std::vector<T>& v) { return 4 + static_cast<uint32_t>(v.size() * sizeof(T)); }
};

/// Fixed-size types that are not plain bytes (e.g. geometry_msgs/Point): one by one, all of one length.
template <typename T>
struct VectorSerializer<T, std::allocator<T>,
                        typename boost::enable_if<mpl::and_<mt::IsFixedSize<T>, mpl::not_<mt::IsSimple<T> > > >::type>
    : ElementwiseVector<T> {
  static uint32_t serializedLength(const std::vector<T>& v) {
    return 4 + (v.empty() ? 0 : static_cast<uint32_t>(v.size()) * serializationLength(v.front()));
  }
};

}  // namespace ros::serialization
