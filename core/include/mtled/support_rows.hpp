#pragma once
// Compressed sparse rows (integration points or nodes to the nodes of their supports) and their transpose.
#include <cstdint>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

// Compressed rows: row r has entries offsets[r] .. offsets[r+1]-1.
struct SupportRows {
  std::vector<std::int64_t> offsets;
  std::vector<Index> nodes;
  std::vector<double> values;  // N_I at the row's point (empty when not stored)

  Index rows() const { return offsets.empty() ? 0 : static_cast<Index>(offsets.size() - 1); }
  std::int64_t size(Index row) const { return offsets[row + 1] - offsets[row]; }
  // Appends the nodes of row r.
  void append_row(Index row, std::vector<Index>& out) const {
    out.insert(out.end(), nodes.begin() + offsets[row], nodes.begin() + offsets[row + 1]);
  }
};

// The transpose of a relation from `rows` rows (integration points) to `columns` columns (nodes): row c of the
// result lists, in `nodes`, the rows whose entries name column c, in row order, so that a sum over them runs in
// one order whatever the thread count. entries_of(row, add) calls add(column) for each entry of the row.
template <class EntriesOf>
SupportRows transpose_rows(Index rows, Index columns, EntriesOf&& entries_of) {
  SupportRows transpose;
  auto& offsets = transpose.offsets;
  offsets.assign(static_cast<std::size_t>(columns) + 1, 0);
  for (Index r = 0; r < rows; ++r) entries_of(r, [&](Index c) { ++offsets[static_cast<std::size_t>(c) + 1]; });
  for (std::size_t c = 0; c < static_cast<std::size_t>(columns); ++c) offsets[c + 1] += offsets[c];
  transpose.nodes.resize(static_cast<std::size_t>(offsets.back()));
  std::vector<std::int64_t> next(offsets.begin(), offsets.end() - 1);
  for (Index r = 0; r < rows; ++r)
    entries_of(r, [&](Index c) { transpose.nodes[static_cast<std::size_t>(next[static_cast<std::size_t>(c)]++)] = r; });
  return transpose;
}

}  // namespace mtled
