// The CUDA backend's kernels (kernels.hpp). The forces in three launches: F at each point (a slice of 32 points per
// block, its rows shared by the block's warps), the stresses (each material's law, compiled into its own plugin:
// Material::device_law), the node-centric sum of the forces (a slice of 32 nodes per block); one thread per node for
// the update (the CPU's explicit_update arithmetic, update_arithmetic.hpp); fixed grids with tree reductions in
// shared memory for the sums.
#include <cfloat>
#include <climits>
#include <cmath>

#include "kernels.hpp"
#include "mtled/update_arithmetic.hpp"

namespace mtled::cuda {
namespace {

constexpr int kThreads = 256;

int blocks_for(std::int64_t n) { return static_cast<int>((n + kThreads - 1) / kThreads); }

// ---- the force kernel -------------------------------------------------------------------------------------------
// The gradient and node passes. A block takes one slice, its rows shared by Parts warps, warp w taking entries w, w + Parts, ...:
// each thread's chain of dependent loads is Parts times shorter than a whole row's, and the slices' hundreds of
// blocks reach every multiprocessor (a warp per slice left most of the GPU idle on the default scene: its 7,502 nodes
// were 30 blocks, each thread walking about 200 entries one after the other; on an H100 the node pass went from 335
// to 46 us). The warps' partial sums are added in warp order, so every run adds in the same order.

constexpr int kPointParts = 4;  // a point's row: about 40 entries
constexpr int kNodeParts = 16;  // a node's row: about 200
constexpr int kPointThreads = kPointParts * kSlice, kNodeThreads = kNodeParts * kSlice;

// Sums `Values` values per lane over the slice's Parts warps in warp order; true in warp 0, which holds the sums.
template <int Parts, int Values>
__device__ bool add_parts(double (&mine)[Values]) {
  __shared__ double parts[Values][Parts][kSlice];
  const int lane = threadIdx.x % kSlice, part = threadIdx.x / kSlice;
  for (int v = 0; v < Values; ++v) parts[v][part][lane] = mine[v];
  __syncthreads();
  if (part != 0) return false;
  for (int v = 0; v < Values; ++v) {
    double sum = parts[v][0][lane];
    for (int w = 1; w < Parts; ++w) sum += parts[v][w][lane];
    mine[v] = sum;
  }
  return true;
}

// F - I = sum u_I (x) grad N_I of each point into its record's first 9 doubles.
template <class Real>
__global__ void __launch_bounds__(kPointThreads) gradient_pass(PointPass<Real> a) {
  const std::int64_t slice = blockIdx.x;
  const int lane = threadIdx.x % kSlice, part = threadIdx.x / kSlice;
  const std::int64_t end = a.rows.slice_begin[slice + 1];
  double sum[9] = {};
  for (std::int64_t e = a.rows.slice_begin[slice] + part * kSlice + lane; e < end; e += kPointThreads) {
    const std::int64_t node = a.rows.column[e];
    const double g[3] = {static_cast<double>(a.rows.gx[e]), static_cast<double>(a.rows.gy[e]),
                         static_cast<double>(a.rows.gz[e])};
    const double2 xy = *reinterpret_cast<const double2*>(a.u4 + 4 * node);
    const double u[3] = {xy.x, xy.y, a.u4[4 * node + 2]};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) sum[3 * i + k] = fma(u[i], g[k], sum[3 * i + k]);
  }
  const std::int64_t p = slice * kSlice + lane;
  if (!add_parts<kPointParts>(sum) || p >= a.rows.rows) return;
  double* record = a.records + kDeviceRecord * p;
  for (int c = 0; c < 9; ++c) record[c] = sum[c];
}

// f_I = sum over node I's points of (w F S) t_pI.
template <class Real>
__global__ void __launch_bounds__(kNodeThreads) node_pass(NodePass<Real> a) {
  const std::int64_t slice = blockIdx.x;
  const int lane = threadIdx.x % kSlice, part = threadIdx.x / kSlice;
  const std::int64_t end = a.rows.slice_begin[slice + 1];
  double f[3] = {0.0, 0.0, 0.0};
  for (std::int64_t e = a.rows.slice_begin[slice] + part * kSlice + lane; e < end; e += kNodeThreads) {
    const double* record = a.records + kDeviceRecord * static_cast<std::int64_t>(a.rows.column[e]);
    const double t[3] = {static_cast<double>(a.rows.gx[e]), static_cast<double>(a.rows.gy[e]),
                         static_cast<double>(a.rows.gz[e])};
    const double2 p0 = *reinterpret_cast<const double2*>(record);      // P00 P01
    const double2 p1 = *reinterpret_cast<const double2*>(record + 2);  // P02 P10
    const double2 p2 = *reinterpret_cast<const double2*>(record + 4);  // P11 P12
    const double2 p3 = *reinterpret_cast<const double2*>(record + 6);  // P20 P21
    const double p22 = record[8];
    f[0] = fma(p0.x, t[0], fma(p0.y, t[1], fma(p1.x, t[2], f[0])));
    f[1] = fma(p1.y, t[0], fma(p2.x, t[1], fma(p2.y, t[2], f[1])));
    f[2] = fma(p3.x, t[0], fma(p3.y, t[1], fma(p22, t[2], f[2])));
  }
  if (!add_parts<kNodeParts>(f)) return;
  const std::int32_t node = a.rows.row[slice * kSlice + lane];
  if (node < 0) return;
  double* out = a.f4 + 4 * static_cast<std::int64_t>(node);
  out[0] = f[0];
  out[1] = f[1];
  out[2] = f[2];
}

// ---- the update and the sums ------------------------------------------------------------------------------------

__global__ void predict_kernel(std::int32_t nodes, const double* u, const double* u_previous, const double* f,
                               const double* f_previous, const double* f_ext, const double* mass, double alpha,
                               double beta, double gamma, double* prediction, double* free,
                               unsigned long long* first_non_finite) {
  const std::int64_t i = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= nodes) return;
  const double step = alpha / mass[i];
  for (int c = 0; c < 3; ++c) {
    const std::int64_t d = 4 * i + c;
    const double value = updated_unknown(d, u, u_previous, f_ext, f, f_previous, step, beta, gamma);
    prediction[d] = value;
    free[d] = value;
    if (!isfinite(value)) atomicMin(first_non_finite, static_cast<unsigned long long>(3 * i + c));
  }
}

