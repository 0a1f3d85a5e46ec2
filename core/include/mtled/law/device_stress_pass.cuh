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

#include "mtled/law/arithmetic-inl.h"
#include "mtled/law/device_stress_pass.hpp"

namespace mtled::scalar {

// Record p holds F - I; it gets w P = w F S, or zeros and first_bad where F or S is inadmissible.
template <class Law>
__global__ void law_stress_pass(Law law, DeviceStressPass pass) {
  const std::int64_t p = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= pass.points || pass.material[p] != pass.material_index) return;
  double* record = pass.records + kDeviceRecord * p;
  Matrix3<double> F;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) F.m[i][k] = i == k ? 1.0 + record[3 * i + k] : record[3 * i + k];
  const LawStress<double> result = evaluate_stress(law, F);
  if (!result.admissible) {
    for (int c = 0; c < kDeviceRecord; ++c) record[c] = 0.0;
    atomicMin(pass.first_bad, static_cast<int>(p));
    return;
  }
  double S[3][3];  // the whole of S from its upper triangle
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) S[i][j] = i <= j ? result.S.m[i][j] : result.S.m[j][i];
  const double w = pass.weight[p];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) record[3 * i + j] = w * (F.m[i][0] * S[0][j] + F.m[i][1] * S[1][j] + F.m[i][2] * S[2][j]);
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
