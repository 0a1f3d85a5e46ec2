#include "mtled/gradient_rows.hpp"

#include <algorithm>
#include <iterator>

namespace mtled {

void GradientRows::assign(const std::vector<std::vector<Index>>& supports, Index padding_node, RowPrecision precision) {
  precision_ = precision;
  block_offsets_.assign(supports.size() + 1, 0);
  sizes_.resize(supports.size());
  entries_ = 0;
  for (std::size_t r = 0; r < supports.size(); ++r) {
    sizes_[r] = static_cast<int>(supports[r].size());
    entries_ += sizes_[r];
    block_offsets_[r + 1] = block_offsets_[r] + (sizes_[r] + kBlock - 1) / kBlock;
  }
  // Slots in order of first use; nodes no row names (an error the model reports) take the last ones.
  constexpr Index kUnset = -1;
  slot_of_node_.assign(static_cast<std::size_t>(padding_node) + 1, kUnset);
  node_of_slot_.clear();
  node_of_slot_.reserve(slot_of_node_.size());
  auto give_slot = [&](Index node) {
    Index& slot = slot_of_node_[static_cast<std::size_t>(node)];
    if (slot != kUnset) return;
    slot = static_cast<Index>(node_of_slot_.size());
    node_of_slot_.push_back(node);
  };
  for (const auto& support : supports)
    for (Index node : support) give_slot(node);
  for (Index node = 0; node < padding_node; ++node) give_slot(node);
  slot_of_node_[static_cast<std::size_t>(padding_node)] = padding_node;
  node_of_slot_.push_back(padding_node);
  with_arrays([&](auto& blocks, auto& tests) {
    blocks.clear();
    blocks.resize(static_cast<std::size_t>(this->blocks()));  // unwritten: every block is written below
    tests.clear();
    const auto rows = static_cast<std::int64_t>(supports.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t r = 0; r < rows; ++r) {
      for (std::int64_t b = block_offsets_[r]; b < block_offsets_[r + 1]; ++b) {
        auto& block = blocks[static_cast<std::size_t>(b)];
        for (auto& component : block.gradients) std::fill(std::begin(component), std::end(component), 0);
        std::fill(std::begin(block.records), std::end(block.records), 4 * padding_node);
      }
      for (std::size_t k = 0; k < supports[r].size(); ++k) {
        const std::size_t p = position(static_cast<Index>(r), static_cast<int>(k));
        blocks[p / kBlock].records[p % kBlock] = 4 * slot(supports[r][k]);
      }
    }
  });
}

void GradientRows::set_gradient(Index row, int k, const Vec3& gradient) {
  const std::size_t p = position(row, k);
  with_arrays([&](auto& blocks, auto&) {
    for (int c = 0; c < 3; ++c)
      blocks[p / kBlock].gradients[c][p % kBlock] = static_cast<real_of<decltype(blocks)>>(gradient[c]);
  });
}

Vec3 GradientRows::gradient(Index row, int k) const {
  const std::size_t p = position(row, k);
  return with_arrays([&](const auto& blocks, const auto&) {
    const auto& g = blocks[p / kBlock].gradients;
    return Vec3{g[0][p % kBlock], g[1][p % kBlock], g[2][p % kBlock]};
  });
}

// The test gradients: 3 x kBlock per block, the x, then the y, then the z components of its entries.
void GradientRows::own_test_gradients() {
  with_arrays([&](const auto& blocks, auto& tests) {
    if (!tests.empty()) return;
    tests.resize(3 * kBlock * blocks.size());  // unwritten: the copy writes every element
    const auto count = static_cast<std::int64_t>(blocks.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t b = 0; b < count; ++b)
      for (int c = 0; c < 3; ++c)
        std::copy_n(blocks[b].gradients[c], kBlock,
                    tests.begin() + static_cast<std::ptrdiff_t>(test_index(kBlock * b, c)));
  });
}

void GradientRows::set_test_gradient(Index row, int k, const Vec3& gradient) {
  own_test_gradients();
  const std::size_t p = position(row, k);
  with_arrays([&](const auto& blocks, auto& tests) {
    for (int c = 0; c < 3; ++c) tests[test_index(p, c)] = static_cast<real_of<decltype(blocks)>>(gradient[c]);
  });
}

Vec3 GradientRows::stored_test_gradient(Index row, int k) const {
  if (!has_own_test_gradients()) return gradient(row, k);
  const std::size_t p = position(row, k);
  return with_arrays([&](const auto&, const auto& tests) {
    return Vec3{tests[test_index(p, 0)], tests[test_index(p, 1)], tests[test_index(p, 2)]};
  });
}

}  // namespace mtled
