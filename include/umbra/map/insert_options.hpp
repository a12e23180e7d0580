// Moved to umbra/integrate/insert_options.hpp (the integrators own it); this header
// stays so that code written against earlier releases still compiles.
#pragma once

#include "umbra/integrate/insert_options.hpp"
