# CMake package of Yggdrasil's C API: `find_package(yggdrasil CONFIG)` (point
# `yggdrasil_DIR` or `CMAKE_PREFIX_PATH` at this folder) or `add_subdirectory(capi)`.
#
# Defines the imported targets
#   yggdrasil::yggdrasil  libyggdrasil.so, with yggdrasil.h and yggdrasil.hpp (C++17)
#   yggdrasil::static     libyggdrasil.a and the system libraries it needs
# over the library cargo built: `cargo build --release -p ygg-capi` first.
#
# Cache variables:
#   YGGDRASIL_PROFILE           cargo profile to link: release (default) or debug
#   YGGDRASIL_CARGO_TARGET_DIR  cargo's target directory (default: $CARGO_TARGET_DIR,
#                               else the workspace's target/)
if(TARGET yggdrasil::yggdrasil)
  return()
endif()

get_filename_component(_ygg_capi_dir "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
get_filename_component(_ygg_workspace "${_ygg_capi_dir}/.." ABSOLUTE)
if(DEFINED ENV{CARGO_TARGET_DIR})
  set(_ygg_default_target "$ENV{CARGO_TARGET_DIR}")
else()
  set(_ygg_default_target "${_ygg_workspace}/target")
endif()
set(YGGDRASIL_CARGO_TARGET_DIR "${_ygg_default_target}" CACHE PATH "cargo target directory holding libyggdrasil")
set(YGGDRASIL_PROFILE "release" CACHE STRING "cargo profile of libyggdrasil to link (release or debug)")

set(_ygg_lib_dir "${YGGDRASIL_CARGO_TARGET_DIR}/${YGGDRASIL_PROFILE}")
set(_ygg_shared "${_ygg_lib_dir}/libyggdrasil.so")
set(_ygg_static "${_ygg_lib_dir}/libyggdrasil.a")
if(NOT EXISTS "${_ygg_shared}")
  if(YGGDRASIL_PROFILE STREQUAL "release")
    set(_ygg_build "cargo build --release -p ygg-capi")
  else()
    set(_ygg_build "cargo build -p ygg-capi")
  endif()
  set(yggdrasil_FOUND FALSE)
  set(yggdrasil_NOT_FOUND_MESSAGE
      "yggdrasil: ${_ygg_shared} does not exist; run `${_ygg_build}` in ${_ygg_workspace} first (or set YGGDRASIL_PROFILE / YGGDRASIL_CARGO_TARGET_DIR)")
  if(NOT yggdrasil_FIND_QUIETLY)
    message(FATAL_ERROR "${yggdrasil_NOT_FOUND_MESSAGE}")
  endif()
  return()
endif()

find_package(Threads REQUIRED)

add_library(yggdrasil::yggdrasil SHARED IMPORTED GLOBAL)
set_target_properties(yggdrasil::yggdrasil PROPERTIES
  IMPORTED_LOCATION "${_ygg_shared}"
  IMPORTED_NO_SONAME TRUE
  INTERFACE_INCLUDE_DIRECTORIES "${_ygg_capi_dir}/include"
  INTERFACE_COMPILE_FEATURES cxx_std_17)

add_library(yggdrasil::static STATIC IMPORTED GLOBAL)
set_target_properties(yggdrasil::static PROPERTIES
  IMPORTED_LOCATION "${_ygg_static}"
  INTERFACE_INCLUDE_DIRECTORIES "${_ygg_capi_dir}/include"
  INTERFACE_COMPILE_FEATURES cxx_std_17
  INTERFACE_LINK_LIBRARIES "Threads::Threads;${CMAKE_DL_LIBS};m;rt")

set(yggdrasil_FOUND TRUE)
set(yggdrasil_VERSION 0.1.0)
