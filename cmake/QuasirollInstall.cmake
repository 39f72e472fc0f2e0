# Install rules and the CMake package (included at the end of the top-level
# CMakeLists.txt). `cmake --install <build> --prefix <p>` installs
#   <p>/include/quasiroll/{core,solvers,integrators,bench,conformance}/*.h
#     (not *_internal.h)
#   <p>/lib/libquasiroll_{core,solvers,integrators,harness,conformance}.a
#   <p>/bin/quasiroll
#   <p>/share/quasiroll/{bench/scenes,bench/suites,bench/io/runs_columns.tsv,reports}
#   <p>/lib/cmake/quasiroll/quasirollConfig{,Version}.cmake + targets
# so that find_package(quasiroll) gives quasiroll::core, ::solvers,
# ::integrators, ::harness, ::conformance (if QUASIROLL_WITH_CONFORMANCE) and
# the executable quasiroll::quasiroll.
#
# The libraries stay static (the default): their private third-party
# dependencies are exported as $<LINK_ONLY:...> and quasirollConfig.cmake
# finds the packages of the backends that were enabled (docs/plugins.md).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(QUASIROLL_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/quasiroll)
set(QUASIROLL_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/quasiroll)
set(QUASIROLL_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/quasiroll)

# Headers: include/quasiroll/core/nlp.h, included as <quasiroll/core/nlp.h>
# (the headers' own includes have the same form).
foreach(_dir core solvers integrators bench)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_dir}/
          DESTINATION ${QUASIROLL_INSTALL_INCLUDEDIR}/${_dir}
          COMPONENT devel
          FILES_MATCHING PATTERN "*.h"
          PATTERN "cli" EXCLUDE PATTERN "scenes" EXCLUDE PATTERN "suites" EXCLUDE
          # Internal to a backend (third-party types, e.g. SUNDIALS): not
          # part of the installed API.
          PATTERN "*_internal.h" EXCLUDE)
endforeach()
set(_quasiroll_install_targets quasiroll_core quasiroll_solvers quasiroll_integrators
    quasiroll_harness quasiroll_warnings quasiroll)
if(QUASIROLL_WITH_CONFORMANCE)
  # The kit's sources are in tests/conformance (next to the tests that use
  # them); its headers are <quasiroll/conformance/...>.
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/tests/conformance/
          DESTINATION ${QUASIROLL_INSTALL_INCLUDEDIR}/conformance
          COMPONENT devel FILES_MATCHING PATTERN "*.h")
  set_target_properties(quasiroll_conformance PROPERTIES EXPORT_NAME conformance)
  list(APPEND _quasiroll_install_targets quasiroll_conformance)
endif()

# Export names: quasiroll_core -> quasiroll::core etc. quasiroll_warnings is
# an INTERFACE target that only carries warning flags; the static libraries
# reference it as $<LINK_ONLY:...> (no effect on consumers), so it has to be
# in the export set too.
set_target_properties(quasiroll_core PROPERTIES EXPORT_NAME core)
set_target_properties(quasiroll_solvers PROPERTIES EXPORT_NAME solvers)
set_target_properties(quasiroll_integrators PROPERTIES EXPORT_NAME integrators)
set_target_properties(quasiroll_harness PROPERTIES EXPORT_NAME harness)
set_target_properties(quasiroll_warnings PROPERTIES EXPORT_NAME internal_warnings)

install(TARGETS ${_quasiroll_install_targets}
        EXPORT quasirollTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT devel
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime
        # Only include/: <quasiroll/core/nlp.h>, so that no quasiroll header
        # can be reached (or shadowed) as "core/nlp.h".
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# Run-time data.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/bench/scenes ${PROJECT_SOURCE_DIR}/bench/suites
                  ${PROJECT_SOURCE_DIR}/bench/atlases
        DESTINATION ${QUASIROLL_INSTALL_DATADIR}/bench COMPONENT runtime)
# The runs.csv schema, read by the report (reports/quasiroll_report/data.py).
install(FILES ${PROJECT_SOURCE_DIR}/bench/io/runs_columns.tsv
        DESTINATION ${QUASIROLL_INSTALL_DATADIR}/bench/io COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/reports/
        DESTINATION ${QUASIROLL_INSTALL_DATADIR}/reports COMPONENT runtime
        PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE)

install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CITATION.cff
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)

install(EXPORT quasirollTargets NAMESPACE quasiroll::
        DESTINATION ${QUASIROLL_INSTALL_CMAKEDIR} COMPONENT devel)
# The backends' find_dependency() calls, from the quasiroll_add_backend()
# calls (cmake/QuasirollBackend.cmake).
quasiroll_backend_config_code(QUASIROLL_BACKEND_DEPENDENCIES)
configure_package_config_file(
  ${CMAKE_CURRENT_LIST_DIR}/quasirollConfig.cmake.in
  ${PROJECT_BINARY_DIR}/quasirollConfig.cmake
  INSTALL_DESTINATION ${QUASIROLL_INSTALL_CMAKEDIR}
  PATH_VARS QUASIROLL_INSTALL_INCLUDEDIR QUASIROLL_INSTALL_DATADIR)
# 0.x: minor versions may break the plugin interface.
write_basic_package_version_file(
  ${PROJECT_BINARY_DIR}/quasirollConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/quasirollConfig.cmake
              ${PROJECT_BINARY_DIR}/quasirollConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/QuasirollReferenceBlas.cmake
        DESTINATION ${QUASIROLL_INSTALL_CMAKEDIR} COMPONENT devel)
