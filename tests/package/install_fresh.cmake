# cmake -DBUILD_DIR=<build tree> -DPREFIX=<dir> -P install_fresh.cmake
# Removes PREFIX, then installs the library package (component ident_development) into it.
if(NOT BUILD_DIR OR NOT PREFIX)
  message(FATAL_ERROR "usage: cmake -DBUILD_DIR=<build> -DPREFIX=<dir> -P install_fresh.cmake")
endif()
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}"
                        --component ident_development
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${result})")
endif()
foreach(f include/ident/ident/regression/rls.h include/ident/common/error.h include/ident/models/arx.h
          lib/cmake/Ident/IdentConfig.cmake lib/cmake/Ident/IdentConfigVersion.cmake)
  if(NOT EXISTS "${PREFIX}/${f}")
    message(FATAL_ERROR "install is missing ${f}")
  endif()
endforeach()
