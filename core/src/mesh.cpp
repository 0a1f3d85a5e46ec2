#include "mtled/mesh.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

namespace mtled {

double tet_volume(const TetMesh& mesh, Index t) {
  const auto& tet = mesh.tets[static_cast<std::size_t>(t)];
  const Vec3& a = mesh.points[tet[0]];
  return (mesh.points[tet[1]] - a).dot((mesh.points[tet[2]] - a).cross(mesh.points[tet[3]] - a)) / 6.0;
}

Vec3 tet_centroid(const TetMesh& mesh, Index t) {
  const auto& tet = mesh.tets[static_cast<std::size_t>(t)];
  return 0.25 * (mesh.points[tet[0]] + mesh.points[tet[1]] + mesh.points[tet[2]] + mesh.points[tet[3]]);
}

std::array<Vec3, 4> tet_quadrature_points(const TetMesh& mesh, Index t) {
  constexpr double a = 0.5854101966249685, b = 0.1381966011250105;  // (5 + 3 sqrt 5) / 20, (5 - sqrt 5) / 20
  const auto& tet = mesh.tets[static_cast<std::size_t>(t)];
  std::array<Vec3, 4> points;
  for (int k = 0; k < 4; ++k) {
    Vec3& x = points[static_cast<std::size_t>(k)];
    x = Vec3::Zero();
    for (int j = 0; j < 4; ++j) x += (j == k ? a : b) * mesh.points[tet[j]];
  }
  return points;
}

std::pair<Vec3, Vec3> bounding_box(const std::vector<Vec3>& points) {
  Vec3 lo = points.front(), hi = lo;
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

double tet_radius_ratio(const TetMesh& mesh, Index t) {
  const auto& tet = mesh.tets[t];
  const Vec3& p0 = mesh.points[tet[0]];
  // 3 r_in / r_circ: r_in = 3 V / (sum of face areas), r_circ from the edge vectors at vertex 0.
  const Vec3 a = mesh.points[tet[1]] - p0, b = mesh.points[tet[2]] - p0, c = mesh.points[tet[3]] - p0;
  const double volume = std::abs(a.dot(b.cross(c))) / 6.0;
  if (!(volume > 0.0)) return 0.0;
  const Vec3 opposite = (mesh.points[tet[2]] - mesh.points[tet[1]]).cross(mesh.points[tet[3]] - mesh.points[tet[1]]);
  const double area = 0.5 * (a.cross(b).norm() + b.cross(c).norm() + c.cross(a).norm() + opposite.norm());
  const double circumradius =
      (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b)).norm() / (12.0 * volume);
  return 3.0 * (3.0 * volume / area) / circumradius;
}

MeshQuality mesh_quality(const TetMesh& mesh) {
  MeshQuality quality{180.0, 1.0};
  constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const auto& tet = mesh.tets[t];
    const std::array<Vec3, 4> p = {mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]], mesh.points[tet[3]]};
    // The dihedral angle along edge (i, j): between the other two vertices seen along the edge.
    for (const auto& e : kEdges) {
      const Vec3 axis = (p[e[1]] - p[e[0]]).normalized();
      Vec3 u = p[e[2]] - p[e[0]], w = p[e[3]] - p[e[0]];
      u -= u.dot(axis) * axis;
      w -= w.dot(axis) * axis;
      const double angle = std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / 3.14159265358979323846;
      quality.min_dihedral_angle_deg = std::min(quality.min_dihedral_angle_deg, angle);
    }
    quality.min_radius_ratio = std::min(quality.min_radius_ratio, tet_radius_ratio(mesh, t));
  }
  return quality;
}

