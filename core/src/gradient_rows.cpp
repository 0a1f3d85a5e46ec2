#include "mtled/gradient_rows.hpp"

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
  records_.assign(static_cast<std::size_t>(kBlock * blocks()), 4 * padding_node);
  const auto values = static_cast<std::size_t>(3 * kBlock * blocks());
  double_gradients_.assign(precision == RowPrecision::double_precision ? values : 0, 0.0);
  single_gradients_.assign(precision == RowPrecision::single_precision ? values : 0, 0.0f);
  double_tests_.clear();
  single_tests_.clear();
  for (std::size_t r = 0; r < supports.size(); ++r)
    for (std::size_t k = 0; k < supports[r].size(); ++k)
      records_[position(static_cast<Index>(r), static_cast<int>(k))] = 4 * slot(supports[r][k]);
}

// A block holds the x, then the y, then the z components of its kBlock entries.
void GradientRows::store(AlignedVector<double>& doubles, AlignedVector<float>& singles, std::size_t position,
                         const Vec3& v) const {
  const std::size_t first = 3 * kBlock * (position / kBlock) + position % kBlock;
  for (int c = 0; c < 3; ++c) {
    if (precision_ == RowPrecision::single_precision)
      singles[first + c * kBlock] = static_cast<float>(v[c]);
    else
      doubles[first + c * kBlock] = v[c];
  }
}

Vec3 GradientRows::load(const AlignedVector<double>& doubles, const AlignedVector<float>& singles,
                        std::size_t position) const {
  const std::size_t i = 3 * kBlock * (position / kBlock) + position % kBlock;
  if (precision_ == RowPrecision::single_precision)
    return {singles[i], singles[i + kBlock], singles[i + 2 * kBlock]};
  return {doubles[i], doubles[i + kBlock], doubles[i + 2 * kBlock]};
}

void GradientRows::set_gradient(Index row, int k, const Vec3& gradient) {
  store(double_gradients_, single_gradients_, position(row, k), gradient);
}

Vec3 GradientRows::gradient(Index row, int k) const {
  return load(double_gradients_, single_gradients_, position(row, k));
}

void GradientRows::set_test_gradient(Index row, int k, const Vec3& gradient) {
  if (!has_own_test_gradients()) {
    double_tests_ = double_gradients_;
    single_tests_ = single_gradients_;
  }
  store(double_tests_, single_tests_, position(row, k), gradient);
}

Vec3 GradientRows::stored_test_gradient(Index row, int k) const {
  if (!has_own_test_gradients()) return gradient(row, k);
  return load(double_tests_, single_tests_, position(row, k));
}

}  // namespace mtled
