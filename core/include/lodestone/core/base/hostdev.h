#pragma once
// LODESTONE_HOSTDEV marks small physics functions (the Langevin law, B-spline
// weights, stresses) that are compiled for the CPU and, by nvcc, for the GPU.
// Written once, used by both backends.
#if defined(__CUDACC__)
#define LODESTONE_HOSTDEV __host__ __device__
#else
#define LODESTONE_HOSTDEV
#endif
