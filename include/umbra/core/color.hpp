// Rgb: an 8-bit color, as point clouds and colored maps carry it.
#pragma once

#include <cstdint>

namespace umbra {

struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  friend constexpr bool operator==(Rgb, Rgb) = default;
};

}  // namespace umbra
