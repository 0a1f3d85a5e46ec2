// Consistent integration's correction of the test-function gradients (integration_correction.hpp).
#include "integration_correction.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "mtled/log.hpp"

namespace mtled {

// The corrections: with delta_I(p) = xi_I - mean_{J in p} xi_J, node I's constraint sum_p w_p delta_I(p) = r_I
// reads (L xi)_I = W_I xi_I - sum_{p ni I} w_p mean_p(xi) = r_I, W_I = sum_{p ni I} w_p. L is symmetric positive
// semi-definite (a weighted graph Laplacian of the supports: sum_J L_IJ = 0), its null space the constant
// vectors, which change no delta; r sums to zero (sum_I grad N_I = 0 and sum_I b_I = closed-surface integral
// of n = 0) up to round-off, which is removed. Solved by Jacobi-preconditioned conjugate gradients, matrix-free,
// the three components together.
namespace {

// The coarse level of the correction's two-level preconditioner: the nodes binned into aggregates on a grid
// (about kNodesPerAggregate each), and the operator restricted to them, A_c = P^T A P with P the aggregates'
// indicator vectors, factorised once. A = W - B D B^T (B: node-point incidence of the supports, D = w_p / n_p), so
// A_c = P^T W P - sum_p (w_p / n_p) c_p c_p^T with c_p[a] the number of p's support nodes in aggregate a: built in
// one pass over the points, without applying A. Added to the Jacobi step, it takes out the smooth error Jacobi
// leaves (the operator is a graph Laplacian of the supports: constants are its null space), so conjugate gradients
// need a fraction of the iterations on large clouds.
class CoarseCorrection {
 public:
  static constexpr Index kNodesPerAggregate = 64;
  static constexpr Index kMaxAggregates = 1500;

  CoarseCorrection(const std::vector<Vec3>& nodes, const std::vector<double>& node_weight, const GradientRows& rows,
                   const std::vector<double>& point_weight) {
    const auto n = static_cast<Index>(nodes.size());
    aggregate_ = bin_on_grid(nodes, std::clamp<Index>(n / kNodesPerAggregate, 1, kMaxAggregates));
    const Index m = *std::max_element(aggregate_.begin(), aggregate_.end()) + 1;
    Eigen::MatrixXd coarse = Eigen::MatrixXd::Zero(m, m);
    for (Index i = 0; i < n; ++i) coarse(aggregate_[i], aggregate_[i]) += node_weight[static_cast<std::size_t>(i)];
    std::vector<std::pair<Index, int>> counts;  // the point's aggregates and how many of its nodes lie in each
    for (Index p = 0; p < rows.rows(); ++p) {
      counts.clear();
      for (int k = 0; k < rows.size(p); ++k) {
        const Index a = aggregate_[rows.node(p, k)];
        auto it = std::find_if(counts.begin(), counts.end(), [a](const auto& c) { return c.first == a; });
        if (it == counts.end())
          counts.emplace_back(a, 1);
        else
          ++it->second;
      }
      const double scale = point_weight[static_cast<std::size_t>(p)] / rows.size(p);
      for (const auto& [a, ca] : counts)
        for (const auto& [b, cb] : counts) coarse(a, b) -= scale * ca * cb;
    }
    // Constants are A_c's null space, and the residuals it is given have no mean: adding a multiple of 1 1^T
    // makes it positive definite without changing those solutions.
    coarse.array() += coarse.diagonal().mean() / static_cast<double>(m);
    factor_.compute(coarse);
    // One aggregate holds only the null space: no coarse level (nor where the factorisation failed).
    if (m > 1 && factor_.info() == Eigen::Success) restricted_ = Eigen::MatrixXd::Zero(m, 3);
  }

