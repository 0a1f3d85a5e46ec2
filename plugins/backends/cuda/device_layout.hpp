#pragma once
// The CUDA backend's arrays, built on the host from the discretisation's rows (and tested without a GPU): both passes
// of the force kernel in sliced ELLPACK layout (SELL-C, C = 32, Kreutzer et al., SIAM J. Sci. Comput. 36 (2014) C401),
// so that the 32 threads of a warp, one row each, read 32 consecutive entries at every step of their loops:
//   points: row p = integration point p, columns its support nodes with grad N (F = I + sum u (x) grad N);
//   nodes:  one row per node, columns the points whose supports hold it with the test gradient
//           t_pI = grad N_I + the consistent-integration correction (f_I = sum_p (w P)_p t_pI: each node sums its own
//           force, in one order on every run, where the CPU's threads add into their own buffers).
// A slice is 32 consecutive rows padded to its longest; padding entries name a sink column whose value is zero (one
// past the last node, one past the last point), so the loops need no test. The node rows are sorted by length
// within windows of kSortWindow rows (SELL-C-sigma) to cut the padding; a row's entries stay in point order, so each
// node's sum runs in one order on every run.
#include <cstdint>
#include <vector>

#include "mtled/discretisation.hpp"
#include "sliced_rows.hpp"

namespace mtled::cuda {

constexpr int kSortWindow = 256;

template <class Real>
struct DeviceLayout {
  std::int32_t nodes = 0, points = 0;
  SlicedRows<Real> point_rows;  // columns: nodes (sink: `nodes`)
  SlicedRows<Real> node_rows;   // columns: points (sink: `points`)
};

// The layout of the discretisation's rows in the precision they are stored in (Real = float for single-precision rows).
template <class Real>
DeviceLayout<Real> build_device_layout(const Discretisation& model);

}  // namespace mtled::cuda
