#pragma once
// The internal-force kernel's vectorised parts (force_kernel.cpp), written once with Google Highway and
// dispatched at run time to the best instruction set the CPU has. Model::internal_forces runs them in two passes:
//   over batches of consecutive integration points with the same material,
//     gather:         F = I + sum_I u_I (x) grad N_I      (one SIMD lane per support entry)
//     the material:   S(F) for the batch                  (Material::stress_batch, one lane per point)
//     stress records: the columns of w F S                (kStressRecord doubles per point)
//   then over the nodes (node-centric assembly),
//     node_forces:    f_I = sum_p (w F S)_p t_pI          (one lane per force component)
// with t_pI the test-function gradients of TestGradientRows. The gather's per-node array u4 holds 4 doubles per
// node (x, y, z, 0) and a zero padding node at the end (GradientRows). Every lane of a batch past its count is
// filled with F = I. Both passes read the rows in the precision they are stored in and sum in double.
#include "mtled/interfaces/material.hpp"
#include "mtled/model.hpp"

namespace mtled::force_kernel {

// batch.F for integration points first .. first + batch.count - 1; meanwhile asks the caches for the rows of
// the next as many points, up to prefetch_end (exclusive).
void gather(const GradientRows& rows, const double* u4, Index first, Index prefetch_end, StressBatch& batch);
// The stress records of the batch's points, the first at `records`: the columns of w_p F S, zero for lanes with
// skip[p] set (an inadmissible point adds no force).
void store_stress_records(const StressBatch& batch, const double* weights, const bool* skip, double* records);
// f (3 per node) of nodes begin .. end - 1 from the integration points' stress records.
void node_forces(const TestGradientRows& rows, const double* records, Index begin, Index end, double* f);

}  // namespace mtled::force_kernel
