#pragma once
// MTLED_HOST_DEVICE marks a function that is compiled for the host and, in CUDA code, for the device as well: the
// arithmetic the CPU and a GPU backend share is written once (the laws, mtled/law/; the explicit update,
// mtled/update_arithmetic.hpp).
#ifdef __CUDACC__
#define MTLED_HOST_DEVICE __host__ __device__
#else
#define MTLED_HOST_DEVICE
#endif
