#include "mesh_partition.hpp"

#include <metis.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "mtled/support_rows.hpp"

namespace mtled {

MeshPartition partition_mesh(const TetMesh& mesh, int parts) {
  MeshPartition out{std::vector<int>(mesh.tets.size(), 0), std::vector<int>(static_cast<std::size_t>(mesh.node_count()), 0)};
  if (parts <= 1) return out;
  idx_t elements = static_cast<idx_t>(mesh.tet_count()), nodes = static_cast<idx_t>(mesh.node_count());
  std::vector<idx_t> element_start(static_cast<std::size_t>(elements) + 1), element_nodes;
  element_nodes.reserve(4 * static_cast<std::size_t>(elements));
  for (idx_t t = 0; t < elements; ++t) {
    for (const Index n : mesh.tets[static_cast<std::size_t>(t)]) element_nodes.push_back(static_cast<idx_t>(n));
    element_start[static_cast<std::size_t>(t) + 1] = 4 * (t + 1);
  }
  idx_t common = 3, count = parts, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_NUMBERING] = 0;
  std::vector<idx_t> epart(static_cast<std::size_t>(elements)), npart(static_cast<std::size_t>(nodes));
  const int status = METIS_PartMeshDual(&elements, &nodes, element_start.data(), element_nodes.data(), nullptr,
                                        nullptr, &common, &count, nullptr, options, &cut, epart.data(), npart.data());
  if (status != METIS_OK) throw std::runtime_error("METIS_PartMeshDual failed (status " + std::to_string(status) + ")");
  out.tet_part.assign(epart.begin(), epart.end());
  out.node_part.assign(npart.begin(), npart.end());
  return out;
}

std::vector<int> boundary_layers(const TetMesh& mesh, const MeshPartition& partition, int layers) {
  const auto nodes = static_cast<std::size_t>(mesh.node_count());
  const std::vector<int>& owner = partition.node_part;
  // A node's neighbours: the other vertices of its tets.
  const SupportRows node_tets = transpose_rows(mesh.tet_count(), mesh.node_count(), [&](Index t, auto&& add) {
    for (const Index v : mesh.tets[static_cast<std::size_t>(t)]) add(v);
  });
  const auto for_each_neighbour = [&](std::size_t n, auto&& visit) {
    for (std::int64_t k = node_tets.offsets[n]; k < node_tets.offsets[n + 1]; ++k)
      for (const Index v : mesh.tets[static_cast<std::size_t>(node_tets.nodes[static_cast<std::size_t>(k)])])
        if (static_cast<std::size_t>(v) != n) visit(static_cast<std::size_t>(v));
  };
  // hops[n]: edges from n to the nearest node another part owns, through nodes of n's own part.
  std::vector<int> hops(nodes, layers);
  std::vector<Index> front, next;
  for (std::size_t n = 0; n < nodes; ++n) {
    for_each_neighbour(n, [&](std::size_t m) { hops[n] = owner[m] != owner[n] ? 1 : hops[n]; });
    if (hops[n] == 1) front.push_back(static_cast<Index>(n));
  }
  for (int distance = 2; distance < layers && !front.empty(); ++distance) {
    next.clear();
    for (const Index n : front)
      for_each_neighbour(static_cast<std::size_t>(n), [&](std::size_t m) {
        if (owner[m] == owner[static_cast<std::size_t>(n)] && hops[m] > distance) {
          hops[m] = distance;
          next.push_back(static_cast<Index>(m));
        }
      });
    front.swap(next);
  }
  std::vector<int> layer(mesh.tets.size(), layers);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (const Index n : mesh.tets[t]) {
      const auto i = static_cast<std::size_t>(n);
      layer[t] = std::min(layer[t], owner[i] != partition.tet_part[t] ? 0 : hops[i]);
    }
  return layer;
}

PartSizes part_sizes(const MeshPartition& partition, std::span<const int> point_part, const GradientRows& rows) {
  int parts = 1;
  for (const int p : partition.node_part) parts = std::max(parts, p + 1);
  for (const int p : point_part) parts = std::max(parts, p + 1);
  const auto count = static_cast<std::size_t>(parts);
  PartSizes sizes{std::vector<std::int64_t>(count, 0), std::vector<std::int64_t>(count, 0),
                  std::vector<std::int64_t>(count, 0), std::vector<std::int64_t>(count, 0), std::vector<int>(count, 0)};
  std::vector<int> neighbour_seen(count, -1);
  for (const int p : partition.node_part) ++sizes.owned_nodes[static_cast<std::size_t>(p)];
  // Nodes reached by each part, marked with the part's number so that one array serves every part in turn.
  std::vector<int> reached(partition.node_part.size(), -1);
  std::vector<std::vector<Index>> points_of(static_cast<std::size_t>(parts));
  for (std::size_t p = 0; p < point_part.size(); ++p) points_of[static_cast<std::size_t>(point_part[p])].push_back(static_cast<Index>(p));
  for (int part = 0; part < parts; ++part) {
    sizes.points[static_cast<std::size_t>(part)] = static_cast<std::int64_t>(points_of[static_cast<std::size_t>(part)].size());
    for (const Index p : points_of[static_cast<std::size_t>(part)]) {
      sizes.boundary_points[static_cast<std::size_t>(part)] += reaches_another_part(rows, p, partition.node_part, part) ? 1 : 0;
      for (int k = 0; k < rows.size(p); ++k) {
        const auto node = static_cast<std::size_t>(rows.node(p, k));
        if (reached[node] == part) continue;
        reached[node] = part;
        const int owner = partition.node_part[node];
        if (owner == part) continue;
        ++sizes.ghost_nodes[static_cast<std::size_t>(part)];
        if (neighbour_seen[static_cast<std::size_t>(owner)] != part) {
          neighbour_seen[static_cast<std::size_t>(owner)] = part;
          ++sizes.neighbours[static_cast<std::size_t>(part)];
        }
      }
    }
  }
  return sizes;
}

}  // namespace mtled