void remove_unused_nodes(TetMesh& mesh) {
  std::vector<Index> new_index(mesh.points.size(), -1);
  Index next = 0;
  for (auto& tet : mesh.tets) {
    for (auto& v : tet) {
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.points.size()) continue;  // check_mesh reports it
      if (new_index[v] < 0) new_index[v] = next++;
    }
  }
  if (static_cast<std::size_t>(next) == mesh.points.size()) {
    bool identity = true;
    for (std::size_t i = 0; i < new_index.size() && identity; ++i) identity = new_index[i] == static_cast<Index>(i);
    if (identity) return;
  }
  // Keep the original relative order of the nodes (it carries the generator's locality).
  std::vector<Index> order;
  for (std::size_t i = 0; i < new_index.size(); ++i)
    if (new_index[i] >= 0) order.push_back(static_cast<Index>(i));
  next = 0;
  for (Index old : order) new_index[old] = next++;
  std::vector<Vec3> points;
  points.reserve(order.size());
  for (Index old : order) points.push_back(mesh.points[old]);
  for (auto& tet : mesh.tets)
    for (auto& v : tet)
      if (v >= 0 && static_cast<std::size_t>(v) < new_index.size()) v = new_index[v];
  for (auto& [name, nodes] : mesh.node_sets) {
    std::vector<Index> kept;
    for (Index n : nodes)
      if (n >= 0 && static_cast<std::size_t>(n) < new_index.size() && new_index[n] >= 0) kept.push_back(new_index[n]);
    nodes = std::move(kept);
  }
  mesh.points = std::move(points);
}

namespace {

// "tet 7 (number 8 in the mesh's order, centroid at (x, y, z) m)": internal node numbers mean nothing to the
// person who wrote the mesh file, the position does.
std::string describe_tet(const TetMesh& mesh, Index t) {
  const Vec3 centroid = tet_centroid(mesh, t);
  return fmt::format("tet {} (number {} in the mesh's order of tets, centroid at ({:.6g}, {:.6g}, {:.6g}) m)", t,
                     t + 1, centroid[0], centroid[1], centroid[2]);
}

// One tet's use of a face: the face's vertices sorted (its key), the tet, which of its faces (kTetFaces) it is, and
// whether the tet's outward order of them is an even permutation of the sorted one.
struct FaceUse {
  std::array<Index, 3> face;
  Index tet;
  int which;
  bool even;
};
// With positive volume (b-a).((c-a)x(d-a)) > 0, these vertex orders give outward normals.
constexpr int kTetFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

// visit(first, last) for each face of the mesh with the tets that use it, in order of the sorted vertices, the uses in
// tet order. The uses are bucketed by their smallest vertex (a counting sort: two passes over the tets) and sorted
// within each bucket: linear in the mesh, where one sort of all 4 x tets uses, or a hash table, is not.
template <class Visit>
void for_each_face(const TetMesh& mesh, Visit visit) {
  auto use = [](const std::array<Index, 4>& tet, int which, Index t) {
    const int(&f)[3] = kTetFaces[which];
    FaceUse u{{tet[f[0]], tet[f[1]], tet[f[2]]}, t, which, true};
    for (const auto& [a, b] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{0, 1}}) {  // a bubble sort's swaps
      if (u.face[a] > u.face[b]) {
        std::swap(u.face[a], u.face[b]);
        u.even = !u.even;
      }
    }
    return u;
  };
  std::vector<std::int64_t> bucket(mesh.points.size() + 1, 0);
  for (const auto& tet : mesh.tets)
    for (const auto& f : kTetFaces) ++bucket[static_cast<std::size_t>(std::min({tet[f[0]], tet[f[1]], tet[f[2]]})) + 1];
  for (std::size_t v = 0; v < mesh.points.size(); ++v) bucket[v + 1] += bucket[v];
  std::vector<FaceUse> uses(static_cast<std::size_t>(bucket.back()));
  std::vector<std::int64_t> next(bucket.begin(), bucket.end() - 1);
  for (Index t = 0; t < mesh.tet_count(); ++t)
    for (int which = 0; which < 4; ++which) {
      const FaceUse u = use(mesh.tets[static_cast<std::size_t>(t)], which, t);
      uses[static_cast<std::size_t>(next[static_cast<std::size_t>(u.face[0])]++)] = u;
    }
  auto order = [](const FaceUse& a, const FaceUse& b) { return a.face != b.face ? a.face < b.face : a.tet < b.tet; };
  for (std::size_t v = 0; v < mesh.points.size(); ++v) {
    const auto first = uses.begin() + bucket[v], last = uses.begin() + bucket[v + 1];
    std::sort(first, last, order);
    for (auto group = first; group != last;) {
      auto end = group + 1;
      while (end != last && end->face == group->face) ++end;
      visit(group, end);
      group = end;
    }
  }
}

