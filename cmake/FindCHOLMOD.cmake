# FindCHOLMOD: Debian's SuiteSparse 5.12 ships neither CMake config nor pkg-config files.
# Defines SuiteSparse::CHOLMOD (imported, links cholmod + suitesparseconfig) and CHOLMOD_VERSION.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSECONFIG_LIBRARY suitesparseconfig)
if(CHOLMOD_INCLUDE_DIR AND EXISTS "${CHOLMOD_INCLUDE_DIR}/cholmod_core.h")
  file(STRINGS "${CHOLMOD_INCLUDE_DIR}/cholmod_core.h" _cholmod_version_lines
       REGEX "#define CHOLMOD_(MAIN|SUB|SUBSUB)_VERSION")
  string(REGEX REPLACE ".*MAIN_VERSION +([0-9]+).*" "\\1" _major "${_cholmod_version_lines}")
  string(REGEX REPLACE ".*SUB_VERSION +([0-9]+).*SUBSUB.*" "\\1" _minor "${_cholmod_version_lines}")
  string(REGEX REPLACE ".*SUBSUB_VERSION +([0-9]+).*" "\\1" _patch "${_cholmod_version_lines}")
  set(CHOLMOD_VERSION "${_major}.${_minor}.${_patch}")
endif()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD
  REQUIRED_VARS CHOLMOD_LIBRARY SUITESPARSECONFIG_LIBRARY CHOLMOD_INCLUDE_DIR
  VERSION_VAR CHOLMOD_VERSION)
if(CHOLMOD_FOUND AND NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
    IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${SUITESPARSECONFIG_LIBRARY}")
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY SUITESPARSECONFIG_LIBRARY)