// Reduces `Values` values over the threads of a block in a fixed tree (shared memory); the results are valid on
// thread 0. Each thread first reduces its grid-stride share in index order, and a second one-block launch reduces the
// blocks' partials the same way: the same order on every run.
template <int Values, class Reduce>
__device__ void block_reduce(double (&mine)[Values], Reduce reduce) {
  __shared__ double shared[Values][kReduceThreads];
  for (int v = 0; v < Values; ++v) shared[v][threadIdx.x] = mine[v];
  __syncthreads();
  for (int stride = kReduceThreads / 2; stride > 0; stride /= 2) {
    if (threadIdx.x < stride)
      for (int v = 0; v < Values; ++v)
        shared[v][threadIdx.x] = reduce(v, shared[v][threadIdx.x], shared[v][threadIdx.x + stride]);
    __syncthreads();
  }
  for (int v = 0; v < Values; ++v) mine[v] = shared[v][0];
  __syncthreads();
}

struct AddAll {
  __device__ double operator()(int, double a, double b) const { return a + b; }
};

__global__ void increment_partials(std::int32_t nodes, const double* u, const double* u_previous, const double* f,
                                   const double* f_previous, const double* mass, double* partials) {
  double mine[2] = {0.0, 0.0};
  for (std::int64_t i = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < nodes;
       i += static_cast<std::int64_t>(gridDim.x) * blockDim.x)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t d = 4 * i + c;
      const double du = u[d] - u_previous[d];
      mine[0] += du * (f[d] - f_previous[d]);
      mine[1] += du * du * mass[i];
    }
  block_reduce<2>(mine, AddAll{});
  if (threadIdx.x == 0) {
    partials[blockIdx.x] = mine[0];
    partials[kReduceBlocks + blockIdx.x] = mine[1];
  }
}

__global__ void increment_finish(const double* partials, IncrementSumsDevice* out) {
  double mine[2] = {partials[threadIdx.x], partials[kReduceBlocks + threadIdx.x]};
  block_reduce<2>(mine, AddAll{});
  if (threadIdx.x == 0) *out = {mine[0], mine[1]};
}

// Values: 0 largest increment, 1 largest displacement, 2 projection energy, 3 kinetic product, 4 the fastest node's
// |m product|, 5 the fastest node (as a double: exact below 2^53), 6 the largest residual step. StepReduce reduces
// the sums 0-3 and 6 (at 4 of its array).
struct StepReduce {
  __device__ double operator()(int v, double a, double b) const { return v <= 1 || v == 4 ? fmax(a, b) : a + b; }
};

__device__ void fastest_of(double& energy, double& node, double other_energy, double other_node) {
  if (other_energy > energy || (other_energy == energy && other_node < node)) {
    energy = other_energy;
    node = other_node;
  }
}

