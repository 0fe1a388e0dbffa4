# Helpers shared by the layer CMakeLists files.

# Warnings for our own targets (not for consumers).
function(ident_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic
                                           $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
endfunction()

# ident_add_layer(<target> <alias> <dir> [SOURCES ...] [EXCLUDE ...] DEPS ...): a static library made of
# every .cc file in <dir> (recursively; files added later are picked up at build time) except those named
# in EXCLUDE, or of exactly the files named in SOURCES; include root = the repository root.
function(ident_add_layer target alias dir)
  cmake_parse_arguments(ARG "" "" "DEPS;SOURCES;EXCLUDE" ${ARGN})
  if(ARG_SOURCES)
    list(TRANSFORM ARG_SOURCES PREPEND "${dir}/" OUTPUT_VARIABLE sources)
  else()
    file(GLOB_RECURSE sources CONFIGURE_DEPENDS "${dir}/*.cc")
    list(TRANSFORM ARG_EXCLUDE PREPEND "${dir}/")
    list(REMOVE_ITEM sources ${ARG_EXCLUDE})
  endif()
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
                                                $<INSTALL_INTERFACE:include/ident>)
    target_link_libraries(${target} PUBLIC ${ARG_DEPS})
    target_compile_features(${target} PUBLIC cxx_std_20)
    ident_set_warnings(${target})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
                                                   $<INSTALL_INTERFACE:include/ident>)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
    target_compile_features(${target} INTERFACE cxx_std_20)
  endif()
  add_library(${alias} ALIAS ${target})
  # Installed/exported as the alias name: ident_core -> Ident::ident (see cmake/IdentInstall.cmake).
  string(REPLACE "Ident::" "" export_name "${alias}")
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
endfunction()
