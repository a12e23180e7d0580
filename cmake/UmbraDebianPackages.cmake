# Debian packages from CPack, one per install component:
#   libumbra       the shared libraries (runtime)
#   libumbra-dev   headers, the CMake package, umbra.pc (development)
#   umbra          the `umbra` program and, with ROS, umbra_server (tools)
#   python3-umbra  the Python module for the python3 it was built for (python)
# Made with `cpack -G DEB` in a build folder (README, "Debian packages");
# installed with `apt install ./*.deb`. They install under /usr with the
# folders this build was configured with (lib, or lib/<multiarch> when
# configured with CMAKE_INSTALL_PREFIX=/usr): both are on ld.so's and
# pkg-config's default paths. tests/install/run_deb_test.sh checks them.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_NAME umbra)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "umbra developers <umbra@localhost>")
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Dependencies on Debian's libraries from what the binaries link
# (dpkg-shlibdeps). No shlibs file: CPack 3.25 would write one for every
# package and warns for the Python module, which has no soname.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# dpkg-shlibdeps runs in each package's staging folder; umbra's own
# libraries, which the program and the module need, are in libumbra's,
# beside it. (That they come from libumbra is said by the component
# dependencies below, with the exact version.)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS "../runtime${CPACK_PACKAGING_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}")
set(CPACK_DEBIAN_PACKAGE_SECTION science)

# The packages depend on each other as the components do (CPACK_COMPONENT_*_DEPENDS),
# with the exact version: libumbra (= 0.1.0).
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(CPACK_COMPONENTS_ALL runtime development tools)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME libumbra)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION libs)
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION "umbra: probabilistic 3D occupancy maps (shared libraries)")

set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_NAME libumbra-dev)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_SECTION libdevel)
set(CPACK_COMPONENT_DEVELOPMENT_DEPENDS runtime)
# umbra.pc (Requires.private) and umbraConfig.cmake (find_dependency) name
# these; a consumer's pkg-config or find_package fails without them.
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_DEPENDS "libzstd-dev, libbz2-dev, libpng-dev, zlib1g-dev, liblzf-dev")
set(CPACK_COMPONENT_DEVELOPMENT_DESCRIPTION "umbra: headers, CMake package and pkg-config file (C++20)")

set(CPACK_DEBIAN_TOOLS_PACKAGE_NAME umbra)
set(CPACK_COMPONENT_TOOLS_DEPENDS runtime)
set(CPACK_COMPONENT_TOOLS_DESCRIPTION "umbra: the umbra command-line program (build, info, convert, query, render, view)")

if(TARGET umbra_python)
  list(APPEND CPACK_COMPONENTS_ALL python)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-umbra)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
  set(CPACK_COMPONENT_PYTHON_DEPENDS runtime)
  # The compiled module is for one Python version (its file name says so).
  math(EXPR umbra_next_python_minor "${UMBRA_PYTHON_VERSION_MINOR} + 1")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
      "python3 (>= ${UMBRA_PYTHON_VERSION_MAJOR}.${UMBRA_PYTHON_VERSION_MINOR}), python3 (<< ${UMBRA_PYTHON_VERSION_MAJOR}.${umbra_next_python_minor}), python3-numpy")
  set(CPACK_COMPONENT_PYTHON_DESCRIPTION "umbra: the Python module umbra (numpy in and out)")
endif()

include(CPack)
