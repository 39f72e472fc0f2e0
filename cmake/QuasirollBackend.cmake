# One call per backend (docs/plugins.md, "Adding a backend"): included by the
# top-level CMakeLists.txt, called in solvers/CMakeLists.txt and
# integrators/CMakeLists.txt.
#
#   quasiroll_add_backend(<name>
#     TARGET <quasiroll_solvers|quasiroll_integrators>
#     SOURCES <file.cc>...
#     DESCRIPTION "<one line for feature_summary>"
#     [OPTION <QUASIROLL_WITH_X> [DEFAULT ON|OFF]]
#     [PACKAGES <package>...]
#     [LIBRARIES <imported target>...])
#
# Without OPTION the backend is always built (quasiroll's own code). With
# OPTION, for a backend that needs third-party libraries:
# * option(<QUASIROLL_WITH_X>), default ON; several backends may name the
#   same option (ida and cvode-projection: QUASIROLL_WITH_SUNDIALS);
# * when ON, each package is looked up and must be found (a configure error
#   names the option that turns the backend off). A package is
#   "<Name> [find_package arguments]", e.g. "Ceres" or
#   "NLopt CONFIG PATHS <dir>", or "pkg-config <module>", which gives the
#   imported target PkgConfig::<MODULE> (upper case);
# * the sources join TARGET, with LIBRARIES linked PRIVATE (their headers
#   stay in the backend's .cc); "A|B" links A if that target exists, else B;
# * TARGET gets the compile definitions QUASIROLL_HAVE_X (the #ifdef around
#   the backend's lines in registry.cc) and QUASIROLL_X_VERSION="<version of
#   the first package>" (its BackendInfo::library_version);
# * add_feature_info(<name>) for feature_summary, with the option;
# * the option and the packages are recorded: bench/CMakeLists.txt records
#   them in run.json / meta.json (quasiroll_backend_build_info), and the
#   installed quasirollConfig.cmake find_dependency()s exactly the packages
#   of the enabled backends (quasiroll_backend_config_code, used by
#   cmake/QuasirollInstall.cmake).
#
# Recorded in global properties:
#   QUASIROLL_BACKEND_OPTIONS            the options, in call order
#   QUASIROLL_BACKEND_<OPT>_NAMES        the backends of an option
#   QUASIROLL_BACKEND_<OPT>_COMPONENTS   solvers and/or integrators
#   QUASIROLL_BACKEND_<OPT>_VERSION      the first package's version
#   QUASIROLL_BACKEND_<OPT>_DEPENDENCIES the installed config's lookups
#   QUASIROLL_BACKEND_LINK_TARGETS       LIBRARIES of the enabled backends
include(FeatureSummary)
include(${CMAKE_CURRENT_LIST_DIR}/QuasirollReferenceBlas.cmake)

