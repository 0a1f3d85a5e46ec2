// The CUDA backend's kernels (kernels.hpp). The forces in three launches: F at each point (a slice of 32 points per
// block, its rows shared by the block's warps), the stress and its record (one thread per point), the node-centric
// sum of the forces (a slice of 32 nodes per block); one thread per node for the update; fixed grids with tree
// reductions in shared memory for the sums. The laws are the arithmetic of the CPU's stress_batch() (Ogden:
// principal stretches by the closed-form eigensolver of symmetric_eigen3.hpp; neo-Hookean: C^-1 from adj(F)), so
// double-precision runs agree with the CPU to round-off.
#include <cfloat>
#include <climits>
#include <cmath>

#include "kernels.hpp"

namespace mtled::cuda {
namespace {

constexpr int kThreads = 256;

int blocks_for(std::int64_t n) { return static_cast<int>((n + kThreads - 1) / kThreads); }

// ---- the laws -------------------------------------------------------------------------------------------------

__device__ double determinant(const double (&m)[3][3]) {
  return m[0][0] * (m[1][1] * m[2][2] - m[2][1] * m[1][2]) - m[1][0] * (m[0][1] * m[2][2] - m[2][1] * m[0][2]) +
         m[2][0] * (m[0][1] * m[1][2] - m[1][1] * m[0][2]);
}

__device__ void cross(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
__device__ double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
// B v for a symmetric B.
__device__ void times(const double (&B)[3][3], const double* v, double* out) {
  for (int i = 0; i < 3; ++i) out[i] = B[i][0] * v[0] + B[i][1] * v[1] + B[i][2] * v[2];
}

// The eigen decomposition of a symmetric 3x3 matrix (symmetric_eigen3.hpp, Scherzinger & Dohrmann, CMAME 197
// (2008) 4007): the eigenvalue farthest from the others from the characteristic cubic, its vector from the best
// conditioned cross product, the other two by one Jacobi rotation. values[i] belongs to the column vectors[.][i].
__device__ void symmetric_eigen3(const double (&A)[3][3], double (&values)[3], double (&vectors)[3][3]) {
  const double mean = (A[0][0] + A[1][1] + A[2][2]) / 3.0;
  double B[3][3];
  double scale = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      B[i][j] = A[i][j] - (i == j ? mean : 0.0);
      scale = fmax(scale, fabs(B[i][j]));
    }
  if (!(scale > 0.0)) {
    for (int i = 0; i < 3; ++i) {
      values[i] = mean;
      for (int j = 0; j < 3; ++j) vectors[i][j] = i == j ? 1.0 : 0.0;
    }
    return;
  }
  for (auto& row : B)
    for (double& b : row) b /= scale;
  const double j2 = 0.5 * (B[0][0] * B[0][0] + B[1][1] * B[1][1] + B[2][2] * B[2][2]) + B[0][1] * B[0][1] +
                    B[0][2] * B[0][2] + B[1][2] * B[1][2];
  const double rho = 2.0 * sqrt(j2 / 3.0);
  const double cos_3theta = fmin(1.0, fmax(-1.0, 4.0 * determinant(B) / (rho * rho * rho)));
  const double theta = acos(cos_3theta) / 3.0;
  const double eta = theta < M_PI / 6.0 ? rho * cos(theta) : rho * cos(theta + 2.0 * M_PI / 3.0);
  const double r0[3] = {B[0][0] - eta, B[0][1], B[0][2]};
  const double r1[3] = {B[1][0], B[1][1] - eta, B[1][2]};
  const double r2[3] = {B[2][0], B[2][1], B[2][2] - eta};
  double c01[3], c02[3], c12[3];
  cross(r0, r1, c01);
  cross(r0, r2, c02);
  cross(r1, r2, c12);
  const double n01 = dot(c01, c01), n02 = dot(c02, c02), n12 = dot(c12, c12);
  // Chosen by value, not through a pointer to one of the three: that would put them in local memory.
  const bool first = n01 >= n02 && n01 >= n12, second = !first && n02 >= n12;
  const double norm = first ? n01 : second ? n02 : n12;
  const double inverse = 1.0 / sqrt(norm);
  double v1[3];
  for (int i = 0; i < 3; ++i) v1[i] = (first ? c01[i] : second ? c02[i] : c12[i]) * inverse;
  double u[3];
  if (fabs(v1[0]) > fabs(v1[1])) {
    u[0] = -v1[2], u[1] = 0.0, u[2] = v1[0];
  } else {
    u[0] = 0.0, u[1] = v1[2], u[2] = -v1[1];
  }
  const double u_inverse = 1.0 / sqrt(dot(u, u));
  for (double& x : u) x *= u_inverse;
  double w[3], Bu[3], Bw[3], Bv[3];
  cross(v1, u, w);
  times(B, u, Bu);
  times(B, w, Bw);
  const double b_uu = dot(u, Bu), b_uw = dot(u, Bw), b_ww = dot(w, Bw);
  double eta2 = b_uu, eta3 = b_ww, v2[3], v3[3];
  for (int i = 0; i < 3; ++i) v2[i] = u[i], v3[i] = w[i];
  if (b_uw != 0.0) {
    const double tau = (b_ww - b_uu) / (2.0 * b_uw);
    const double t = copysign(1.0, tau) / (fabs(tau) + sqrt(1.0 + tau * tau));
    const double c = 1.0 / sqrt(1.0 + t * t), s = t * c;
    eta2 = b_uu - t * b_uw;
    eta3 = b_ww + t * b_uw;
    for (int i = 0; i < 3; ++i) {
      v2[i] = c * u[i] - s * w[i];
      v3[i] = s * u[i] + c * w[i];
    }
  }
  times(B, v1, Bv);
  const double eta1 = dot(v1, Bv);
  values[0] = eta1 * scale + mean;
  values[1] = eta2 * scale + mean;
  values[2] = eta3 * scale + mean;
  for (int i = 0; i < 3; ++i) {
    vectors[i][0] = v1[i];
    vectors[i][1] = v2[i];
    vectors[i][2] = v3[i];
  }
}

// S (symmetric, full) of F, false where F or S is inadmissible (J <= 0, anything not finite).
__device__ bool stress(const Law& law, const double (&F)[3][3], double (&S)[3][3]) {
  const double J = determinant(F);
  double any = J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) any += 0.0 * F[i][j];
  if (!(J > 0.0) || !(J <= DBL_MAX) || !(any == J)) return false;
  const double J_dU_dJ = law.two_over_D * J * (J - 1.0);
  if (law.kind == kOgden) {
    double C[3][3], lambda2[3], Q[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) C[i][j] = F[0][i] * F[0][j] + F[1][i] * F[1][j] + F[2][i] * F[2][j];
    symmetric_eigen3(C, lambda2, Q);
    const double log_J = log(J);
    double isochoric[3], sum = 0.0;
    for (int i = 0; i < 3; ++i) {
      isochoric[i] = exp(law.half_alpha * (log(lambda2[i]) - (2.0 / 3.0) * log_J));
      sum += isochoric[i];
    }
    const double a = J_dU_dJ - law.stress_factor * (sum * (1.0 / 3.0));
    double principal[3];
    for (int i = 0; i < 3; ++i) principal[i] = (law.stress_factor * isochoric[i] + a) / lambda2[i];
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j)
        S[i][j] = S[j][i] = Q[i][0] * principal[0] * Q[j][0] + Q[i][1] * principal[1] * Q[j][1] +
                            Q[i][2] * principal[2] * Q[j][2];
  } else {
    const double inverse_J = 1.0 / J;
    double Fi[3][3], squared_norm = 0.0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
        Fi[i][j] = (F[r0][c0] * F[r1][c1] - F[r0][c1] * F[r1][c0]) * inverse_J;
        squared_norm += F[i][j] * F[i][j];
      }
    const double shear = law.mu * exp((-2.0 / 3.0) * log(J));
    const double coefficient = J_dU_dJ - shear * (squared_norm / 3.0);
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        S[i][j] = coefficient * (Fi[i][0] * Fi[j][0] + Fi[i][1] * Fi[j][1] + Fi[i][2] * Fi[j][2]);
        if (i == j) S[i][j] += shear;
        S[j][i] = S[i][j];
      }
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!(S[i][j] - S[i][j] == 0.0)) return false;
  return true;
}

