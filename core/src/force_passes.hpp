#pragma once
// The internal-force kernel's vectorised parts (force_passes.cpp), written once with Google Highway and
// dispatched at run time to the best instruction set the CPU has. ForceKernel::internal_forces runs them over
// batches of consecutive integration points with the same material:
//   gather:        F = I + sum_I u_I (x) grad N_I          (one SIMD lane per support entry)
//   the material:  S(F) for the batch                      (Material::stress_batch, one lane per point)
//   first_piola:   P = w F S                               (one lane per point)
//   scatter:       f_I += P t_I                            (one lane per support entry)
// with t_I the test gradient grad N_I + xi_I - m_p (consistent integration's correction xi, m_p its mean over the
// support). The per-node arrays u4, xi4 and f4 hold 4 doubles per node (x, y, z, 0) and a zero padding node at the
// end (GradientRows); m3 holds 3 doubles per integration point. Every lane of a batch past its count is filled with
// F = I. The rows are read in the precision they are stored in, and summed in double.
#include "mtled/gradient_rows.hpp"
#include "mtled/interfaces/material.hpp"

namespace mtled::force_passes {

// batch.F for integration points first .. first + batch.count - 1; gather and scatter ask the caches for the rows'
// lines a few kilobytes ahead as they read them (the next points' rows lie next in memory).
void gather(const GradientRows& rows, const double* u4, Index first, StressBatch& batch);
// P[c][p] = w_p (F S)_c of lane p (c = 3 i + j), for every lane.
void first_piola(const StressBatch& batch, const double* weights, double (&P)[9][StressBatch::kCapacity]);
// f4 += P t over the rows of integration points first .. first + count - 1, lane p of P for point first + p; lanes
// with skip[p] set are left out. t: the rows' stored test gradients where they have their own, else grad N + xi - m
// formed here from xi4 (the nodes' corrections, 4 doubles per slot) and m3 (each point's mean of them, 3 doubles).
void scatter(const GradientRows& rows, const double* xi4, const double* m3, Index first, int count,
             const double (&P)[9][StressBatch::kCapacity], const bool* skip, double* f4);

}  // namespace mtled::force_passes