function(quasiroll_add_backend name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "TARGET;OPTION;DEFAULT;DESCRIPTION"
                        "SOURCES;PACKAGES;LIBRARIES")
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "quasiroll_add_backend(${name}): unknown arguments "
                        "${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_TARGET OR NOT ARG_SOURCES OR NOT ARG_DESCRIPTION)
    message(FATAL_ERROR "quasiroll_add_backend(${name}): TARGET, SOURCES and "
                        "DESCRIPTION are required")
  endif()
  if(NOT ARG_OPTION)
    if(ARG_PACKAGES OR DEFINED ARG_DEFAULT)
      message(FATAL_ERROR "quasiroll_add_backend(${name}): PACKAGES and DEFAULT "
                          "need an OPTION")
    endif()
    add_feature_info(${name} TRUE "${ARG_DESCRIPTION} (always built)")
    _quasiroll_backend_sources(${ARG_TARGET} ${ARG_SOURCES})
    if(ARG_LIBRARIES)
      target_link_libraries(${ARG_TARGET} PRIVATE ${ARG_LIBRARIES})
    endif()
    return()
  endif()

  set(opt ${ARG_OPTION})
  if(NOT opt MATCHES "^QUASIROLL_WITH_([A-Z0-9_]+)$")
    message(FATAL_ERROR "quasiroll_add_backend(${name}): OPTION must be "
                        "QUASIROLL_WITH_<X>, not ${opt}")
  endif()
  set(key ${CMAKE_MATCH_1})
  if(NOT DEFINED ARG_DEFAULT)
    set(ARG_DEFAULT ON)
  endif()
  option(${opt} "Build the backend '${name}' (${ARG_DESCRIPTION})" ${ARG_DEFAULT})
  add_feature_info(${name} ${opt} "${ARG_DESCRIPTION} (${opt})")
  get_property(options GLOBAL PROPERTY QUASIROLL_BACKEND_OPTIONS)
  if(NOT opt IN_LIST options)
    set_property(GLOBAL APPEND PROPERTY QUASIROLL_BACKEND_OPTIONS ${opt})
  endif()
  string(REGEX REPLACE "^quasiroll_" "" component ${ARG_TARGET})
  _quasiroll_append_unique(QUASIROLL_BACKEND_${opt}_NAMES ${name})
  _quasiroll_append_unique(QUASIROLL_BACKEND_${opt}_COMPONENTS ${component})
  if(NOT ${opt})
    return()
  endif()

  set(version "")
  set(first_package TRUE)
  foreach(package IN LISTS ARG_PACKAGES)
    _quasiroll_backend_find(${name} ${opt} "${package}" package_version)
    if(first_package)
      set(version "${package_version}")
      set(first_package FALSE)
    endif()
  endforeach()

  set(libraries "")
  foreach(library IN LISTS ARG_LIBRARIES)
    if(library MATCHES "\\|")
      string(REPLACE "|" ";" alternatives "${library}")
      set(library "")
      foreach(alternative IN LISTS alternatives)
        if(TARGET ${alternative})
          set(library ${alternative})
          break()
        endif()
      endforeach()
      if(NOT library)
        message(FATAL_ERROR "quasiroll_add_backend(${name}): none of the "
                            "targets ${alternatives} exists")
      endif()
    endif()
    list(APPEND libraries ${library})
  endforeach()
  if(QUASIROLL_REFERENCE_LIBS_PINNED)
    # The QUASIROLL_REFERENCE_LAPACK pin (top-level CMakeLists.txt): no
    # backend library brings ATLAS into the process.
    quasiroll_drop_atlas(${libraries})
  endif()

  _quasiroll_backend_sources(${ARG_TARGET} ${ARG_SOURCES})
  if(libraries)
    target_link_libraries(${ARG_TARGET} PRIVATE ${libraries})
    _quasiroll_append_unique(QUASIROLL_BACKEND_LINK_TARGETS ${libraries})
  endif()
  get_target_property(definitions ${ARG_TARGET} COMPILE_DEFINITIONS)
  if(NOT "QUASIROLL_HAVE_${key}" IN_LIST definitions)
    target_compile_definitions(${ARG_TARGET} PRIVATE QUASIROLL_HAVE_${key}
                               QUASIROLL_${key}_VERSION="${version}")
  endif()
  get_property(recorded GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_VERSION SET)
  if(NOT recorded)
    set_property(GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_VERSION "${version}")
  endif()
endfunction()

# Adds the QUASIROLL_HAVE_<X> definition of every enabled optional backend
# to <target> (tests that #ifdef on the backends compiled in).
function(quasiroll_backend_definitions target)
  get_property(options GLOBAL PROPERTY QUASIROLL_BACKEND_OPTIONS)
  foreach(opt IN LISTS options)
    if(${opt})
      string(REGEX REPLACE "^QUASIROLL_WITH_" "QUASIROLL_HAVE_" definition ${opt})
      target_compile_definitions(${target} PRIVATE ${definition})
    endif()
  endforeach()
endfunction()

# For run.json / meta.json (bench/CMakeLists.txt): <options_var> gets
# "QUASIROLL_WITH_X=ON" / "=OFF" per optional backend option, <versions_var>
# "x=<version>" per enabled one (lists, in call order).
function(quasiroll_backend_build_info options_var versions_var)
  get_property(options GLOBAL PROPERTY QUASIROLL_BACKEND_OPTIONS)
  set(states "")
  set(versions "")
  foreach(opt IN LISTS options)
    if(${opt})
      list(APPEND states "${opt}=ON")
      string(REGEX REPLACE "^QUASIROLL_WITH_" "" key ${opt})
      string(TOLOWER "${key}" key)
      get_property(version GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_VERSION)
      list(APPEND versions "${key}=${version}")
    else()
      list(APPEND states "${opt}=OFF")
    endif()
  endforeach()
  set(${options_var} "${states}" PARENT_SCOPE)
  set(${versions_var} "${versions}" PARENT_SCOPE)
endfunction()

