#include "mtled/analysis/grid_field.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "mtled/analysis/mls_transfer.hpp"
#include "mtled/log.hpp"
#include "mtled/scope_timer.hpp"

namespace mtled {

namespace {

// Calls visit(voxel, barycentric coordinates of its centre) for each voxel whose centre lies in the tet with vertices
// x (on a face counts: a voxel on a face shared by two tets is visited by both).
template <class Visit>
void rasterize(const VoxelGrid& grid, const Mat3& to_index, const std::array<Vec3, 4>& x, std::int64_t k_first,
               std::int64_t k_last, Visit&& visit) {
  Mat3 edges;
  for (int c = 0; c < 3; ++c) edges.col(c) = x[static_cast<std::size_t>(c) + 1] - x[0];
  const double volume = edges.determinant();
  if (!(std::abs(volume) > 0.0)) return;
  const Mat3 to_barycentric = edges.inverse();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : x) {
    const Vec3 q = to_index * (p - grid.origin);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  std::array<std::int64_t, 3> first{}, last{};
  for (std::size_t a = 0; a < 3; ++a) {
    first[a] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo[static_cast<Index>(a)] - 1e-9)));
    last[a] = std::min<std::int64_t>(grid.size[a] - 1,
                                     static_cast<std::int64_t>(std::floor(hi[static_cast<Index>(a)] + 1e-9)));
  }
  constexpr double kOnFace = -1e-12;
  for (std::int64_t k = std::max(first[2], k_first); k <= std::min(last[2], k_last); ++k)
    for (std::int64_t j = first[1]; j <= last[1]; ++j)
      for (std::int64_t i = first[0]; i <= last[0]; ++i) {
        const Vec3 b = to_barycentric * (grid.centre(i, j, k) - x[0]);
        const double b0 = 1.0 - b.sum();
        if (b0 >= kOnFace && b.minCoeff() >= kOnFace)
          visit(grid.index(i, j, k), std::array<double, 4>{b0, b[0], b[1], b[2]});
      }
}

std::array<Vec3, 4> vertices(const std::vector<Vec3>& points, const std::array<Index, 4>& tet) {
  return {points[static_cast<std::size_t>(tet[0])], points[static_cast<std::size_t>(tet[1])],
          points[static_cast<std::size_t>(tet[2])], points[static_cast<std::size_t>(tet[3])]};
}

// rasterize() for every tet (vertices at `points`): visit(tet, voxel, barycentric coordinates). The grid is cut into
// slabs of a few k-planes, done in parallel; within a slab the tets go in order, so a voxel sees the tets in the
// order a serial loop would, and only one thread writes it.
template <class Visit>
void rasterize_all(const VoxelGrid& grid, const std::vector<Vec3>& points,
                   const std::vector<std::array<Index, 4>>& tets, Visit&& visit) {
  const Mat3 to_index = grid.axes.inverse();
  constexpr std::int64_t kSlab = 4;
  const std::int64_t slabs = (grid.size[2] + kSlab - 1) / kSlab;
  std::vector<std::vector<std::uint32_t>> members(static_cast<std::size_t>(slabs));
  for (std::size_t t = 0; t < tets.size(); ++t) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& p : vertices(points, tets[t])) {
      const double k = to_index.row(2).dot(p - grid.origin);
      lo = std::min(lo, k);
      hi = std::max(hi, k);
    }
    const auto first = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo - 1e-9)) / kSlab);
    const auto last = std::min<std::int64_t>(slabs - 1, static_cast<std::int64_t>(std::floor(hi + 1e-9)) / kSlab);
    for (std::int64_t slab = first; slab <= last; ++slab)
      members[static_cast<std::size_t>(slab)].push_back(static_cast<std::uint32_t>(t));
  }
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t slab = 0; slab < slabs; ++slab)
    for (const std::uint32_t t : members[static_cast<std::size_t>(slab)])
      rasterize(grid, to_index, vertices(points, tets[t]), slab * kSlab, slab * kSlab + kSlab - 1,
                [&](std::int64_t v, const std::array<double, 4>& b) { visit(t, v, b); });
}