// ---- the force kernel -------------------------------------------------------------------------------------------
// Three launches. A block takes one slice, its rows shared by Parts warps, warp w taking entries w, w + Parts, ...:
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
  double* record = a.records + kRecord * p;
  for (int c = 0; c < 9; ++c) record[c] = sum[c];
}

// One thread per point: F from its record, the stress, and the record w F S in its place.
__global__ void stress_pass(std::int64_t points, const double* weight, const std::uint16_t* material, const Law* laws,
                            double* records, int* first_bad) {
  const std::int64_t p = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= points) return;
  double* record = records + kRecord * p;
  double F[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) F[i][k] = i == k ? 1.0 + record[3 * i + k] : record[3 * i + k];
  double S[3][3];
  if (!stress(laws[material[p]], F, S)) {
    for (int c = 0; c < kRecord; ++c) record[c] = 0.0;
    atomicMin(first_bad, static_cast<int>(p));
    return;
  }
  const double w = weight[p];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      record[3 * i + j] = w * (F[i][0] * S[0][j] + F[i][1] * S[1][j] + F[i][2] * S[2][j]);
}

// f_I = sum over node I's points of (w F S) t_pI.
template <class Real>
__global__ void __launch_bounds__(kNodeThreads) node_pass(NodePass<Real> a) {
  const std::int64_t slice = blockIdx.x;
  const int lane = threadIdx.x % kSlice, part = threadIdx.x / kSlice;
  const std::int64_t end = a.rows.slice_begin[slice + 1];
  double f[3] = {0.0, 0.0, 0.0};
  for (std::int64_t e = a.rows.slice_begin[slice] + part * kSlice + lane; e < end; e += kNodeThreads) {
    const double* record = a.records + kRecord * static_cast<std::int64_t>(a.rows.column[e]);
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
    const double f_int = gamma != 0.0 ? f[d] + gamma * (f[d] - f_previous[d]) : f[d];
    const double value = u[d] + beta * (u[d] - u_previous[d]) + step * ((f_ext != nullptr ? f_ext[d] : 0.0) - f_int);
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
void internal_forces(const PointPass<Real>& points, const NodePass<Real>& nodes, cudaStream_t stream) {
  const std::int64_t point_slices = (points.rows.rows + kSlice - 1) / kSlice;
  if (point_slices > 0) {
    gradient_pass<Real><<<static_cast<int>(point_slices), kPointThreads, 0, stream>>>(points);
    stress_pass<<<blocks_for(points.rows.rows), kThreads, 0, stream>>>(points.rows.rows, points.weight, points.material,
                                                                       points.laws, points.records, points.first_bad);
  }
  const std::int64_t node_slices = (nodes.rows.rows + kSlice - 1) / kSlice;
  if (node_slices > 0) node_pass<Real><<<static_cast<int>(node_slices), kNodeThreads, 0, stream>>>(nodes);
}
template void internal_forces<float>(const PointPass<float>&, const NodePass<float>&, cudaStream_t);
template void internal_forces<double>(const PointPass<double>&, const NodePass<double>&, cudaStream_t);

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
