#pragma once
// The contract between a GPU backend and a material's code for the device (device_stress_pass.cuh): the backend
// keeps one record of kDeviceRecord doubles per integration point on the device, F - I in its first 9 (row by row)
// before the stress pass and w P = w F S after it; a law's stress pass fills the records of its own points.
#include <cstdint>

namespace mtled {

constexpr int kDeviceRecord = 10;  // 9 used, one zero: 80 bytes, 16-byte aligned

// One stress pass, every pointer in device memory.
struct DeviceStressPass {
  std::int64_t points = 0;                  // integration points of the model
  const double* weight = nullptr;           // each point's integration weight w
  const std::uint16_t* material = nullptr;  // each point's material, an index the backend gave
  std::uint16_t material_index = 0;         // the points this pass computes: material[p] == material_index
  double* records = nullptr;                // points x kDeviceRecord
  int* first_bad = nullptr;                 // atomicMin of the refused points' indices
  int device = 0;                           // the CUDA device
  void* stream = nullptr;                   // the cudaStream_t the pass is queued on
};

// A law's device code, as the material plugin exports it (Material::device_law): `stress_pass` queues the pass on
// its stream with the law's constants `law` and returns its launch's cudaError_t (0: queued). Empty where the plugin
// was built without CUDA.
struct DeviceLaw {
  int (*stress_pass)(const void* law, const DeviceStressPass& pass) = nullptr;
  const void* law = nullptr;
};

}  // namespace mtled
