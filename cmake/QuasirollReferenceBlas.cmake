# Shared by the build (top-level CMakeLists.txt) and the installed package
# (quasirollConfig.cmake): the QUASIROLL_REFERENCE_LAPACK pin, see
# docs/performance.md, "Reproducibility".

# Removes ATLAS (libf77blas, libcblas, libatlas) from the link interface of
# each given imported target that names them (Ceres::ceres does on Debian).
# The reference libblas.so.3 exports the same Fortran BLAS symbols, so with
# it no ATLAS library is loaded at all. Called for the libraries of every
# enabled backend (cmake/QuasirollBackend.cmake, quasirollConfig.cmake).
function(quasiroll_drop_atlas)
  foreach(target IN LISTS ARGN)
    if(NOT TARGET ${target})
      continue()
    endif()
    get_target_property(links ${target} INTERFACE_LINK_LIBRARIES)
    if(NOT links)
      continue()
    endif()
    set(kept ${links})
    list(FILTER kept EXCLUDE REGEX "lib(f77blas|cblas|atlas)\\.so")
    if(NOT kept STREQUAL links)
      set_target_properties(${target} PROPERTIES INTERFACE_LINK_LIBRARIES "${kept}")
    endif()
  endforeach()
endfunction()