template <int Values>
__device__ void fastest_reduce(double (&mine)[Values]) {
  __shared__ double energy[kReduceThreads], node[kReduceThreads];
  energy[threadIdx.x] = mine[4];
  node[threadIdx.x] = mine[5];
  __syncthreads();
  for (int stride = kReduceThreads / 2; stride > 0; stride /= 2) {
    if (threadIdx.x < stride) fastest_of(energy[threadIdx.x], node[threadIdx.x], energy[threadIdx.x + stride], node[threadIdx.x + stride]);
    __syncthreads();
  }
  mine[4] = energy[0];
  mine[5] = node[0];
  __syncthreads();
}

__global__ void step_partials(std::int32_t nodes, const double* prediction, const double* free, const double* u,
                              const double* u_previous, const double* mass, double beta, double* partials) {
  double mine[kStepPartials] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (std::int64_t i = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < nodes;
       i += static_cast<std::int64_t>(gridDim.x) * blockDim.x) {
    double added = 0.0, product = 0.0;
    for (int c = 0; c < 3; ++c) {
      const std::int64_t d = 4 * i + c;
      const double after = prediction[d] - u[d], before = free[d] - u[d];
      added += fmax(0.0, after * after - before * before);
      product += (u[d] - u_previous[d]) * after;
      mine[0] = fmax(mine[0], fabs(after));
      mine[1] = fmax(mine[1], fabs(prediction[d]));
      mine[6] = fmax(mine[6], fabs(after - beta * (u[d] - u_previous[d])));
    }
    mine[2] += mass[i] * added;
    const double e = mass[i] * product;
    mine[3] += e;
    fastest_of(mine[4], mine[5], fabs(e), static_cast<double>(i));
  }
  fastest_reduce(mine);
  double sums[5] = {mine[0], mine[1], mine[2], mine[3], mine[6]};
  block_reduce<5>(sums, StepReduce{});
  if (threadIdx.x == 0) {
    for (int v = 0; v < 4; ++v) partials[v * kReduceBlocks + blockIdx.x] = sums[v];
    partials[4 * kReduceBlocks + blockIdx.x] = mine[4];
    partials[5 * kReduceBlocks + blockIdx.x] = mine[5];
    partials[6 * kReduceBlocks + blockIdx.x] = sums[4];
  }
}

__global__ void step_finish(const double* partials, StepSumsDevice* out) {
  double mine[kStepPartials];
  for (int v = 0; v < kStepPartials; ++v) mine[v] = partials[v * kReduceBlocks + threadIdx.x];
  fastest_reduce(mine);
  double sums[5] = {mine[0], mine[1], mine[2], mine[3], mine[6]};
  block_reduce<5>(sums, StepReduce{});
  if (threadIdx.x == 0) *out = {sums[0], sums[1], sums[2], sums[3], mine[4], static_cast<long long>(mine[5]), sums[4]};
}

// ---- layouts ----------------------------------------------------------------------------------------------------

__global__ void pack_kernel(std::int32_t nodes, const double* v4, double* v3) {
  const std::int64_t d = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (d < 3 * static_cast<std::int64_t>(nodes)) v3[d] = v4[4 * (d / 3) + d % 3];
}

__global__ void unpack_kernel(std::int32_t nodes, const double* v3, double* v4) {
  const std::int64_t d = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (d < 3 * static_cast<std::int64_t>(nodes)) v4[4 * (d / 3) + d % 3] = v3[d];
}

__global__ void gather_kernel(std::int32_t count, const std::int32_t* nodes, const double* v4, double* v3) {
  const std::int64_t d = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (d < 3 * static_cast<std::int64_t>(count)) v3[d] = v4[4 * static_cast<std::int64_t>(nodes[d / 3]) + d % 3];
}

// ---- the constraint projection's products -------------------------------------------------------------------------

__global__ void constrained_values_kernel(ConstraintView b, const double* v, double* out) {
  const std::int64_t r = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (r >= b.rows) return;
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::int64_t e = b.row_offsets[r]; e < b.row_offsets[r + 1]; ++e) {
    const double* vi = v + 4 * static_cast<std::int64_t>(b.row_nodes[e]);
    for (int j = 0; j < b.k; ++j) sum[j] += b.row_values[e] * vi[b.components[j]];
  }
  for (int j = 0; j < b.k; ++j) out[b.k * r + j] = sum[j];
}

