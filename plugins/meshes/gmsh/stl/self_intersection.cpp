#include "stl/self_intersection.hpp"

#include <algorithm>
#include <cmath>

namespace mtled {

namespace {

using Triangle = std::array<Vec3, 3>;

// Six times the signed volume of (a, b, c, d): the side of plane abc that d lies on. Exact zeros (points
// with simple coordinates on a common plane) take the coplanar branch; near-zeros from round-off give
// signs whose only effect is on configurations that touch to within round-off.
double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return (b - a).cross(c - a).dot(d - a); }

double orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

bool on_segment_2d(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& x) {
  return std::min(p[0], q[0]) <= x[0] && x[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= x[1] &&
         x[1] <= std::max(p[1], q[1]);
}

bool segments_meet_2d(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                      const Eigen::Vector2d& b) {
  const double d1 = orient2d(a, b, p), d2 = orient2d(a, b, q), d3 = orient2d(p, q, a), d4 = orient2d(p, q, b);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  return (d1 == 0 && on_segment_2d(a, b, p)) || (d2 == 0 && on_segment_2d(a, b, q)) ||
         (d3 == 0 && on_segment_2d(p, q, a)) || (d4 == 0 && on_segment_2d(p, q, b));
}

bool inside_triangle_2d(const Eigen::Vector2d& x, const std::array<Eigen::Vector2d, 3>& t) {
  const double d1 = orient2d(t[0], t[1], x), d2 = orient2d(t[1], t[2], x), d3 = orient2d(t[2], t[0], x);
  return (d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0);
}

// Segment and triangle in one plane: projected on the coordinate plane where the triangle is largest.
bool coplanar_segment_meets_triangle(const Vec3& p, const Vec3& q, const Triangle& t) {
  const Vec3 normal = (t[1] - t[0]).cross(t[2] - t[0]).cwiseAbs();
  int drop = 0;
  normal.maxCoeff(&drop);
  auto project = [drop](const Vec3& x) { return Eigen::Vector2d(x[(drop + 1) % 3], x[(drop + 2) % 3]); };
  const std::array<Eigen::Vector2d, 3> t2{project(t[0]), project(t[1]), project(t[2])};
  const Eigen::Vector2d p2 = project(p), q2 = project(q);
  if (inside_triangle_2d(p2, t2) || inside_triangle_2d(q2, t2)) return true;
  for (int k = 0; k < 3; ++k)
    if (segments_meet_2d(p2, q2, t2[k], t2[(k + 1) % 3])) return true;
  return false;
}

// Closed segment pq against the closed triangle t.
bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Triangle& t) {
  const double dp = orient3d(t[0], t[1], t[2], p), dq = orient3d(t[0], t[1], t[2], q);
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0)) return false;
  if (dp == 0 && dq == 0) return coplanar_segment_meets_triangle(p, q, t);
  // The segment reaches the plane: it meets the triangle when the line pq passes each edge on the same side.
  const double s1 = orient3d(p, q, t[0], t[1]), s2 = orient3d(p, q, t[1], t[2]), s3 = orient3d(p, q, t[2], t[0]);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

int shared_corners(const std::array<Index, 3>& a, const std::array<Index, 3>& b) {
  int shared = 0;
  for (const Index i : a) shared += std::count(b.begin(), b.end(), i) > 0 ? 1 : 0;
  return shared;
}

// The edge of `t` opposite its corner shared with `other` (exactly one corner is shared).
std::array<int, 2> edge_opposite_shared(const std::array<Index, 3>& t, const std::array<Index, 3>& other) {
  for (int k = 0; k < 3; ++k)
    if (std::count(other.begin(), other.end(), t[static_cast<std::size_t>(k)]) > 0) return {(k + 1) % 3, (k + 2) % 3};
  return {1, 2};
}

