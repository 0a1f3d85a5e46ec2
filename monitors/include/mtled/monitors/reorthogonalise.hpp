#pragma once
// Gram-Schmidt against a basis stored as the columns of a tall matrix (the stable-step monitor's Lanczos vectors: 60
// of 222,702 unknowns, 107 MB, on the brain phantom), spread over the run's threads.
#include <Eigen/Core>

#include "mtled/monitor.hpp"

namespace mtled {

// w -= Q Q^T w over Q's first `columns` columns, by row chunks of a fixed size (kReorthogonalisationChunk): each
// chunk's share of Q^T w on the threads for_each_share runs (on the caller when it is empty), the shares added in
// chunk order, so the result does not depend on how the chunks were spread; then each chunk's rows of w.
inline constexpr Eigen::Index kReorthogonalisationChunk = 256;
void reorthogonalise(const Eigen::MatrixXd& q, Eigen::Index columns, Eigen::VectorXd& w,
                     const ForEachShare& for_each_share);

}  // namespace mtled
