# Shared by the build (top-level CMakeLists.txt) and the installed package
# (quasirollConfig.cmake): the QUASIROLL_REFERENCE_LAPACK pin, see
# docs/performance.md, "Reproducibility".

# Removes ATLAS (libf77blas, libcblas, libatlas) from Ceres' link interface,
# which names them on Debian. The reference libblas.so.3 exports the same
# Fortran BLAS symbols, so with it no ATLAS library is loaded at all.
function(quasiroll_drop_atlas_from_ceres)
  if(NOT TARGET Ceres::ceres)
    return()
  endif()
  get_target_property(_links Ceres::ceres INTERFACE_LINK_LIBRARIES)
  if(NOT _links)
    return()
  endif()
  list(FILTER _links EXCLUDE REGEX "lib(f77blas|cblas|atlas)\\.so")
  set_target_properties(Ceres::ceres PROPERTIES INTERFACE_LINK_LIBRARIES
                                                "${_links}")
endfunction()
