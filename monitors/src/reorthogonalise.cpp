#include "mtled/monitors/reorthogonalise.hpp"

#include <algorithm>
#include <cstdint>

namespace mtled {

void reorthogonalise(const Eigen::MatrixXd& q, Eigen::Index columns, Eigen::VectorXd& w,
                     const ForEachShare& for_each_share) {
  constexpr Eigen::Index kChunk = kReorthogonalisationChunk;
  const Eigen::Index rows = q.rows(), chunks = (rows + kChunk - 1) / kChunk;
  const auto each_chunk = [&](const auto& body) {
    const std::function<void(std::int64_t, std::int64_t)> chunk_range = [&](std::int64_t begin, std::int64_t end) {
      for (Eigen::Index c = begin; c < end; ++c) body(c, c * kChunk, std::min(kChunk, rows - c * kChunk));
    };
    if (for_each_share)
      for_each_share(chunks, chunk_range);
    else
      chunk_range(0, chunks);
  };
  Eigen::MatrixXd shares(columns, chunks);
  each_chunk([&](Eigen::Index c, Eigen::Index first, Eigen::Index n) {
    shares.col(c).noalias() = q.block(first, 0, n, columns).transpose() * w.segment(first, n);
  });
  Eigen::VectorXd h = Eigen::VectorXd::Zero(columns);
  for (Eigen::Index c = 0; c < chunks; ++c) h += shares.col(c);
  each_chunk([&](Eigen::Index, Eigen::Index first, Eigen::Index n) {
    w.segment(first, n).noalias() -= q.block(first, 0, n, columns) * h;
  });
}

}  // namespace mtled
