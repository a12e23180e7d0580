# Private build settings for umbra's own targets; never exported to users.
add_library(umbra_build_settings INTERFACE)
target_compile_options(umbra_build_settings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
  # GCC 12 warns falsely about std::string concatenation (GCC bug 105329).
  $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>
  # The ray walker must round exactly as OctoMap does: no fused multiply-add.
  -ffp-contract=off
  # GCC 12.2 (Debian 12) miscompiles a float stored by SLP-vectorised code and
  # read back as double: it forwards the original double, skipping the
  # rounding to float (found as ray casts entering voxels 1e-7 m off OctoMap's;
  # reproducer and note in docs/design.md, "Compiler"). Rounding to float
  # exactly as OctoMap does is the point of the walkers, so SLP is off.
  $<$<CXX_COMPILER_ID:GNU>:-fno-tree-slp-vectorize>)
if(UMBRA_ENABLE_ASSERTS)
  target_compile_definitions(umbra_build_settings INTERFACE UMBRA_ENABLE_ASSERTS)
endif()
if(UMBRA_SANITIZE)
  target_compile_options(umbra_build_settings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer)
  target_link_options(umbra_build_settings INTERFACE -fsanitize=address,undefined)
endif()
if(UMBRA_SANITIZE_THREAD)
  target_compile_options(umbra_build_settings INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_link_options(umbra_build_settings INTERFACE -fsanitize=thread)
endif()
