# MEDSPRING_CUDA: the CUDA backend (src/gpu, docs/gpu.md). AUTO (default) builds it when a CUDA compiler
# is found by check_language(CUDA) (nvcc on PATH, $CUDACXX, or /usr/local/cuda/bin/nvcc); ON requires
# one; OFF never builds it. AUTO is off in sanitizer/fuzz builds. Sets MEDSPRING_HAS_CUDA. Kernels are built for CMAKE_CUDA_ARCHITECTURES
# (default 90: H100/H200).
set(MEDSPRING_CUDA AUTO CACHE STRING "Build the CUDA backend (src/gpu): AUTO, ON or OFF")
set_property(CACHE MEDSPRING_CUDA PROPERTY STRINGS AUTO ON OFF)
set(MEDSPRING_HAS_CUDA OFF)
# AUTO stays off in sanitizer and fuzz builds: nvcc's objects and the CUDA runtime are not instrumented.
if(MEDSPRING_CUDA STREQUAL "AUTO" AND (MEDSPRING_SANITIZE OR MEDSPRING_FUZZ))
  message(STATUS "MedSpring: CUDA backend OFF (AUTO in a sanitizer/fuzz build)")
elseif(NOT MEDSPRING_CUDA STREQUAL "OFF" AND NOT EMSCRIPTEN)
  if(NOT CMAKE_CUDA_COMPILER AND NOT DEFINED ENV{CUDACXX} AND EXISTS /usr/local/cuda/bin/nvcc)
    find_program(_medspring_nvcc nvcc)
    if(NOT _medspring_nvcc)
      set(ENV{CUDACXX} /usr/local/cuda/bin/nvcc)
    endif()
  endif()
  include(CheckLanguage)
  check_language(CUDA)
  if(CMAKE_CUDA_COMPILER)
    if(NOT DEFINED CMAKE_CUDA_ARCHITECTURES)
      set(CMAKE_CUDA_ARCHITECTURES 90)
    endif()
    enable_language(CUDA)
    set(MEDSPRING_HAS_CUDA ON)
    message(STATUS "MedSpring: CUDA backend ON (${CMAKE_CUDA_COMPILER}, architectures ${CMAKE_CUDA_ARCHITECTURES})")
  elseif(MEDSPRING_CUDA STREQUAL "ON")
    message(FATAL_ERROR "MEDSPRING_CUDA=ON but no CUDA compiler was found: install the CUDA toolkit "
      "(Debian non-free: nvidia-cuda-toolkit), set CUDACXX=/path/to/nvcc, or configure with -DMEDSPRING_CUDA=OFF")
  else()
    message(STATUS "MedSpring: CUDA backend OFF (no CUDA compiler found; MEDSPRING_CUDA=AUTO)")
  endif()
endif()