  // z += P A_c^-1 P^T r.
  void add_to(const std::vector<Vec3>& r, std::vector<Vec3>& z) {
    if (restricted_.rows() == 0) return;
    restricted_.setZero();
    for (std::size_t i = 0; i < r.size(); ++i) restricted_.row(aggregate_[i]) += r[i].transpose();
    factor_.solveInPlace(restricted_);
    for (std::size_t i = 0; i < z.size(); ++i) z[i] += restricted_.row(aggregate_[i]).transpose();
  }
  Index aggregates() const { return static_cast<Index>(restricted_.rows()); }

 private:
  // Each node's cell of a regular grid over the nodes' bounding box with about `cells` occupied cells, numbered
  // densely in order of first appearance.
  static std::vector<Index> bin_on_grid(const std::vector<Vec3>& nodes, Index cells) {
    const auto [lo, hi] = bounding_box(nodes);
    const Vec3 extent = (hi - lo).cwiseMax(Vec3::Constant(1e-300));
    const double side = std::cbrt(extent.prod() / static_cast<double>(cells));
    const Eigen::Array3i divisions = (extent / side).array().ceil().cast<int>().max(1);
    std::vector<Index> cell_number(static_cast<std::size_t>(divisions.prod()), -1), out(nodes.size());
    Index next = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const Eigen::Array3i c = (((nodes[i] - lo).array() / extent.array()) * divisions.cast<double>())
                                   .floor()
                                   .cast<int>()
                                   .min(divisions - 1);
      Index& number = cell_number[static_cast<std::size_t>((c[2] * divisions[1] + c[1]) * divisions[0] + c[0])];
      if (number < 0) number = next++;
      out[i] = number;
    }
    return out;
  }

  std::vector<Index> aggregate_;
  Eigen::LLT<Eigen::MatrixXd> factor_;
  Eigen::MatrixXd restricted_;
};

std::vector<Vec3> solve_correction(const std::vector<Vec3>& nodes, const GradientRows& rows,
                                   const std::vector<double>& weights, std::vector<Vec3> r) {
  const auto start = std::chrono::steady_clock::now();
  const Index n = static_cast<Index>(nodes.size()), points = rows.rows();
  // Each node's integration points (the transpose of the rows), for the product in node order.
  const SupportRows node_points = transpose_rows(points, n, [&](Index ip, auto&& add) {
    for (int k = 0; k < rows.size(ip); ++k) add(rows.node(ip, k));
  });
  const std::vector<std::int64_t>& first = node_points.offsets;
  std::vector<double> W(static_cast<std::size_t>(n), 0.0), diagonal(static_cast<std::size_t>(n), 0.0);
  for (Index i = 0; i < n; ++i)
    for (auto e = first[i]; e < first[i + 1]; ++e) {
      const Index ip = node_points.nodes[e];
      W[i] += weights[ip];
      diagonal[i] += weights[ip] * (1.0 - 1.0 / rows.size(ip));
    }
  // w_p mean_p(x) per point, then summed per node: the weight goes in with the mean, so the second pass reads
  // one array at the scattered points instead of two.
  // x by the kernel's slots (GradientRows::slot) for the first pass: the rows' records name slots, which follow the
  // rows' order of first use, so the pass reads x nearly in order and without a slot-to-node lookup per entry.
  std::vector<Vec3> weighted_mean(static_cast<std::size_t>(points)), x_at_slot(static_cast<std::size_t>(n));
  const auto apply = [&](const std::vector<Vec3>& x, std::vector<Vec3>& y) {
    for (Index i = 0; i < n; ++i) x_at_slot[static_cast<std::size_t>(rows.slot(i))] = x[i];
#pragma omp parallel for schedule(static)
    for (Index ip = 0; ip < points; ++ip) {
      Vec3 sum = Vec3::Zero();
      for (int k = 0; k < rows.size(ip); ++k) sum += x_at_slot[rows.entry_slot(ip, k)];
      weighted_mean[ip] = (weights[ip] / rows.size(ip)) * sum;
    }
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) {
      Vec3 sum = Vec3::Zero();
      for (auto e = first[i]; e < first[i + 1]; ++e) sum += weighted_mean[node_points.nodes[e]];
      y[i] = W[i] * x[i] - sum;
    }
  };
  Vec3 drift = Vec3::Zero();
  for (const Vec3& v : r) drift += v;
  for (Vec3& v : r) v -= drift / n;
  std::vector<Vec3> x(static_cast<std::size_t>(n), Vec3::Zero()), z(r.size()), p(r.size()), q(r.size());
  const auto dot = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    Vec3 s = Vec3::Zero();
    for (std::size_t i = 0; i < a.size(); ++i) s += a[i].cwiseProduct(b[i]);
    return s;
  };
  CoarseCorrection coarse(nodes, W, rows, weights);
  const auto precondition = [&](const std::vector<Vec3>& from, std::vector<Vec3>& to) {
    for (Index i = 0; i < n; ++i) to[i] = diagonal[i] > 0.0 ? Vec3(from[i] / diagonal[i]) : Vec3::Zero();
    coarse.add_to(from, to);
  };
  precondition(r, z);
  p = z;
  Vec3 rz = dot(r, z);
  const Vec3 target = 1e-24 * dot(r, r).cwiseMax(Vec3::Constant(1e-300));  // |r| down by 1e12
  int iteration = 0;
  for (; iteration < 20000 && (dot(r, r).array() > target.array()).any(); ++iteration) {
    apply(p, q);
    const Vec3 pq = dot(p, q);
    for (Index i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d)
        if (pq[d] > 0.0) {
          x[i][d] += rz[d] / pq[d] * p[i][d];
          r[i][d] -= rz[d] / pq[d] * q[i][d];
        }
    precondition(r, z);
    const Vec3 rz_next = dot(r, z);
    for (Index i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) p[i][d] = z[i][d] + (rz[d] > 0.0 ? rz_next[d] / rz[d] : 0.0) * p[i][d];
    rz = rz_next;
  }
  log().debug(
      "consistent integration: corrections solved in {} conjugate-gradient iterations ({} aggregates on the "
      "coarse level), {:.2f} s",
      iteration, coarse.aggregates(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return x;
}

}  // namespace

