# Install rules: `cmake --install <build> [--prefix <dir>]` puts in place
#   include/ident/{common,models,approx,ident}/**.h  the public headers, paths preserved (consumers write
#                                               #include "ident/regression/rls.h" as inside the tree)
#   lib/libident_{models,approx,linalg,regression,observers,registry,smoothing,density,control,io}.a  the libraries
#   lib/cmake/Ident/IdentConfig.cmake, IdentConfigVersion.cmake, IdentTargets*.cmake
# Consumers: find_package(Ident 0.1 REQUIRED) and link Ident::ident (all of them) or one folder's target
# (Ident::regression, Ident::observers, Ident::smoothing, ...). Everything here is in the COMPONENT `ident_development`, so
# `cmake --install <build> --component ident_development` installs only the library package.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(IDENT_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/Ident")

set(ident_installed_targets ident_common ident_models ident_approx ident_linalg ident_regression ident_observers
                            ident_registry ident_smoothing ident_density ident_control ident_io ident_workflow ident_core)
install(TARGETS ${ident_installed_targets}
        EXPORT IdentTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT ident_development
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT ident_development
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ident)
foreach(layer common models approx ident)
  install(DIRECTORY "${PROJECT_SOURCE_DIR}/${layer}/"
          DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/ident/${layer}"
          COMPONENT ident_development
          FILES_MATCHING PATTERN "*.h")
endforeach()
install(EXPORT IdentTargets
        NAMESPACE Ident::
        DESTINATION ${IDENT_INSTALL_CMAKEDIR}
        COMPONENT ident_development)

configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/IdentConfig.cmake.in"
                              "${PROJECT_BINARY_DIR}/IdentConfig.cmake"
                              INSTALL_DESTINATION ${IDENT_INSTALL_CMAKEDIR})
write_basic_package_version_file("${PROJECT_BINARY_DIR}/IdentConfigVersion.cmake"
                                 VERSION ${PROJECT_VERSION}
                                 COMPATIBILITY SameMajorVersion)
install(FILES "${PROJECT_BINARY_DIR}/IdentConfig.cmake" "${PROJECT_BINARY_DIR}/IdentConfigVersion.cmake"
        DESTINATION ${IDENT_INSTALL_CMAKEDIR}
        COMPONENT ident_development)

# A Debian package of everything installed (`cpack --config <build>/CPackConfig.cmake`): the way to put
# the program, the library and the Python package on the workers of a Dask cluster. Under /usr/local,
# where Debian's python3 finds the package (lib/python3.X/dist-packages).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ident)
set(CPACK_PACKAGE_CONTACT "ident maintainers")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "recursive, outlier-robust system identification (C++, CLI, Python)")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr/local)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libeigen3-dev, libboost-dev, libfmt-dev, nlohmann-json3-dev, python3, python3-numpy, python3-pandas, python3-matplotlib")
include(CPack)