// With every tet right-handed, an interior face is seen with opposite orientations from its two tets. Two
// tets on the same side of their shared face overlap: one of them was inverted (a node moved through the
// opposite face) and merely re-ordering its nodes would hide a folded mesh. A face shared by more than two
// tets is overlapping material as well.
void check_no_overlaps(const TetMesh& mesh) {
  std::vector<Problem> problems;
  std::size_t overlaps = 0;
  for_each_face(mesh, [&](auto first, auto last) {
    const auto count = last - first;
    const bool fine = count == 1 || (count == 2 && first->even != (first + 1)->even);
    if (fine || ++overlaps > 5) return;
    const auto& face = first->face;
    const Vec3 centre = (mesh.points[face[0]] + mesh.points[face[1]] + mesh.points[face[2]]) / 3.0;
    if (count == 2) {
      problems.push_back({mesh.source, fmt::format("{} and {} lie on the same side of their shared face (centre at "
                                                   "({:.6g}, {:.6g}, {:.6g}) m): one of them is inverted (a node "
                                                   "moved through the opposite face) or the two overlap; fix the "
                                                   "node or re-mesh",
                                                   describe_tet(mesh, first->tet), describe_tet(mesh, (first + 1)->tet),
                                                   centre[0], centre[1], centre[2])});
    } else {
      problems.push_back(
          {mesh.source, fmt::format("{} tets share the face centred at ({:.6g}, {:.6g}, {:.6g}) m (at "
                                    "most two can): the mesh has overlapping or repeated tets, "
                                    "starting with {}; re-mesh",
                                    count, centre[0], centre[1], centre[2], describe_tet(mesh, first->tet))});
    }
  });
  if (overlaps > 5) problems.push_back({mesh.source, fmt::format("... {} such faces in all", overlaps)});
  if (!problems.empty()) throw InputError(std::move(problems));
}

}  // namespace

void check_mesh(TetMesh& mesh, bool fix_orientation, bool allow_overlaps) {
  std::vector<Problem> problems;
  const std::string& where = mesh.source;
  if (mesh.tets.empty()) throw InputError(where, "the mesh has no tetrahedra (mtled needs a volume mesh of 4-node tets)");
  for (std::size_t i = 0; i < mesh.points.size(); ++i) {
    if (!mesh.points[i].allFinite()) {
      problems.push_back({where, fmt::format("node {} has non-finite coordinates", i)});
      if (problems.size() > 10) break;
    }
  }
  const Index n = mesh.node_count();
  for (std::size_t t = 0; t < mesh.tets.size() && problems.size() <= 10; ++t) {
    for (Index v : mesh.tets[t]) {
      if (v < 0 || v >= n) {
        problems.push_back({where, fmt::format("tet {} refers to node {}, outside 0..{}", t, v, n - 1)});
        break;
      }
    }
  }
  if (mesh.tet_region.size() != mesh.tets.size()) mesh.tet_region.assign(mesh.tets.size(), 0);
  if (mesh.region_names.empty()) mesh.region_names.push_back("all");
  if (!problems.empty()) throw InputError(std::move(problems));

  // A volume is "zero" relative to the cube of the mesh's mean edge length.
  double mean_edge = 0.0;
  for (const auto& tet : mesh.tets) mean_edge += (mesh.points[tet[1]] - mesh.points[tet[0]]).norm();
  mean_edge /= static_cast<double>(mesh.tets.size());
  const double zero_volume = 1e-12 * mean_edge * mean_edge * mean_edge;
  std::size_t inverted = 0, degenerate = 0;
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const double v = tet_volume(mesh, t);
    if (!(std::abs(v) > zero_volume)) {
      if (++degenerate <= 5)
        problems.push_back({where, fmt::format("{} has zero volume ({:.3g} m^3; its nodes lie in one plane): remove "
                                               "it or re-mesh", describe_tet(mesh, t), v)});
    } else if (v < 0.0) {
      ++inverted;
      if (fix_orientation) {
        std::swap(mesh.tets[t][2], mesh.tets[t][3]);
      } else if (inverted <= 5) {
        problems.push_back({where, fmt::format("{} is inverted (negative volume {:.3g} m^3)", describe_tet(mesh, t), v)});
      }
    }
  }
  if (degenerate > 5) problems.push_back({where, fmt::format("... {} zero-volume tets in all", degenerate)});
  if (!problems.empty()) throw InputError(std::move(problems));
  if (!allow_overlaps) check_no_overlaps(mesh);
}