std::vector<Vec3> integration_correction(const TetMesh& mesh, const GradientRows& rows,
                                         const SupportRows& interpolation, const std::vector<double>& weights) {
  const Index n = mesh.node_count(), points = rows.rows();
  // Boundary integral b_I = int_Gamma N_I n dGamma by vertex quadrature: each boundary triangle gives a third
  // of its area vector to each of its vertices K, and N_I is evaluated at the nodes (the rows used for
  // interpolation). With the same points as the nodal constraints, the boundary term P b_I of a homogeneous
  // stress is exactly sum_K N_I(X_K) (P A_K): reactions at the constrained nodes can balance it, so the patch
  // test holds to the steady-state tolerance (a Gauss rule on the faces leaves an O(h) mismatch).
  std::vector<Vec3> area(static_cast<std::size_t>(n), Vec3::Zero());
  for (const auto& f : boundary_faces(mesh)) {
    const Vec3& a = mesh.points[f[0]];
    const Vec3 share = (mesh.points[f[1]] - a).cross(mesh.points[f[2]] - a) / 6.0;  // area / 3, outward
    for (Index v : f) area[v] += share;
  }
  // r_I = b_I - sum_ip w grad N_I: what the corrections must add to node I's gradient integral.
  std::vector<Vec3> residual(static_cast<std::size_t>(n), Vec3::Zero());
  for (Index k = 0; k < n; ++k) {
    if (area[k].squaredNorm() == 0.0) continue;  // interior node
    for (std::int64_t e = interpolation.offsets[k]; e < interpolation.offsets[k + 1]; ++e)
      residual[interpolation.nodes[e]] += interpolation.values[e] * area[k];
  }
  for (Index ip = 0; ip < points; ++ip)
    for (int k = 0; k < rows.size(ip); ++k) residual[rows.node(ip, k)] -= weights[ip] * rows.gradient(ip, k);
  return solve_correction(mesh.points, rows, weights, std::move(residual));
}

}  // namespace mtled