__global__ void add_correction_kernel(ConstraintView b, const double* y, double* v) {
  const std::int64_t n = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (n >= b.nodes) return;
  double sum[3] = {0.0, 0.0, 0.0};
  for (std::int64_t e = b.node_offsets[n]; e < b.node_offsets[n + 1]; ++e) {
    const double* yr = y + b.k * static_cast<std::int64_t>(b.node_rows[e]);
    for (int j = 0; j < b.k; ++j) sum[j] += b.node_values[e] * yr[j];
  }
  double* vn = v + 4 * static_cast<std::int64_t>(b.node_list[n]);
  for (int j = 0; j < b.k; ++j) vn[b.components[j]] += sum[j];
}

}  // namespace

template <class Real>
void deformation_gradients(const PointPass<Real>& points, cudaStream_t stream) {
  const std::int64_t point_slices = (points.rows.rows + kSlice - 1) / kSlice;
  if (point_slices > 0) gradient_pass<Real><<<static_cast<int>(point_slices), kPointThreads, 0, stream>>>(points);
}
template void deformation_gradients<float>(const PointPass<float>&, cudaStream_t);
template void deformation_gradients<double>(const PointPass<double>&, cudaStream_t);

template <class Real>
void nodal_forces(const NodePass<Real>& nodes, cudaStream_t stream) {
  const std::int64_t node_slices = (nodes.rows.rows + kSlice - 1) / kSlice;
  if (node_slices > 0) node_pass<Real><<<static_cast<int>(node_slices), kNodeThreads, 0, stream>>>(nodes);
}
template void nodal_forces<float>(const NodePass<float>&, cudaStream_t);
template void nodal_forces<double>(const NodePass<double>&, cudaStream_t);

void predict(std::int32_t nodes, const double* u4, const double* u_previous4, const double* f4,
             const double* f_previous4, const double* f_ext4, const double* mass, double alpha, double beta,
             double gamma, double* prediction4, double* free4, unsigned long long* first_non_finite,
             cudaStream_t stream) {
  predict_kernel<<<blocks_for(nodes), kThreads, 0, stream>>>(nodes, u4, u_previous4, f4, f_previous4, f_ext4, mass,
                                                             alpha, beta, gamma, prediction4, free4, first_non_finite);
}

void increment_sums(std::int32_t nodes, const double* u4, const double* u_previous4, const double* f4,
                    const double* f_previous4, const double* mass, double* partials, IncrementSumsDevice* out,
                    cudaStream_t stream) {
  increment_partials<<<kReduceBlocks, kReduceThreads, 0, stream>>>(nodes, u4, u_previous4, f4, f_previous4, mass,
                                                                    partials);
  increment_finish<<<1, kReduceThreads, 0, stream>>>(partials, out);
}

void step_sums(std::int32_t nodes, const double* prediction4, const double* free4, const double* u4,
               const double* u_previous4, const double* mass, double beta, double* partials, StepSumsDevice* out,
               cudaStream_t stream) {
  step_partials<<<kReduceBlocks, kReduceThreads, 0, stream>>>(nodes, prediction4, free4, u4, u_previous4, mass, beta,
                                                              partials);
  step_finish<<<1, kReduceThreads, 0, stream>>>(partials, out);
}

void pack(std::int32_t nodes, const double* v4, double* v3, cudaStream_t stream) {
  if (nodes > 0) pack_kernel<<<blocks_for(3 * static_cast<std::int64_t>(nodes)), kThreads, 0, stream>>>(nodes, v4, v3);
}

void unpack(std::int32_t nodes, const double* v3, double* v4, cudaStream_t stream) {
  if (nodes > 0) unpack_kernel<<<blocks_for(3 * static_cast<std::int64_t>(nodes)), kThreads, 0, stream>>>(nodes, v3, v4);
}

void gather(std::int32_t count, const std::int32_t* nodes, const double* v4, double* v3, cudaStream_t stream) {
  if (count > 0)
    gather_kernel<<<blocks_for(3 * static_cast<std::int64_t>(count)), kThreads, 0, stream>>>(count, nodes, v4, v3);
}

void constrained_values(const ConstraintView& block, const double* v4, double* out, cudaStream_t stream) {
  if (block.rows > 0) constrained_values_kernel<<<blocks_for(block.rows), kThreads, 0, stream>>>(block, v4, out);
}

void add_correction(const ConstraintView& block, const double* y, double* v4, cudaStream_t stream) {
  if (block.nodes > 0) add_correction_kernel<<<blocks_for(block.nodes), kThreads, 0, stream>>>(block, y, v4);
}

}  // namespace mtled::cuda
