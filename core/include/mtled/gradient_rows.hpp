#pragma once
// The shape-function gradients at the integration points, laid out for the vectorised force kernel
// (core/src/force_passes.cpp), which reads them and nothing else of the discretisation.
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

// The precision the force kernel's rows are stored in. Sums, stresses and the state are double either way; "single"
// halves the bytes the kernel streams per support entry at a relative rounding of about 6e-8 in each gradient.
enum class RowPrecision { double_precision, single_precision };

// kBlock support entries as the force kernel's gather reads them: the x, the y and the z gradient components, each
// contiguous (structure of arrays, so one SIMD load reads one component of the kBlock entries), then the entries'
// record offsets (4 x the node's slot, below: the kernel's per-node arrays have 4 doubles per slot). One stream per
// row and, in single precision, one 64-byte cache line per block: the kernel prefetches a block's lines as it steps.
inline constexpr int kRowBlockEntries = 4;
template <class Real>
struct RowBlock {
  Real gradients[3][kRowBlockEntries];
  Index records[kRowBlockEntries];
};
static_assert(sizeof(RowBlock<float>) == 64 && sizeof(RowBlock<double>) == 112);

// Shape-function gradients at the integration points, laid out for the force kernel's gather of F: row r holds
// blocks block_begin(r) .. block_end(r) - 1 (RowBlock, above). A row's last block is padded with zero gradients on
// the padding node (the node count: one past the last node, and its own slot), which the kernel's per-node array
// carries as a zero-displacement sink. Gradients are stored in the precision asked for; gradient() returns the
// stored value, so setup code sees what the kernel uses.
//
// The kernel's per-node arrays are numbered by slot, not by node: slots follow the order in which the rows first
// name each node, so the nodes that consecutive integration points read lie next to each other in memory (a window of
// points reads a few contiguous kilobytes of records, not 40 scattered lines of a cloud-sized array). Every sum keeps
// its order, so the forces are bitwise those of numbering by node; only the arrays' layout changes. The padding node
// keeps its own number as its slot.
class GradientRows {
 public:
  static constexpr int kBlock = kRowBlockEntries;

  // One row per support list; gradients zero until set.
  void assign(const std::vector<std::vector<Index>>& supports, Index padding_node, RowPrecision precision);
  void set_gradient(Index row, int k, const Vec3& gradient);
  // The test-function gradients the force kernel's scatter reads (the model's consistent integration: grad N_I + xi_I
  // - the mean of xi over the row), in the gradients' precision, 3 x kBlock per block (x, y, z; no records: the
  // scatter reads those from the blocks). Until own_test_gradients() they are the gradients themselves and take no
  // memory; own_test_gradients() makes them a copy of the gradients (in parallel; nothing if already done), after
  // which set_test_gradient overwrites one entry and may be called from several threads for distinct entries.
  // set_test_gradient calls own_test_gradients() itself when needed.
  void own_test_gradients();
  void set_test_gradient(Index row, int k, const Vec3& gradient);

  RowPrecision precision() const { return precision_; }
  Index rows() const { return static_cast<Index>(sizes_.size()); }
  int size(Index row) const { return sizes_[row]; }  // entries, padding excluded
  std::int64_t entries() const { return entries_; }   // all rows, padding excluded
  Index node(Index row, int k) const { return node_at_slot(entry_slot(row, k)); }
  // Appends the nodes of row r (its support: the u_I the point's F reads).
  void append_nodes(Index row, std::vector<Index>& out) const {
    for (int k = 0; k < size(row); ++k) out.push_back(node(row, k));
  }
  // Where node `node`'s record sits in the kernel's per-node arrays (4 doubles per slot), and the node at a slot.
  Index slot(Index node) const { return slot_of_node_[static_cast<std::size_t>(node)]; }
  Index entry_slot(Index row, int k) const { return record(position(row, k)) / 4; }  // slot(node(row, k))
  Index node_at_slot(Index slot) const { return node_of_slot_[static_cast<std::size_t>(slot)]; }
  Vec3 gradient(Index row, int k) const;
  Vec3 stored_test_gradient(Index row, int k) const;  // as the kernel reads it (the gradient where none is stored)

  std::int64_t block_begin(Index row) const { return block_offsets_[row]; }
  std::int64_t block_end(Index row) const { return block_offsets_[row + 1]; }
  // Real: the stored precision (float for single_precision). The stored test gradients exist only where
  // has_own_test_gradients().
  template <class Real>
  const RowBlock<Real>* block(std::int64_t block) const;
  template <class Real>
  const Real* block_test_gradients(std::int64_t block) const;
  bool has_own_test_gradients() const { return !double_tests_.empty() || !single_tests_.empty(); }
  std::int64_t blocks() const { return block_offsets_.empty() ? 0 : block_offsets_.back(); }

 private:
  std::size_t position(Index row, int k) const { return static_cast<std::size_t>(kBlock * block_offsets_[row] + k); }
  Index record(std::size_t position) const {
    const std::size_t block = position / kBlock, k = position % kBlock;
    return precision_ == RowPrecision::single_precision ? single_blocks_[block].records[k]
                                                        : double_blocks_[block].records[k];
  }
  // Where component c of entry `position` sits in the test gradients (3 x kBlock per block).
  static std::size_t test_index(std::size_t position, int c) {
    return 3 * kBlock * (position / kBlock) + static_cast<std::size_t>(c * kBlock) + position % kBlock;
  }
  // visit(blocks, tests): the two arrays of the rows' precision.
  template <class Visit>
  decltype(auto) with_arrays(Visit visit) {
    if (precision_ == RowPrecision::single_precision) return visit(single_blocks_, single_tests_);
    return visit(double_blocks_, double_tests_);
  }
  template <class Visit>
  decltype(auto) with_arrays(Visit visit) const {
    if (precision_ == RowPrecision::single_precision) return visit(single_blocks_, single_tests_);
    return visit(double_blocks_, double_tests_);
  }
  template <class Blocks>  // float or double: the precision of an array of RowBlocks
  using real_of = std::remove_cvref_t<decltype(std::declval<Blocks>()[0].gradients[0][0])>;

  RowPrecision precision_ = RowPrecision::double_precision;
  std::vector<std::int64_t> block_offsets_;
  std::vector<int> sizes_;
  std::int64_t entries_ = 0;
  std::vector<Index> slot_of_node_, node_of_slot_;  // both padding_node + 1 long
  // Written in parallel after each resize (assign, set_test_gradient): UnfilledVector.
  UnfilledVector<RowBlock<double>> double_blocks_;  // the one the precision names is filled
  UnfilledVector<RowBlock<float>> single_blocks_;
  UnfilledVector<double> double_tests_;  // empty until a test gradient is set
  UnfilledVector<float> single_tests_;
};

template <>
inline const RowBlock<double>* GradientRows::block<double>(std::int64_t block) const {
  return double_blocks_.data() + block;
}
template <>
inline const RowBlock<float>* GradientRows::block<float>(std::int64_t block) const {
  return single_blocks_.data() + block;
}
template <>
inline const double* GradientRows::block_test_gradients<double>(std::int64_t block) const {
  return double_tests_.data() + 3 * kBlock * block;
}
template <>
inline const float* GradientRows::block_test_gradients<float>(std::int64_t block) const {
  return single_tests_.data() + 3 * kBlock * block;
}

}  // namespace mtled
