# CMake package of Yggdrasil's C API: `find_package(yggdrasil CONFIG)` (point
# `yggdrasil_DIR` or `CMAKE_PREFIX_PATH` at this folder) or `add_subdirectory(capi)`.
#
# Defines the imported targets
#   yggdrasil::yggdrasil  libyggdrasil.so, with yggdrasil.h and yggdrasil.hpp (C++17)
#   yggdrasil::static     libyggdrasil.a and the system libraries it needs
#
# From a source tree (this file in <repo>/capi/cmake), CMake builds the library: the
# target yggdrasil_cargo runs `cargo build -p ygg-capi` (incremental, so a no-op when
# nothing changed) before anything that links these targets; cargo must be on PATH.
# From an installed package (`cmake --install` of capi/: <prefix>/lib/cmake/yggdrasil),
# the installed library is used as it is.
#
# Cache variables (source tree):
#   YGGDRASIL_PROFILE           cargo profile to build and link: release (default) or debug
#   YGGDRASIL_CARGO_TARGET_DIR  cargo's target directory (default: $CARGO_TARGET_DIR,
#                               else the workspace's target/)
#   YGGDRASIL_BUILD_WITH_CARGO  ON (default): CMake runs cargo; OFF: link a library
#                               cargo built before (`cargo build [--release] -p ygg-capi`)
#   YGGDRASIL_CARGO             the cargo executable (default: found on PATH)
if(TARGET yggdrasil::yggdrasil)
  return()
endif()
find_package(Threads REQUIRED)

get_filename_component(_ygg_here "${CMAKE_CURRENT_LIST_DIR}" ABSOLUTE)
get_filename_component(_ygg_capi_dir "${_ygg_here}/.." ABSOLUTE)
get_filename_component(_ygg_workspace "${_ygg_capi_dir}/.." ABSOLUTE)

if(EXISTS "${_ygg_workspace}/Cargo.toml" AND EXISTS "${_ygg_capi_dir}/Cargo.toml")
  # ---- a source tree: cargo builds the library ----
  set(_ygg_include "${_ygg_capi_dir}/include")
  if(DEFINED ENV{CARGO_TARGET_DIR})
    set(_ygg_default_target "$ENV{CARGO_TARGET_DIR}")
  else()
    set(_ygg_default_target "${_ygg_workspace}/target")
  endif()
  set(YGGDRASIL_CARGO_TARGET_DIR "${_ygg_default_target}" CACHE PATH "cargo target directory holding libyggdrasil")
  set(YGGDRASIL_PROFILE "release" CACHE STRING "cargo profile of libyggdrasil to build and link (release or debug)")
  set_property(CACHE YGGDRASIL_PROFILE PROPERTY STRINGS release debug)
  option(YGGDRASIL_BUILD_WITH_CARGO "build libyggdrasil with cargo as part of the CMake build" ON)
  set(_ygg_lib_dir "${YGGDRASIL_CARGO_TARGET_DIR}/${YGGDRASIL_PROFILE}")
  if(YGGDRASIL_PROFILE STREQUAL "release")
    set(_ygg_profile_flag "--release")
  elseif(YGGDRASIL_PROFILE STREQUAL "debug")
    set(_ygg_profile_flag "")
  else()
    message(FATAL_ERROR "yggdrasil: YGGDRASIL_PROFILE is ${YGGDRASIL_PROFILE}; expected release or debug")
  endif()
  if(YGGDRASIL_BUILD_WITH_CARGO)
    find_program(YGGDRASIL_CARGO cargo HINTS "$ENV{CARGO_HOME}/bin" "$ENV{HOME}/.cargo/bin")
    if(NOT YGGDRASIL_CARGO)
      message(FATAL_ERROR "yggdrasil: cargo not found (install Rust, or set YGGDRASIL_CARGO)")
    endif()
    if(NOT TARGET yggdrasil_cargo)
      # Always run: cargo knows whether anything changed (the Rust sources are not
      # listed to CMake). The libraries are byproducts, so Ninja and Make order the link
      # steps after it.
      add_custom_target(yggdrasil_cargo
        COMMAND "${YGGDRASIL_CARGO}" build ${_ygg_profile_flag} -p ygg-capi
                --target-dir "${YGGDRASIL_CARGO_TARGET_DIR}"
        WORKING_DIRECTORY "${_ygg_workspace}"
        BYPRODUCTS "${_ygg_lib_dir}/libyggdrasil.so" "${_ygg_lib_dir}/libyggdrasil.a"
        COMMENT "cargo build ${_ygg_profile_flag} -p ygg-capi (libyggdrasil)"
        USES_TERMINAL
        VERBATIM)
    endif()
  elseif(NOT EXISTS "${_ygg_lib_dir}/libyggdrasil.so")
    set(yggdrasil_FOUND FALSE)
    set(yggdrasil_NOT_FOUND_MESSAGE
        "yggdrasil: ${_ygg_lib_dir}/libyggdrasil.so does not exist; run `cargo build ${_ygg_profile_flag} -p ygg-capi` in ${_ygg_workspace} first, or set YGGDRASIL_BUILD_WITH_CARGO=ON")
    if(NOT yggdrasil_FIND_QUIETLY)
      message(FATAL_ERROR "${yggdrasil_NOT_FOUND_MESSAGE}")
    endif()
    return()
  endif()
else()
  # ---- an installed package: <prefix>/lib/cmake/yggdrasil/ ----
  get_filename_component(_ygg_prefix "${_ygg_here}/../../.." ABSOLUTE)
  set(_ygg_lib_dir "${_ygg_prefix}/lib")
  set(_ygg_include "${_ygg_prefix}/include")
  if(NOT EXISTS "${_ygg_lib_dir}/libyggdrasil.so")
    set(yggdrasil_FOUND FALSE)
    set(yggdrasil_NOT_FOUND_MESSAGE "yggdrasil: ${_ygg_lib_dir}/libyggdrasil.so is missing from the installed package")
    if(NOT yggdrasil_FIND_QUIETLY)
      message(FATAL_ERROR "${yggdrasil_NOT_FOUND_MESSAGE}")
    endif()
    return()
  endif()
endif()

add_library(yggdrasil::yggdrasil SHARED IMPORTED GLOBAL)
set_target_properties(yggdrasil::yggdrasil PROPERTIES
  IMPORTED_LOCATION "${_ygg_lib_dir}/libyggdrasil.so"
  IMPORTED_NO_SONAME TRUE
  INTERFACE_INCLUDE_DIRECTORIES "${_ygg_include}"
  INTERFACE_COMPILE_FEATURES cxx_std_17)

add_library(yggdrasil::static STATIC IMPORTED GLOBAL)
set_target_properties(yggdrasil::static PROPERTIES
  IMPORTED_LOCATION "${_ygg_lib_dir}/libyggdrasil.a"
  INTERFACE_INCLUDE_DIRECTORIES "${_ygg_include}"
  INTERFACE_COMPILE_FEATURES cxx_std_17
  INTERFACE_LINK_LIBRARIES "Threads::Threads;${CMAKE_DL_LIBS};m;rt")

if(TARGET yggdrasil_cargo)
  # Whatever links either target waits for cargo (followed through the imported targets).
  add_dependencies(yggdrasil::yggdrasil yggdrasil_cargo)
  add_dependencies(yggdrasil::static yggdrasil_cargo)
endif()

set(yggdrasil_FOUND TRUE)
set(yggdrasil_VERSION 0.1.0)
