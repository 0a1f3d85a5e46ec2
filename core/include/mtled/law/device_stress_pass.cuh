#pragma once
// A law's stress pass on an NVIDIA GPU, from its single source (arithmetic-inl.h with T = double, compiled as device
// code): one thread per integration point of the law's material. A material plugin built with CUDA has one .cu file
// for its law `MyLaw` (header my_law-inl.h):
//
//   #include "mtled/law/device_stress_pass.cuh"
//   #include "my_law-inl.h"
//   MTLED_LAW_DEVICE_STRESS_PASS(MyLaw, my_law_device_stress_pass)
//
// and its Material::device_law() returns {&my_law_device_stress_pass, &law_}.
#include <cuda_runtime.h>

#include "mtled/law/stress_record.hpp"

namespace mtled::scalar {

// Record p holds F - I; it gets w P = w F S (stress_record.hpp), or zeros and first_bad where F or S is
// inadmissible.
template <class Law>
__global__ void law_stress_pass(Law law, DeviceStressPass pass) {
  const std::int64_t p = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= pass.points || pass.material[p] != pass.material_index) return;
  if (!stress_record(law, pass.weight[p], pass.records + kDeviceRecord * p))
    atomicMin(pass.first_bad, static_cast<int>(p));
}

// The plugin's CUDA runtime is its own (statically linked): it learns the backend's device here, and reports its
// launch's error to the backend.
template <class Law>
int launch_law_stress_pass(const void* law, const DeviceStressPass& pass) {
  constexpr int kThreads = 256;
  const auto blocks = static_cast<unsigned>((pass.points + kThreads - 1) / kThreads);
  if (blocks == 0) return 0;
  if (const cudaError_t error = cudaSetDevice(pass.device); error != cudaSuccess) return static_cast<int>(error);
  law_stress_pass<Law><<<blocks, kThreads, 0, static_cast<cudaStream_t>(pass.stream)>>>(*static_cast<const Law*>(law),
                                                                                          pass);
  return static_cast<int>(cudaGetLastError());
}

}  // namespace mtled::scalar

// Defines mtled::function(const void* law, const DeviceStressPass&), the law's DeviceLaw::stress_pass.
#define MTLED_LAW_DEVICE_STRESS_PASS(Law, function)                \
  namespace mtled {                                                \
  int function(const void* law, const DeviceStressPass& pass) {    \
    return scalar::launch_law_stress_pass<Law>(law, pass);         \
  }                                                                \
  }