void forward(const BodyState& body, const VoxelGrid& grid, const MlsTransfer& transfer, GridField& out) {
  auto& inside = out.inside_body;
  rasterize_all(grid, body.nodes, body.tets, [&](std::uint32_t, std::int64_t v, const std::array<double, 4>&) {
    inside[static_cast<std::size_t>(v)] = 1;
  });
  std::int64_t count = 0;
  // Slices in parallel (MlsTransfer is thread-safe), handed out as they finish: the body fills them unevenly.
#pragma omp parallel for schedule(dynamic) reduction(+ : count)
  for (std::int64_t k = 0; k < grid.size[2]; ++k)
    for (std::int64_t j = 0; j < grid.size[1]; ++j)
      for (std::int64_t i = 0; i < grid.size[0]; ++i) {
        const auto v = static_cast<std::size_t>(grid.index(i, j, k));
        if (!inside[v]) continue;
        ++count;
        out.values[v] = transfer.at(grid.centre(i, j, k), body.displacement);
      }
  out.inside = count;
}

// Where tet t's linear map takes the moved point x back: the reference point with x's barycentric coordinates in the
// moved tet (computed as rasterize() computes them, so the same bits).
Vec3 reference_point(const BodyState& body, const std::vector<Vec3>& moved, std::uint32_t t, const Vec3& x) {
  const auto at = vertices(moved, body.tets[t]);
  const auto reference = vertices(body.nodes, body.tets[t]);
  Mat3 edges;
  for (int c = 0; c < 3; ++c) edges.col(c) = at[static_cast<std::size_t>(c) + 1] - at[0];
  const Vec3 b = edges.inverse() * (x - at[0]);
  return (1.0 - b.sum()) * reference[0] + b[0] * reference[1] + b[1] * reference[2] + b[2] * reference[3];
}

// Newton's method on X + u(X) = x with u's MLS gradient, from X (the prediction along the row; where u cannot be read
// there, the moved tet's linear map, `fallback()`); it stops where a step no longer lowers the residual (a point the
// moved tets fold over). X and jacobian (I + du/dX there) are left at the last point accepted; returns its residual.
template <class Fallback>
Vec3 solve_reference_point(const MlsTransfer& transfer, const std::vector<Vec3>& displacement, const Vec3& x,
                           double tolerance, Vec3& X, Mat3& jacobian, Fallback&& fallback) {
  const auto residual = [&](const Vec3& at, Mat3& J) {
    const Vec3 r = at + transfer.at(at, displacement, J) - x;
    J += Mat3::Identity();
    return r;
  };
  Vec3 r;
  try {
    r = residual(X, jacobian);
  } catch (const std::runtime_error&) {  // a prediction out of the cloud
    X = fallback();
    r = residual(X, jacobian);
  }
  for (int iteration = 0; iteration < 30 && r.norm() > tolerance; ++iteration) {
    const Vec3 next = X - jacobian.partialPivLu().solve(r);
    Mat3 next_jacobian;
    Vec3 r_next;
    try {
      r_next = residual(next, next_jacobian);
    } catch (const std::runtime_error&) {  // a step out of the cloud, where MLS has no neighbourhood
      break;
    }
    if (!(r_next.norm() < r.norm())) break;
    X = next;
    r = r_next;
    jacobian = next_jacobian;
  }
  return r;
}

