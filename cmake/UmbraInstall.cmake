# Installation: headers, libraries, the CMake package (find_package(umbra
# CONFIG) -> umbra::umbra, umbra::core, umbra::io) and a pkg-config file.
include(CMakePackageConfigHelpers)

install(TARGETS umbra_core umbra_io umbra
  EXPORT umbraTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/umbra DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT umbraTargets NAMESPACE umbra:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/umbraConfig.cmake.in
  ${PROJECT_BINARY_DIR}/umbraConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/umbraConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/umbraConfig.cmake ${PROJECT_BINARY_DIR}/umbraConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/umbra)

file(RELATIVE_PATH UMBRA_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
configure_file(${PROJECT_SOURCE_DIR}/cmake/umbra.pc.in ${PROJECT_BINARY_DIR}/umbra.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/umbra.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
