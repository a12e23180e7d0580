# What every install rule and installed target of umbra shares; included from
# the top-level CMakeLists.txt before any target or install rule is made,
# because targets copy CMAKE_INSTALL_RPATH when they are created and install
# rules take the default component when they are written.

# Installed programs find umbra's own shared libraries relative to where they
# lie ($ORIGIN/../lib from bin/), so `P/bin/umbra` runs from any prefix P
# without LD_LIBRARY_PATH or ldconfig, and an installed tree still works when
# moved (a .deb's contents, a tarball). The system's libraries (zstd, png,
# ROS) are found through ld.so's own paths as usual. The libraries set
# $ORIGIN (cmake/UmbraInstall.cmake), the Python module its own path
# (python/CMakeLists.txt).
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(CMAKE_INSTALL_RPATH "${CMAKE_INSTALL_LIBDIR}")
else()
  file(RELATIVE_PATH umbra_bin_to_lib "/prefix/${CMAKE_INSTALL_BINDIR}" "/prefix/${CMAKE_INSTALL_LIBDIR}")
  set(CMAKE_INSTALL_RPATH "$ORIGIN/${umbra_bin_to_lib}")
endif()

# The Debian packages (cmake/UmbraDebianPackages.cmake) are made of install
# components: runtime (libumbra), development (libumbra-dev), tools (umbra)
# and python (python3-umbra). The libraries and the Python module name
# theirs; every program's rule (tools/, ros/) names none and lands in tools.
set(CMAKE_INSTALL_DEFAULT_COMPONENT_NAME tools)
