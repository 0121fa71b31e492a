// MEDSPRING_HD marks a function that is compiled for the CPU and, under nvcc, for the GPU too
// (`__host__ __device__`): the physics of one node and one spring is written once (physics/kernels.hpp)
// and used by the CPU step and the CUDA kernels (src/gpu, docs/gpu.md). Outside nvcc it is empty.
#pragma once

#if defined(__CUDACC__)
#define MEDSPRING_HD __host__ __device__
#else
#define MEDSPRING_HD
#endif
