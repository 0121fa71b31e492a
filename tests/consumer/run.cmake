# Driver of the package tests (tests/consumer/CMakeLists.txt): cmake -DSTEP=... -P run.cmake
#   STEP=install   a fresh `cmake --install BUILD --prefix WORK/prefix` (components dev and libs)
#   STEP=cmake     configure NAME (SRC) against WORK/prefix with CMAKE_PREFIX_PATH, build, run it
#   STEP=pkgconfig build SRC's first_simulation.cpp with make and `pkg-config medspring`, run it
#   STEP=deb       cpack -G DEB; checks both packages' Depends and file lists with dpkg-deb -I / -c
#   STEP=errors    find_package(MedSpring COMPONENTS nosuch) and (VTK disabled) COMPONENTS io must fail
#                  with the component list / the Debian package in the message; an optional component
#                  whose package is missing (CGAL disabled) is reported as not found
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

# expect(<regex>...): every regex matches the output of the last run().
function(expect)
  foreach(regex IN LISTS ARGN)
    if(NOT last_output MATCHES "${regex}")
      message(FATAL_ERROR "output does not match '${regex}':\n${last_output}")
    endif()
  endforeach()
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
  set(ENV{LD_LIBRARY_PATH} "${prefix}/${LIBDIR}")  # shared libraries (BUILD_SHARED_LIBS) in a private prefix
  run("run first_simulation" ok "${EXPECT}" "${bin}/first_simulation")
  message(STATUS "${last_output}")

elseif(STEP STREQUAL "errors")
  set(bin "${WORK}/errors")
  file(REMOVE_RECURSE "${bin}")
  foreach(case nosuch novtk)
    file(MAKE_DIRECTORY "${bin}/${case}")
    if(case STREQUAL "novtk" AND NOT HAVE_IO)
      continue()  # a build without the io layer
    endif()
    if(case STREQUAL "nosuch")
      set(components "engine nosuch")
      set(args "")
      set(regex "MedSpring has no component 'nosuch'; the components of this installation are: engine(, [a-z]+)*")
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
  # an optional component whose package is missing is reported as not found; the rest is usable
  # (and an unknown optional one too)
  file(MAKE_DIRECTORY "${bin}/optional")
  file(WRITE "${bin}/optional/CMakeLists.txt" "cmake_minimum_required(VERSION 3.16)\nproject(optional CXX)\n"
    "find_package(MedSpring REQUIRED OPTIONAL_COMPONENTS meshing nosuch)\n"
    "message(STATUS \"engine=\${MedSpring_engine_FOUND} meshing=\${MedSpring_meshing_FOUND} nosuch=\${MedSpring_nosuch_FOUND}\")\n"
    "if(TARGET MedSpring::meshing OR NOT TARGET MedSpring::engine)\n  message(FATAL_ERROR \"wrong targets\")\nendif()\n")
  run("find_package(MedSpring OPTIONAL_COMPONENTS meshing nosuch) without CGAL" ok
    "engine=TRUE meshing=FALSE nosuch=FALSE" ${CMAKE_COMMAND} -S "${bin}/optional" -B "${bin}/optional/build"
    ${configure_args} -DCMAKE_DISABLE_FIND_PACKAGE_CGAL=ON)

elseif(STEP STREQUAL "deb")
  # cpack -G DEB from this build, then the control fields and file lists of both packages.
  set(dist "${WORK}/deb")
  file(REMOVE_RECURSE "${dist}")
  run("cpack -G DEB" ok "libmedspring-dev_${VERSION}_[a-z0-9]+\\.deb generated"
    ${CMAKE_CPACK_COMMAND} --config "${BUILD}/CPackConfig.cmake" -G DEB -B "${dist}")
  file(GLOB dev "${dist}/libmedspring-dev_${VERSION}_*.deb")
  file(GLOB cli "${dist}/medspring_${VERSION}_*.deb")
  if(NOT dev OR NOT cli)
    message(FATAL_ERROR "cpack did not write libmedspring-dev_${VERSION}_*.deb and medspring_${VERSION}_*.deb")
  endif()
  run("dpkg-deb -I libmedspring-dev" ok "Package: libmedspring-dev\n" dpkg-deb -I "${dev}")
  expect("Depends: libeigen3-dev \\(>= 3\\.3\\)\n" "Recommends: [^\n]*libvtk9-dev" "Section: libdevel")
  if(last_output MATCHES "Depends:[^\n]*(vtk|cgal)")
    message(FATAL_ERROR "libmedspring-dev depends on VTK/CGAL, which only its components need:\n${last_output}")
  endif()
  run("dpkg-deb -c libmedspring-dev" ok "" dpkg-deb -c "${dev}")
  foreach(file usr/include/medspring/sim/simulation.hpp usr/include/medspring/io/mesh_io.hpp
      usr/lib/cmake/MedSpring/MedSpringConfig.cmake usr/lib/cmake/MedSpring/MedSpringConfigVersion.cmake
      usr/lib/cmake/MedSpring/MedSpringEngineTargets.cmake usr/lib/cmake/MedSpring/MedSpringIoTargets.cmake
      usr/lib/pkgconfig/medspring.pc usr/lib/libmedspring_core)
    string(FIND "${last_output}" "./${file}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "libmedspring-dev lacks /${file}:\n${last_output}")
    endif()
  endforeach()
  if(last_output MATCHES "usr/bin/")
    message(FATAL_ERROR "libmedspring-dev holds programs:\n${last_output}")
  endif()
  # the command's Depends come from dpkg-shlibdeps: the C++ runtime and VTK's runtime library
  run("dpkg-deb -I medspring" ok "Package: medspring\n" dpkg-deb -I "${cli}")
  expect("Depends: [^\n]*libstdc\\+\\+6" "Depends: [^\n]*libvtk9\\.1" "Recommends: [^\n]*python3-matplotlib")
  if(last_output MATCHES "Depends:[^\n]*-dev")
    message(FATAL_ERROR "the medspring command depends on a -dev package:\n${last_output}")
  endif()
  run("dpkg-deb -c medspring" ok "\\./usr/bin/medspring\n.*\\./usr/share/medspring/scenes/phantom/kidney_1\\.0N_nonlinear\\.json"
    dpkg-deb -c "${cli}")
  expect("\\./usr/share/bash-completion/completions/medspring\n")  # generated from apps/commands.cpp
  if(last_output MATCHES "usr/include/|\\.a\n")
    message(FATAL_ERROR "the medspring package holds headers or libraries:\n${last_output}")
  endif()

else()
  message(FATAL_ERROR "run.cmake: unknown STEP '${STEP}'")
endif()
