#pragma once
// The CUDA backend's kernels (kernels.cu), called from the host engine (cuda_backend.cpp) with device pointers.
// Device vectors of nodal values hold 4 doubles per node (x, y, z, 0) plus a zero sink node at the end; the stress
// records hold kDeviceRecord doubles per integration point (mtled/law/device_stress_pass.hpp: F - I, then w F S) plus
// a zero sink record. Every reduction runs over a fixed
// grid in a fixed order, so a result is the same on every run (no floating-point atomics).
#include <cuda_runtime.h>

#include <cstdint>

#include "mtled/law/device_stress_pass.hpp"
#include "sliced_rows.hpp"

namespace mtled::cuda {

// Device pointers of one pass's sliced rows (SlicedRows).
template <class Real>
struct SlicedView {
  const std::int64_t* slice_begin = nullptr;
  const std::int32_t* column = nullptr;
  const Real* gx = nullptr;
  const Real* gy = nullptr;
  const Real* gz = nullptr;
  const std::int32_t* row = nullptr;  // the node pass's lane -> node
  std::int64_t rows = 0;
};

template <class Real>
struct PointPass {
  SlicedView<Real> rows;
  const double* u4 = nullptr;  // the displacements evaluated
  double* records = nullptr;
};

template <class Real>
struct NodePass {
  SlicedView<Real> rows;
  const double* records = nullptr;
  double* f4 = nullptr;
};

// f = f_int(u) in three steps on `stream`: F - I at the points into their records, the stresses (each material's
// DeviceLaw, queued by the host), the nodes' sums of the records.
template <class Real>
void deformation_gradients(const PointPass<Real>& points, cudaStream_t stream);
template <class Real>
void nodal_forces(const NodePass<Real>& nodes, cudaStream_t stream);

// pred = u + beta (u - u_prev) + alpha M^-1 (f_ext - f - gamma (f - f_prev)) (f_ext null: none; f_prev read only
// where gamma != 0), free = pred; first_non_finite gets the lowest unknown (3 node + component) of pred that is not
// finite.
void predict(std::int32_t nodes, const double* u4, const double* u_previous4, const double* f4,
             const double* f_previous4, const double* f_ext4, const double* mass, double alpha, double beta,
             double gamma, double* prediction4, double* free4, unsigned long long* first_non_finite,
             cudaStream_t stream);

// What the host reads back of the reductions (one copy per call).
struct IncrementSumsDevice {
  double stiffness, inertia;
};
// A force evaluation's one read-back: its sums and its first inadmissible point (INT_MAX-ish 0x7f7f7f7f: none).
struct EvaluationDevice {
  IncrementSumsDevice sums;
  int first_bad;
};
struct StepSumsDevice {
  double largest_increment, largest_displacement, projection_energy, kinetic_product, fastest_energy;
  long long fastest_node;
  double largest_residual_step;
};
constexpr int kReduceBlocks = 256;
constexpr int kReduceThreads = 256;

// du.(f - f_prev), du.M du with du = u - u_prev, into *out (device), partials: 2 kReduceBlocks doubles of scratch.
void increment_sums(std::int32_t nodes, const double* u4, const double* u_previous4, const double* f4,
                    const double* f_previous4, const double* mass, double* partials, IncrementSumsDevice* out,
                    cudaStream_t stream);
// The step's sums (StepSums) of pred (after the projection), free (before it), u and u_prev, with the update's beta,
// into *out (device); partials: kStepPartials kReduceBlocks doubles of scratch.
constexpr int kStepPartials = 7;
void step_sums(std::int32_t nodes, const double* prediction4, const double* free4, const double* u4,
               const double* u_previous4, const double* mass, double beta, double* partials, StepSumsDevice* out,
               cudaStream_t stream);

// Between the host's 3 doubles per node and the device's 4: v3 (contiguous, copied in one transfer) to or from v4.
void pack(std::int32_t nodes, const double* v4, double* v3, cudaStream_t stream);
void unpack(std::int32_t nodes, const double* v3, double* v4, cudaStream_t stream);
// v3 = the 3 components of v4 at `nodes` (count of them), in list order.
void gather(std::int32_t count, const std::int32_t* nodes, const double* v4, double* v3, cudaStream_t stream);

// The constraint projection's two products for one block (ConstraintBlock, on the device): out = Phi v (rows x k,
// the components interleaved) and v += M^-1 Phi^T y.
struct ConstraintView {
  std::int64_t rows = 0, nodes = 0;
  int components[3] = {0, 0, 0};
  int k = 0;
  const std::int64_t* row_offsets = nullptr;
  const std::int32_t* row_nodes = nullptr;
  const double* row_values = nullptr;
  const std::int32_t* node_list = nullptr;
  const std::int64_t* node_offsets = nullptr;
  const std::int32_t* node_rows = nullptr;
  const double* node_values = nullptr;
};
void constrained_values(const ConstraintView& block, const double* v4, double* out, cudaStream_t stream);
void add_correction(const ConstraintView& block, const double* y, double* v4, cudaStream_t stream);

}  // namespace mtled::cuda