void resampling(const BodyState& body, const VoxelGrid& grid, const MlsTransfer& transfer, double tolerance,
                GridField& out) {
  std::vector<Vec3> moved(body.nodes.size());
  for (std::size_t n = 0; n < moved.size(); ++n) moved[n] = body.nodes[n] + body.displacement[n];
  // Per voxel: the first moved tet found around its centre (its linear map gives Newton's first guess), and whether
  // another moved tet holds the centre too with a different reference point.
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  if (body.tets.size() >= kNone) throw std::invalid_argument("displacement_on_grid: 2^32 tets or more");
  LargeVector<std::uint32_t> found = large_vector(static_cast<std::size_t>(grid.count()), kNone);
  LargeVector<char> folded = large_vector<char>(found.size(), 0);
  const auto centre_of = [&](std::int64_t v) {
    return grid.centre(v % grid.size[0], (v / grid.size[0]) % grid.size[1], v / (grid.size[0] * grid.size[1]));
  };
  PhaseLog phases;
  rasterize_all(grid, moved, body.tets, [&](std::uint32_t t, std::int64_t v, const std::array<double, 4>& b) {
    const auto s = static_cast<std::size_t>(v);
    if (found[s] == kNone) {
      found[s] = t;
      return;
    }
    const auto reference = vertices(body.nodes, body.tets[t]);
    const Vec3 X = b[0] * reference[0] + b[1] * reference[1] + b[2] * reference[2] + b[3] * reference[3];
    if ((X - reference_point(body, moved, found[s], centre_of(v))).norm() > 1e-6 * (reference[1] - reference[0]).norm())
      folded[s] = 1;  // two moved tets hold the point with different reference points: not a shared face
  });
  phases.lap("voxel centres found in the moved tets");
  std::int64_t inside = 0, overlapping = 0, not_converged = 0;
  double largest = 0.0;
#pragma omp parallel for schedule(dynamic) reduction(+ : inside, overlapping, not_converged) reduction(max : largest)
  for (std::int64_t k = 0; k < grid.size[2]; ++k)
    for (std::int64_t j = 0; j < grid.size[1]; ++j) {
      // The last voxel solved on this row, to predict the next one from: X + (I + du/dX)^-1 (x - x_last).
      bool have_last = false;
      Vec3 last_x, last_X;
      Mat3 last_jacobian;
      for (std::int64_t i = 0; i < grid.size[0]; ++i) {
        const auto v = static_cast<std::size_t>(grid.index(i, j, k));
        if (found[v] == kNone) {
          have_last = false;
          continue;
        }
        ++inside;
        out.inside_body[v] = 1;
        overlapping += folded[v];
        const Vec3 x = grid.centre(i, j, k);
        Mat3 jacobian;
        Vec3 X = have_last ? Vec3(last_X + last_jacobian.partialPivLu().solve(x - last_x))
                           : reference_point(body, moved, found[v], x);
        const Vec3 r = solve_reference_point(transfer, body.displacement, x, tolerance, X, jacobian,
                                             [&] { return reference_point(body, moved, found[v], x); });
        const bool converged = r.norm() <= tolerance;
        not_converged += !converged;
        if (!converged) {
#pragma omp critical(not_converged_voxels)
          out.not_converged_voxels.push_back(static_cast<std::int64_t>(v));
        }
        largest = std::max(largest, r.norm());
        out.values[v] = X - x;
        have_last = converged;
        last_x = x;
        last_X = X;
        last_jacobian = jacobian;
      }
    }
  phases.lap("X + u(X) = x solved at each of them");
  out.inside = inside;
  out.overlapping = overlapping;
  out.not_converged = not_converged;
  std::sort(out.not_converged_voxels.begin(), out.not_converged_voxels.end());  // the same list on any thread count
  out.largest_residual = largest;
}

}  // namespace

GridField displacement_on_grid(const BodyState& body, const VoxelGrid& grid, FieldDirection direction,
                               PluginCatalog& catalog, double tolerance) {
  GridField out;
  out.values = large_vector<Vec3>(static_cast<std::size_t>(grid.count()), Vec3::Zero());
  out.inside_body = large_vector<char>(out.values.size(), 0);
  PhaseLog phases;
  const MlsTransfer transfer(body.nodes, catalog);
  phases.lap("the nodes' supports binned");
  if (direction == FieldDirection::forward)
    forward(body, grid, transfer, out);
  else
    resampling(body, grid, transfer, tolerance, out);
  return out;
}

namespace {

// One line of the squared Euclidean distance transform with its nearest sites (Felzenszwalb and Huttenlocher,
// "Distance transforms of sampled functions", Theory of Computing 8, 2012): d(p) = min_q (h (p - q))^2 + f(q), the
// lower envelope of the parabolas rooted at the q where f is finite. `site` goes along with each q's value.
struct Envelope {
  std::vector<std::int64_t> roots;
  std::vector<double> bounds;
  std::vector<double> values;       // the line's values before the transform, reused from line to line
  std::vector<std::int64_t> sites;  // and their sites

