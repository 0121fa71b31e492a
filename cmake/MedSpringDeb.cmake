# Debian packages through CPack (docs/packaging.md):
#   cpack --config build/CPackConfig.cmake -G DEB -B dist
# gives libmedspring-dev_<version>_<arch>.deb (install component `dev`: headers, libraries, CMake and
# pkg-config files) and medspring_<version>_<arch>.deb (component `cli`: the medspring command, its
# scenes, figure scripts and web page). With -DBUILD_SHARED_LIBS=ON the shared libraries go into a third
# package, libmedspring<soversion>. Build the packages from a build configured with
# -DMEDSPRING_NATIVE=OFF to run them on other machines (the default -march=native ties them to this CPU).

set(CPACK_PACKAGE_NAME medspring)
set(CPACK_PACKAGE_VENDOR "MedSpring")
set(CPACK_PACKAGE_CONTACT "MedSpring developers <medspring@localhost>")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "https://github.com/medspring/medspring")
set(CPACK_COMPONENTS_ALL dev cli)

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libmedspring-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_COMPONENT_DEV_DESCRIPTION "MedSpring C++ library: headers, libraries, CMake and pkg-config files
 find_package(MedSpring) gives the Eigen-only engine; the components io, meshing,
 builders and scene need the packages recommended here.")
# The engine needs Eigen's headers; the edge components (static libraries linking VTK, zlib, CGAL)
# need the -dev packages recorded by medspring_find_package, only when a consumer asks for them.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libeigen3-dev (>= 3.3)")
list(REMOVE_DUPLICATES MEDSPRING_DEB_RECOMMENDS)
list(JOIN MEDSPRING_DEB_RECOMMENDS ", " CPACK_DEBIAN_DEV_PACKAGE_RECOMMENDS)

set(CPACK_DEBIAN_CLI_PACKAGE_NAME medspring)
set(CPACK_DEBIAN_CLI_PACKAGE_SECTION science)
set(CPACK_COMPONENT_CLI_DESCRIPTION "MedSpring command line: real-time soft-tissue simulation
 demo, bench, info, build, run, paper, haptics, export, view, study, accuracy and calibrate,
 with the bundled scenes and bash completion.")
set(CPACK_DEBIAN_CLI_PACKAGE_SHLIBDEPS ON)  # Depends: from dpkg-shlibdeps (VTK, CGAL's gmp/mpfr, libstdc++)
# `medspring paper` renders its figures with python3-vtk9 and matplotlib under xvfb-run.
set(CPACK_DEBIAN_CLI_PACKAGE_RECOMMENDS "python3, python3-vtk9, python3-matplotlib, xvfb, xauth")

if(BUILD_SHARED_LIBS)
  set(MEDSPRING_DEB_LIBS_PACKAGE libmedspring${MEDSPRING_SOVERSION})
  list(APPEND CPACK_COMPONENTS_ALL libs)
  set(CPACK_DEBIAN_LIBS_PACKAGE_NAME ${MEDSPRING_DEB_LIBS_PACKAGE})
  set(CPACK_DEBIAN_LIBS_PACKAGE_SECTION libs)
  set(CPACK_DEBIAN_LIBS_PACKAGE_SHLIBDEPS ON)
  set(CPACK_COMPONENT_LIBS_DESCRIPTION "MedSpring shared libraries")
  string(APPEND CPACK_DEBIAN_DEV_PACKAGE_DEPENDS ", ${MEDSPRING_DEB_LIBS_PACKAGE} (= ${PROJECT_VERSION})")
  set(CPACK_DEBIAN_CLI_PACKAGE_DEPENDS "${MEDSPRING_DEB_LIBS_PACKAGE} (= ${PROJECT_VERSION})")
  # dpkg-shlibdeps looks for MedSpring's own libraries in the build tree (they belong to no package yet).
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS "")
  get_property(targets GLOBAL PROPERTY MEDSPRING_INSTALLED_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(dir ${target} BINARY_DIR)
    list(APPEND CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${dir})
  endforeach()
endif()

include(CPack)