bool facets_cross(const std::vector<Vec3>& v, const std::array<Index, 3>& a, const std::array<Index, 3>& b) {
  const int shared = shared_corners(a, b);
  if (shared >= 2) return false;  // neighbours along an edge
  const Triangle ta{v[static_cast<std::size_t>(a[0])], v[static_cast<std::size_t>(a[1])],
                    v[static_cast<std::size_t>(a[2])]};
  const Triangle tb{v[static_cast<std::size_t>(b[0])], v[static_cast<std::size_t>(b[1])],
                    v[static_cast<std::size_t>(b[2])]};
  if (shared == 1) {
    // Only the edges away from the common corner can cross the other facet without the facets overlapping
    // elsewhere too.
    const auto ea = edge_opposite_shared(a, b), eb = edge_opposite_shared(b, a);
    return segment_meets_triangle(ta[static_cast<std::size_t>(ea[0])], ta[static_cast<std::size_t>(ea[1])], tb) ||
           segment_meets_triangle(tb[static_cast<std::size_t>(eb[0])], tb[static_cast<std::size_t>(eb[1])], ta);
  }
  for (int k = 0; k < 3; ++k) {
    if (segment_meets_triangle(ta[static_cast<std::size_t>(k)], ta[static_cast<std::size_t>((k + 1) % 3)], tb))
      return true;
    if (segment_meets_triangle(tb[static_cast<std::size_t>(k)], tb[static_cast<std::size_t>((k + 1) % 3)], ta))
      return true;
  }
  return false;
}

}  // namespace

std::optional<SurfaceCrossing> find_self_intersection(const std::vector<Vec3>& vertices,
                                                      const std::vector<std::array<Index, 3>>& triangles) {
  const std::size_t n = triangles.size();
  if (n < 2) return std::nullopt;
  std::vector<Eigen::AlignedBox3d> boxes(n);
  Eigen::AlignedBox3d all;
  double extent_sum = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    for (const Index i : triangles[t]) boxes[t].extend(vertices[static_cast<std::size_t>(i)]);
    all.extend(boxes[t]);
    extent_sum += boxes[t].sizes().maxCoeff();
  }
  // Cells about the size of a facet, but never more than about 8 per facet along the box, over its largest
  // face or its volume: then even one facet spanning the whole box enters O(n) cells.
  const Vec3 span = all.sizes().cwiseMax(1e-300);
  const double facets = static_cast<double>(n);
  Vec3 sorted = span;
  std::sort(sorted.begin(), sorted.end());
  const double cell =
      std::max({extent_sum / facets, sorted[2] / (8.0 * facets), std::sqrt(sorted[2] * sorted[1] / (8.0 * facets)),
                std::cbrt(span.prod() / (8.0 * facets)), sorted[2] * 1e-6});
  Eigen::Array3i cells;
  for (int d = 0; d < 3; ++d) cells[d] = std::clamp(static_cast<int>(span[d] / cell) + 1, 1, 1 << 10);
  auto cell_of = [&](const Vec3& x) {
    Eigen::Array3i c;
    for (int d = 0; d < 3; ++d)
      c[d] = std::clamp(static_cast<int>((x[d] - all.min()[d]) / span[d] * cells[d]), 0, cells[d] - 1);
    return c;
  };
  auto cell_index = [&](const Eigen::Array3i& c) {
    return static_cast<std::size_t>(c[0]) +
           static_cast<std::size_t>(cells[0]) *
               (static_cast<std::size_t>(c[1]) + static_cast<std::size_t>(cells[1]) * static_cast<std::size_t>(c[2]));
  };

  // Facets per cell (counting sort keeps the facet order deterministic).
  std::vector<std::pair<std::size_t, std::size_t>> entries;  // (cell, facet)
  std::vector<Eigen::Array3i> low(n), high(n);
  for (std::size_t t = 0; t < n; ++t) {
    low[t] = cell_of(boxes[t].min());
    high[t] = cell_of(boxes[t].max());
    for (int z = low[t][2]; z <= high[t][2]; ++z)
      for (int y = low[t][1]; y <= high[t][1]; ++y)
        for (int x = low[t][0]; x <= high[t][0]; ++x) entries.emplace_back(cell_index({x, y, z}), t);
  }
  std::sort(entries.begin(), entries.end());

  for (std::size_t begin = 0; begin < entries.size();) {
    std::size_t end = begin;
    while (end < entries.size() && entries[end].first == entries[begin].first) ++end;
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t j = i + 1; j < end; ++j) {
        const std::size_t a = entries[i].second, b = entries[j].second;
        if (!boxes[a].intersects(boxes[b])) continue;
        // Test each pair once: in the first cell (lowest x, y, z) the two facets' cell ranges share.
        const Eigen::Array3i first = low[a].max(low[b]);
        if (cell_index(first) != entries[begin].first) continue;
        if (facets_cross(vertices, triangles[a], triangles[b])) {
          const std::size_t first_facet = std::min(a, b);
          Vec3 centroid = Vec3::Zero();
          for (const Index k : triangles[first_facet]) centroid += vertices[static_cast<std::size_t>(k)] / 3.0;
          return SurfaceCrossing{first_facet, std::max(a, b), centroid};
        }
      }
    begin = end;
  }
  return std::nullopt;
}

}  // namespace mtled
