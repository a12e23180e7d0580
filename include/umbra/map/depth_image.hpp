// Moved to umbra/integrate/depth_image.hpp (the integrators own it); this header
// stays so that code written against earlier releases still compiles.
#pragma once

#include "umbra/integrate/depth_image.hpp"