  void transform(std::vector<double>& f, std::vector<std::int64_t>& site, double h) {
    const auto n = static_cast<std::int64_t>(f.size());
    const double h2 = h * h;
    roots.clear();
    bounds.clear();
    const auto meet = [&](std::int64_t q, std::int64_t r) {  // where the parabolas of q > r cross
      return ((f[std::size_t(q)] + h2 * double(q * q)) - (f[std::size_t(r)] + h2 * double(r * r))) /
             (2.0 * h2 * double(q - r));
    };
    for (std::int64_t q = 0; q < n; ++q) {
      if (!std::isfinite(f[std::size_t(q)])) continue;
      double s = -std::numeric_limits<double>::infinity();
      while (!roots.empty() && (s = meet(q, roots.back())) <= bounds.back()) {
        roots.pop_back();
        bounds.pop_back();
        s = -std::numeric_limits<double>::infinity();
      }
      roots.push_back(q);
      bounds.push_back(s);  // this parabola is lowest from s on
    }
    if (roots.empty()) return;
    values.assign(f.begin(), f.end());
    sites.assign(site.begin(), site.end());
    std::size_t k = 0;
    for (std::int64_t p = 0; p < n; ++p) {
      while (k + 1 < roots.size() && bounds[k + 1] <= double(p)) ++k;
      const std::int64_t q = roots[k];
      f[std::size_t(p)] = h2 * double((p - q) * (p - q)) + values[std::size_t(q)];
      site[std::size_t(p)] = sites[std::size_t(q)];
    }
  }
};

}  // namespace

double extend_outside(const VoxelGrid& grid, double decay, GridField& field) {
  const auto& n = grid.size;
  const std::int64_t count = grid.count();
  const Vec3 spacing = grid.spacing();  // the axes are orthogonal (the image readers check it)
  constexpr std::int64_t kNone = -1;
  // Per voxel, the squared distance to the nearest voxel inside and that voxel, exact: one pass along each index
  // axis, each line on its own (so the lines go in parallel).
  LargeVector<double> distance2(static_cast<std::size_t>(count));
  LargeVector<std::int64_t> nearest(distance2.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t v = 0; v < count; ++v) {
    const bool inside = field.inside_body[static_cast<std::size_t>(v)] != 0;
    distance2[static_cast<std::size_t>(v)] = inside ? 0.0 : std::numeric_limits<double>::infinity();
    nearest[static_cast<std::size_t>(v)] = inside ? v : kNone;
  }
  const std::int64_t stride[3] = {1, n[0], n[0] * n[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;  // the other two axes span the lines' starts
    const std::int64_t length = n[std::size_t(axis)];
#pragma omp parallel
    {
      Envelope envelope;
      std::vector<double> line(static_cast<std::size_t>(length));
      std::vector<std::int64_t> line_sites(line.size());
#pragma omp for collapse(2) schedule(static)
      for (std::int64_t y = 0; y < n[std::size_t(b)]; ++y)
        for (std::int64_t x = 0; x < n[std::size_t(a)]; ++x) {
          const std::int64_t first = x * stride[a] + y * stride[b];
          for (std::int64_t p = 0; p < length; ++p) {
            line[std::size_t(p)] = distance2[std::size_t(first + p * stride[axis])];
            line_sites[std::size_t(p)] = nearest[std::size_t(first + p * stride[axis])];
          }
          envelope.transform(line, line_sites, spacing[axis]);
          for (std::int64_t p = 0; p < length; ++p) {
            distance2[std::size_t(first + p * stride[axis])] = line[std::size_t(p)];
            nearest[std::size_t(first + p * stride[axis])] = line_sites[std::size_t(p)];
          }
        }
    }
  }
  double largest = 0.0;
#pragma omp parallel for schedule(static) reduction(max : largest)
  for (std::int64_t v = 0; v < count; ++v) {
    const auto s = static_cast<std::size_t>(v);
    if (field.inside_body[s] || nearest[s] == kNone) continue;
    const double t = std::sqrt(distance2[s]) / decay;
    if (!(t < 1.0)) continue;
    const Vec3& surface = field.values[static_cast<std::size_t>(nearest[s])];
    largest = std::max(largest, surface.norm());
    field.values[s] = (1.0 - t * t * (3.0 - 2.0 * t)) * surface;
  }
  return largest;
}

}  // namespace mtled