# The installed quasirollConfig.cmake's part for the backends (substituted
# for @QUASIROLL_BACKEND_DEPENDENCIES@): quasiroll_WITH_<X> per option, and
# the lookups of the enabled options' packages when a component that links
# them (_quasiroll_need_<component>) is requested.
function(quasiroll_backend_config_code out_var)
  get_property(options GLOBAL PROPERTY QUASIROLL_BACKEND_OPTIONS)
  set(code "")
  foreach(opt IN LISTS options)
    string(REGEX REPLACE "^QUASIROLL_WITH_" "quasiroll_WITH_" variable ${opt})
    get_property(names GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_NAMES)
    list(JOIN names ", " names)
    if(${opt})
      set(value ON)
    else()
      set(value OFF)
    endif()
    string(APPEND code "# ${opt}: ${names}\nset(${variable} ${value})\n")
    get_property(lookups GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_DEPENDENCIES)
    if(NOT ${opt} OR NOT lookups)
      continue()
    endif()
    get_property(components GLOBAL PROPERTY QUASIROLL_BACKEND_${opt}_COMPONENTS)
    list(TRANSFORM components PREPEND "_quasiroll_need_")
    list(JOIN components " OR " condition)
    string(APPEND code "if(${condition})\n")
    foreach(lookup IN LISTS lookups)
      string(APPEND code "  ${lookup}\n")
    endforeach()
    string(APPEND code "endif()\n")
  endforeach()
  get_property(targets GLOBAL PROPERTY QUASIROLL_BACKEND_LINK_TARGETS)
  list(JOIN targets " " targets)
  string(APPEND code "set(_quasiroll_backend_link_targets ${targets})\n")
  set(${out_var} "${code}" PARENT_SCOPE)
endfunction()

# --- internal ---------------------------------------------------------------

function(_quasiroll_append_unique property)
  get_property(values GLOBAL PROPERTY ${property})
  foreach(value IN LISTS ARGN)
    if(NOT value IN_LIST values)
      list(APPEND values ${value})
    endif()
  endforeach()
  set_property(GLOBAL PROPERTY ${property} "${values}")
endfunction()

# Sources a target does not have yet (backends may share a support file).
function(_quasiroll_backend_sources target)
  get_target_property(existing ${target} SOURCES)
  foreach(source IN LISTS ARGN)
    if(NOT source IN_LIST existing)
      target_sources(${target} PRIVATE ${source})
    endif()
  endforeach()
endfunction()

# Looks up one package of an enabled backend (fatal if missing), records the
# installed config's lookup of it and returns its version.
function(_quasiroll_backend_find name opt package version_var)
  separate_arguments(words UNIX_COMMAND "${package}")
  list(POP_FRONT words package_name)
  set(hint "install it (scripts/install-deps.sh) or configure with -D${opt}=OFF")
  if(package_name STREQUAL "pkg-config")
    list(LENGTH words count)
    if(NOT count EQUAL 1)
      message(FATAL_ERROR "quasiroll_add_backend(${name}): \"pkg-config <module>\", "
                          "not \"${package}\"")
    endif()
    string(TOUPPER "${words}" prefix)
    string(MAKE_C_IDENTIFIER "${prefix}" prefix)
    find_package(PkgConfig REQUIRED)
    pkg_check_modules(${prefix} IMPORTED_TARGET ${words})
    if(NOT TARGET PkgConfig::${prefix})
      message(FATAL_ERROR "${opt}=ON: the backend '${name}' needs the "
                          "pkg-config module '${words}'; ${hint}")
    endif()
    set(${version_var} "${${prefix}_VERSION}" PARENT_SCOPE)
    _quasiroll_append_unique(QUASIROLL_BACKEND_${opt}_DEPENDENCIES
                             "_quasiroll_find_pkg_config(${prefix} ${words})")
    return()
  endif()
  find_package(${package_name} ${words})
  if(NOT ${package_name}_FOUND)
    message(FATAL_ERROR "${opt}=ON: the backend '${name}' needs the package "
                        "${package_name}; ${hint}")
  endif()
  set_package_properties(${package_name} PROPERTIES TYPE OPTIONAL
                         PURPOSE "backend '${name}' (${opt})")
  set(${version_var} "${${package_name}_VERSION}" PARENT_SCOPE)
  # Found through a package config: the installed config looks in the same
  # directory first, so that consumers link what quasiroll was built with.
  set(lookup "find_dependency(${package}")
  if(${package_name}_CONFIG AND ${package_name}_DIR)
    string(APPEND lookup " HINTS \"${${package_name}_DIR}\"")
  endif()
  string(APPEND lookup ")")
  _quasiroll_append_unique(QUASIROLL_BACKEND_${opt}_DEPENDENCIES "${lookup}")
endfunction()
