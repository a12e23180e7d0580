# Installation: headers, libraries, the CMake package (find_package(umbra
# CONFIG) -> umbra::umbra, umbra::core, umbra::io) and a pkg-config file, in
# the install components runtime (the shared libraries) and development
# (everything a C++ user compiles against); cmake/UmbraInstallDefaults.cmake
# says how programs and the Python module are installed.
include(CMakePackageConfigHelpers)

install(TARGETS umbra_core umbra_io umbra
  EXPORT umbraTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT development
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# libumbra_io needs libumbra_core, which lies beside it.
set_target_properties(umbra_core umbra_io PROPERTIES INSTALL_RPATH "$ORIGIN")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/umbra DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development)
install(EXPORT umbraTargets NAMESPACE umbra:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra COMPONENT development)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/umbraConfig.cmake.in
  ${PROJECT_BINARY_DIR}/umbraConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/umbraConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/umbraConfig.cmake ${PROJECT_BINARY_DIR}/umbraConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra COMPONENT development)

file(RELATIVE_PATH UMBRA_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
configure_file(${PROJECT_SOURCE_DIR}/cmake/umbra.pc.in ${PROJECT_BINARY_DIR}/umbra.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/umbra.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT development)

include(${PROJECT_SOURCE_DIR}/cmake/UmbraDebianPackages.cmake)
