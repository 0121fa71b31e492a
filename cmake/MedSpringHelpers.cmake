# Library targets, their package components, and tests.
#
# A library joins the installed package in one line: medspring_add_layer(NAME ... [COMPONENT c]).
# Components are what a consumer names in find_package(MedSpring COMPONENTS ...); each has its own
# export file (MedSpring<C>Targets.cmake, included on demand by MedSpringConfig.cmake) and the
# external packages it needs (declared with medspring_find_package). Components it depends on are
# worked out from the MedSpring:: targets a layer links. See docs/packaging.md.

# medspring_add_layer(layer SOURCES ... DEPS ... PRIVATE_DEPS ... [COMPONENT component])
# Declares the library target medspring_<layer>, alias MedSpring::<layer>, with the public
# headers under include/ and the house warning flags; installs and exports it in `component`
# (default: engine, the Eigen-only layers).
# libFuzzer's coverage hooks in a MEDSPRING_FUZZ tree: the layers and files that hold what the fuzz targets
# parse (fuzz/CMakeLists.txt), and the fuzz targets themselves. Not the engine's numerical code or the tests:
# the hooks (a callback on every edge and comparison) made the sanitized suite's physics 2.5x slower for
# nothing the parsers' fuzzing uses (docs/reliability.md, "Build time in CI").
set(MEDSPRING_FUZZ_COVERAGE_LAYERS core geometry io scene)
set(MEDSPRING_FUZZ_COVERAGE_FILES sim/checkpoint.cpp models/model_package.cpp fem/frd.cpp)
function(medspring_fuzz_coverage target)
  if(MEDSPRING_FUZZ)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()

function(medspring_add_layer layer)
  cmake_parse_arguments(ARG "" "COMPONENT" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  if(NOT ARG_COMPONENT)
    set(ARG_COMPONENT engine)
  endif()
  set(target medspring_${layer})
  add_library(${target} ${ARG_SOURCES})
  add_library(MedSpring::${layer} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${layer} POSITION_INDEPENDENT_CODE ON
    OUTPUT_NAME medspring_${layer})
  target_compile_features(${target} PUBLIC cxx_std_20)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS} $<BUILD_INTERFACE:MedSpring::options>)
  if(MEDSPRING_NATIVE)
    # Eigen's alignment (and so the layout and heap allocation of its objects) depends on the
    # instruction set: code using the installed headers must be compiled for the same one.
    target_compile_options(${target} INTERFACE $<INSTALL_INTERFACE:-march=native>)
  endif()
  medspring_shared_library_properties(${target})
  medspring_install_target(${target} COMPONENT ${ARG_COMPONENT} DEPS ${ARG_DEPS})
  if(MEDSPRING_FUZZ AND layer IN_LIST MEDSPRING_FUZZ_COVERAGE_LAYERS)
    medspring_fuzz_coverage(${target})
  elseif(MEDSPRING_FUZZ)
    foreach(file IN LISTS MEDSPRING_FUZZ_COVERAGE_FILES)
      if(file MATCHES "^${layer}/(.+)$")
        set_property(SOURCE ${CMAKE_MATCH_1} APPEND PROPERTY COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
      endif()
    endforeach()
  endif()
endfunction()

# medspring_install_target(target COMPONENT component [DEPS ...])
# Installs `target` into the export set of `component` (declared on first use). DEPS: the MedSpring::
# targets it links, from which the components it needs are recorded. Install components (CPack):
# static libraries, headers and CMake files are `dev`; shared libraries `libs` (their .so link `dev`).
function(medspring_install_target target)
  cmake_parse_arguments(ARG "" "COMPONENT" "DEPS" ${ARGN})
  medspring_component(${ARG_COMPONENT})
  set_property(TARGET ${target} PROPERTY MEDSPRING_COMPONENT ${ARG_COMPONENT})
  set_property(GLOBAL APPEND PROPERTY MEDSPRING_INSTALLED_TARGETS ${target})
  foreach(dep IN LISTS ARG_DEPS)
    if(NOT TARGET ${dep})
      continue()
    endif()
    get_target_property(real ${dep} ALIASED_TARGET)
    if(NOT real)
      set(real ${dep})
    endif()
    get_target_property(dep_component ${real} MEDSPRING_COMPONENT)
    if(dep_component AND NOT dep_component STREQUAL ARG_COMPONENT)
      set_property(GLOBAL APPEND PROPERTY MEDSPRING_COMPONENT_${ARG_COMPONENT}_REQUIRES ${dep_component})
    endif()
  endforeach()
  medspring_component_export_name(${ARG_COMPONENT} export)
  install(TARGETS ${target} EXPORT ${export}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT libs NAMELINK_COMPONENT dev
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT dev)
endfunction()

# medspring_component(component): declares a package component (idempotent; declaration order is
# dependency order: a component may only need components declared before it).
function(medspring_component component)
  get_property(all GLOBAL PROPERTY MEDSPRING_COMPONENTS)
  if(NOT component IN_LIST all)
    set_property(GLOBAL APPEND PROPERTY MEDSPRING_COMPONENTS ${component})
  endif()
endfunction()

# medspring_component_export_name(component out): "io" -> MedSpringIoTargets
function(medspring_component_export_name component out)
  string(SUBSTRING ${component} 0 1 first)
  string(SUBSTRING ${component} 1 -1 rest)
  string(TOUPPER ${first} first)
  set(${out} MedSpring${first}${rest}Targets PARENT_SCOPE)
endfunction()

# medspring_find_package(COMPONENT component DEBIAN debian-package <find_package arguments>)
# find_package(<arguments> REQUIRED) for this build, and the same search (package, version, CONFIG /
# NO_MODULE, COMPONENTS) recorded for the installed MedSpringConfig.cmake, which repeats it for
# consumers asking for `component`, naming `debian-package` when it fails. A macro: the package's
# variables (VTK_LIBRARIES, ...) land in the caller's scope as with find_package.
macro(medspring_find_package)
  cmake_parse_arguments(_msfp "" "COMPONENT;DEBIAN" "" ${ARGN})
  find_package(${_msfp_UNPARSED_ARGUMENTS} REQUIRED)
  medspring_record_package_dependency(${_msfp_COMPONENT} ${_msfp_DEBIAN} ${_msfp_UNPARSED_ARGUMENTS})
endmacro()

function(medspring_record_package_dependency component debian package)
  medspring_component(${component})
  set(version "")
  set(flags "")
  set(components "")
  set(in_components FALSE)
  foreach(arg IN LISTS ARGN)
    if(arg STREQUAL "COMPONENTS")
      set(in_components TRUE)
    elseif(arg MATCHES "^(CONFIG|NO_MODULE|MODULE)$")
      list(APPEND flags ${arg})
    elseif(arg MATCHES "^(REQUIRED|QUIET|EXACT)$")
    elseif(in_components)
      list(APPEND components ${arg})
    elseif(arg MATCHES "^[0-9]" AND NOT version)
      set(version ${arg})
    endif()
  endforeach()
  set_property(GLOBAL APPEND PROPERTY MEDSPRING_COMPONENT_${component}_PACKAGES ${package})
  set_property(GLOBAL APPEND PROPERTY MEDSPRING_PACKAGE_${package}_COMPONENTS_OF_${component} ${components})
  set_property(GLOBAL PROPERTY MEDSPRING_PACKAGE_${package}_VERSION "${version}")
  set_property(GLOBAL PROPERTY MEDSPRING_PACKAGE_${package}_FLAGS "${flags}")
  set_property(GLOBAL PROPERTY MEDSPRING_PACKAGE_${package}_DEBIAN "${debian}")
endfunction()

# medspring_shared_library_properties(target): with BUILD_SHARED_LIBS, the shared library gets a
# VERSION and SOVERSION and exports only MedSpring's own symbols (cmake/medspring.map: the
# medspring:: namespace; Eigen, std and VTK/CGAL code inlined into it stay internal).
function(medspring_shared_library_properties target)
  get_target_property(type ${target} TYPE)
  if(NOT type STREQUAL "SHARED_LIBRARY")
    return()
  endif()
  set_target_properties(${target} PROPERTIES
    VERSION ${PROJECT_VERSION} SOVERSION ${MEDSPRING_SOVERSION}
    VISIBILITY_INLINES_HIDDEN ON)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang" AND NOT APPLE AND NOT EMSCRIPTEN)
    target_link_options(${target} PRIVATE "LINKER:--version-script=${PROJECT_SOURCE_DIR}/cmake/medspring.map")
    set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS ${PROJECT_SOURCE_DIR}/cmake/medspring.map)
  endif()
