# Driver of the package tests (tests/consumer/CMakeLists.txt): cmake -DSTEP=... -P run.cmake
#   STEP=install   a fresh `cmake --install BUILD --prefix WORK/prefix` (components dev and libs)
#   STEP=cmake     configure NAME (SRC) against WORK/prefix with CMAKE_PREFIX_PATH, build, run it
#   STEP=pkgconfig build SRC's first_simulation.cpp with make and `pkg-config medspring`, run it
#   STEP=errors    find_package(MedSpring COMPONENTS nosuch) and (VTK disabled) COMPONENTS io must fail
#                  with the component list / the Debian package in the message
cmake_minimum_required(VERSION 3.25)
set(prefix "${WORK}/prefix")

# run(<what> <expect: ok|fail> <output regex> COMMAND ...): fails the test on a wrong exit status or
# when the output (stdout + stderr) does not match the regex.
function(run what expect regex)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if((expect STREQUAL "ok" AND NOT rc EQUAL 0) OR (expect STREQUAL "fail" AND rc EQUAL 0))
    message(FATAL_ERROR "${what}: exit status ${rc}, expected ${expect}:\n${out}")
  endif()
  string(REGEX REPLACE "[ \t\r\n]+" " " flat "${out}")  # CMake wraps its messages
  if(NOT out MATCHES "${regex}" AND NOT flat MATCHES "${regex}")
    message(FATAL_ERROR "${what}: output does not match '${regex}':\n${out}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

set(configure_args -G "${GENERATOR}" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}"
  "-DCMAKE_CXX_COMPILER=${CXX}")
if(LAUNCHER)
  list(APPEND configure_args "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}")
endif()

if(STEP STREQUAL "install")
  file(REMOVE_RECURSE "${WORK}")
  foreach(component dev libs)
    run("cmake --install --component ${component}" ok "" ${CMAKE_COMMAND} --install "${BUILD}" --prefix "${prefix}"
      --component ${component})
  endforeach()
  if(NOT EXISTS "${prefix}/lib/cmake/MedSpring/MedSpringConfig.cmake" AND
     NOT EXISTS "${prefix}/${LIBDIR}/cmake/MedSpring/MedSpringConfig.cmake")
    message(FATAL_ERROR "no MedSpringConfig.cmake under ${prefix}")
  endif()

elseif(STEP STREQUAL "cmake")
  set(bin "${WORK}/${NAME}")
  file(REMOVE_RECURSE "${bin}")
  run("configure ${NAME}" ok "MedSpring|Configuring done" ${CMAKE_COMMAND} -S "${SRC}" -B "${bin}" ${configure_args})
  string(FIND "${last_output}" "from ${prefix}/" at)
  if(NAME STREQUAL "engine" AND at EQUAL -1)
    message(FATAL_ERROR "configure ${NAME}: MedSpring was not found in ${prefix}:\n${last_output}")
  endif()
  run("build ${NAME}" ok "" ${CMAKE_COMMAND} --build "${bin}")
  run("run ${NAME}" ok "${EXPECT}" "${bin}/${EXE}" "${bin}")
  message(STATUS "${last_output}")

elseif(STEP STREQUAL "pkgconfig")
  set(bin "${WORK}/pkgconfig")
  file(REMOVE_RECURSE "${bin}")
  file(MAKE_DIRECTORY "${bin}")
  set(ENV{PKG_CONFIG_PATH} "${prefix}/${LIBDIR}/pkgconfig")
  run("pkg-config --modversion medspring" ok "^${VERSION}" pkg-config --modversion medspring)
  run("make with pkg-config" ok "" make -C "${bin}" -f "${MAKEFILE}" "SRC=${SRC}" "CXX=${CXX}")
  run("run first_simulation" ok "${EXPECT}" "${bin}/first_simulation")
  message(STATUS "${last_output}")

elseif(STEP STREQUAL "errors")
  set(bin "${WORK}/errors")
  file(REMOVE_RECURSE "${bin}")
  foreach(case nosuch novtk)
    file(MAKE_DIRECTORY "${bin}/${case}")
    if(case STREQUAL "nosuch")
      set(components "io nosuch")
      set(args "")
      set(regex "MedSpring has no component 'nosuch'; the components of this installation are: engine, [a-z, ]*io")
    else()
      set(components "io")
      set(args -DCMAKE_DISABLE_FIND_PACKAGE_VTK=ON)  # a machine without VTK
      set(regex "component 'io' needs VTK \\(CommonCore[A-Za-z ]*\\), on Debian/Ubuntu: apt-get install libvtk9-dev")
    endif()
    file(WRITE "${bin}/${case}/CMakeLists.txt" "cmake_minimum_required(VERSION 3.16)\nproject(${case} CXX)\n"
      "find_package(MedSpring REQUIRED COMPONENTS ${components})\n")
    run("find_package(MedSpring COMPONENTS ${components}) ${args}" fail "${regex}"
      ${CMAKE_COMMAND} -S "${bin}/${case}" -B "${bin}/${case}/build" ${configure_args} ${args})
  endforeach()

else()
  message(FATAL_ERROR "run.cmake: unknown STEP '${STEP}'")
endif()
