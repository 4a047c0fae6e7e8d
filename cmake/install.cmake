# `cmake --install`: the library, its public headers and an exported CMake package, so that
# another project finds it with find_package(sphfem) and links sphfem::sphfem; the CLI; and the
# Python module where it is built (python/CMakeLists.txt).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(SPHFEM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/sphfem)
install(TARGETS sphfem EXPORT sphfemTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/sphfem DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS sphfem_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT sphfemTargets NAMESPACE sphfem:: DESTINATION ${SPHFEM_CMAKE_DIR})

# The static library's own dependencies, which a program linking it must find again.
set(SPHFEM_CONFIG_CUDA ${SPHFEM_ENABLE_CUDA})
set(SPHFEM_CONFIG_GL ${SPHFEM_ENABLE_GL})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/sphfemConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/sphfemConfig.cmake
                              INSTALL_DESTINATION ${SPHFEM_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/sphfemConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/sphfemConfig.cmake
              ${PROJECT_BINARY_DIR}/sphfemConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindTetGen.cmake
        DESTINATION ${SPHFEM_CMAKE_DIR})
