# Finds CHOLMOD from Debian's libsuitesparse-dev (no CMake config is shipped there).
# Defines the imported target SuiteSparse::CHOLMOD, with the BLAS its supernodal factorization
# runs on (core also calls that BLAS's dsyrk directly: certification/interface_schur.cpp).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
find_library(CHOLMOD_BLAS_LIBRARY blas)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SuiteSparseCholmod DEFAULT_MSG CHOLMOD_LIBRARY CHOLMOD_INCLUDE_DIR
                                  SUITESPARSE_CONFIG_LIBRARY CHOLMOD_BLAS_LIBRARY)
if(SuiteSparseCholmod_FOUND AND NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
    IMPORTED_LOCATION ${CHOLMOD_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES ${CHOLMOD_INCLUDE_DIR}
    INTERFACE_LINK_LIBRARIES "${SUITESPARSE_CONFIG_LIBRARY};${CHOLMOD_BLAS_LIBRARY}")
endif()