std::vector<std::array<Index, 3>> boundary_faces(const TetMesh& mesh) {
  // A face is on the boundary when exactly one tet uses it; it keeps that tet's outward order (reversed where the
  // tet's volume is negative).
  std::vector<std::array<Index, 3>> boundary;
  for_each_face(mesh, [&](auto first, auto last) {
    if (last - first != 1) return;
    const auto& tet = mesh.tets[static_cast<std::size_t>(first->tet)];
    const int(&f)[3] = kTetFaces[first->which];
    std::array<Index, 3> oriented{tet[f[0]], tet[f[1]], tet[f[2]]};
    if (tet_volume(mesh, first->tet) < 0.0) std::swap(oriented[1], oriented[2]);
    boundary.push_back(oriented);
  });
  std::sort(boundary.begin(), boundary.end());  // a deterministic order
  return boundary;
}

Index remove_boundary_slivers(TetMesh& mesh) {
  Index removed = 0;
  for (;;) {
    std::vector<int> boundary(mesh.tets.size(), 0);
    for_each_face(mesh, [&](auto first, auto last) {
      if (last - first == 1) ++boundary[static_cast<std::size_t>(first->tet)];
    });
    std::vector<std::array<Index, 4>> tets;
    std::vector<Index> regions;
    for (Index t = 0; t < mesh.tet_count(); ++t) {
      if (boundary[static_cast<std::size_t>(t)] >= 2 && tet_radius_ratio(mesh, t) < kSliverRadiusRatio) continue;
      tets.push_back(mesh.tets[t]);
      regions.push_back(mesh.tet_region[t]);
    }
    if (tets.size() == mesh.tets.size() || tets.empty()) return removed;  // none left, or nothing but slivers
    removed += mesh.tet_count() - static_cast<Index>(tets.size());
    mesh.tets = std::move(tets);
    mesh.tet_region = std::move(regions);
  }
}

std::vector<char> surface_nodes(const TetMesh& mesh) {
  std::vector<char> surface(mesh.points.size(), 0);
  for (const auto& face : boundary_faces(mesh))
    for (Index v : face) surface[v] = 1;
  return surface;
}

std::vector<double> mean_edge_length_at_nodes(const TetMesh& mesh) {
  // Each edge is shared by several tets; counting it once per tet weights edges by their tet count, which is
  // what "the edges that meet at the node" means for a mean over the node's neighbourhood volume.
  std::vector<double> sum(mesh.points.size(), 0.0);
  std::vector<int> count(mesh.points.size(), 0);
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const auto& tet : mesh.tets) {
    for (const auto& e : kEdges) {
      const double length = (mesh.points[tet[e[0]]] - mesh.points[tet[e[1]]]).norm();
      sum[tet[e[0]]] += length;
      sum[tet[e[1]]] += length;
      ++count[tet[e[0]]];
      ++count[tet[e[1]]];
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] = count[i] > 0 ? sum[i] / count[i] : 0.0;
  return sum;
}

std::vector<Index> select_nodes(const NodeSelector& selector, const TetMesh& mesh, const std::vector<char>& surface,
                                const std::string& pointer) {
  std::vector<Index> nodes;
  if (selector.kind == NodeSelector::Kind::group) {
    const auto it = mesh.node_sets.find(selector.group);
    if (it == mesh.node_sets.end()) {
      std::vector<std::string> names;
      for (const auto& [name, set] : mesh.node_sets) names.push_back(name);
      std::string message = fmt::format("the mesh ({}) has no node set \"{}\"", mesh.source, selector.group);
      const auto hint = did_you_mean(selector.group, names);
      message += hint.empty() ? (names.empty() ? "; it has no named node sets: select nodes by geometry instead"
                                               : fmt::format("; it has: {}", fmt::join(names, ", ")))
                              : "; " + hint;
      throw InputError(pointer + "/group", message);
    }
    for (Index n : it->second)
      if (!selector.surface_only || surface[n]) nodes.push_back(n);
  } else {
    const auto [lo, hi] = bounding_box(mesh.points);
    const double tol = selector.tolerance.value_or(1e-6 * (hi - lo).norm());
    for (Index i = 0; i < mesh.node_count(); ++i) {
      if (selector.surface_only && !surface[i]) continue;
      if (selector.contains(mesh.points[i], tol)) nodes.push_back(i);
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

}  // namespace mtled
