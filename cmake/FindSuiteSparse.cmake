# Finds SuiteSparse's CHOLMOD and UMFPACK (Debian: libsuitesparse-dev, no CMake config in
# Debian 12) and defines SuiteSparse::CHOLMOD and SuiteSparse::UMFPACK.
find_path(SuiteSparse_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(SuiteSparse_CHOLMOD_LIBRARY NAMES cholmod)
find_library(SuiteSparse_UMFPACK_LIBRARY NAMES umfpack)
find_library(SuiteSparse_CONFIG_LIBRARY NAMES suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SuiteSparse REQUIRED_VARS SuiteSparse_CHOLMOD_LIBRARY
  SuiteSparse_UMFPACK_LIBRARY SuiteSparse_CONFIG_LIBRARY SuiteSparse_INCLUDE_DIR)
if(SuiteSparse_FOUND)
  foreach(lib CHOLMOD UMFPACK)
    if(NOT TARGET SuiteSparse::${lib})
      add_library(SuiteSparse::${lib} UNKNOWN IMPORTED)
      set_target_properties(SuiteSparse::${lib} PROPERTIES
        IMPORTED_LOCATION "${SuiteSparse_${lib}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${SuiteSparse_INCLUDE_DIR}"
        INTERFACE_LINK_LIBRARIES "${SuiteSparse_CONFIG_LIBRARY}")
    endif()
  endforeach()
endif()