endfunction()

# medspring_pch_launcher(target): a target compiled with a precompiled header (MEDSPRING_PCH) keeps its
# objects cacheable under ccache, which needs the sloppiness pch_defines,time_macros for them (its
# manual; "could_not_use_precompiled_header" in its log otherwise). No-op without a ccache launcher.
function(medspring_pch_launcher target)
  if(CMAKE_CXX_COMPILER_LAUNCHER MATCHES "ccache")
    set_property(TARGET ${target} PROPERTY CXX_COMPILER_LAUNCHER
      ${CMAKE_COMMAND} -E env CCACHE_SLOPPINESS=pch_defines,time_macros ${CMAKE_CXX_COMPILER_LAUNCHER})
  endif()
endfunction()

# medspring_add_test(NAME SOURCES ... DEPS ...): one GoogleTest executable, tests discovered by CTest.
# An executable with a label in MEDSPRING_TEST_EXCLUDE_LABELS is defined but not built (EXCLUDE_FROM_ALL) and
# not registered with CTest: a tree that never runs those labels does not compile them (the sanitized CI tree
# leaves out `long`, scripts/sanitize.sh; docs/reliability.md, "Build time in CI").
set(MEDSPRING_TEST_EXCLUDE_LABELS "" CACHE STRING "Test labels whose executables this build leaves out, e.g. \"long\"")
function(medspring_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  set(excluded FALSE)
  foreach(label IN LISTS ARG_LABELS)
    if(label IN_LIST MEDSPRING_TEST_EXCLUDE_LABELS)
      set(excluded TRUE)
    endif()
  endforeach()
  if(excluded)
    set(excluded EXCLUDE_FROM_ALL)
  else()
    set(excluded "")
  endif()
  add_executable(${name} ${excluded} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main MedSpring::options medspring_test_support)
  set_target_properties(${name} PROPERTIES MEDSPRING_GLUE_CODE ON)  # -O1 (CMakeLists.txt, medspring_options)
  if(excluded)
    return()
  endif()
  if(TARGET medspring_test_pch)
    # One precompiled header for every test executable (tests/CMakeLists.txt): same flags, same PCH.
    target_precompile_headers(${name} REUSE_FROM medspring_test_pch)
    medspring_pch_launcher(${name})
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
endfunction()
