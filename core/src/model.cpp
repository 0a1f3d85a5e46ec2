#include "mtled/model.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include "force_kernel.hpp"
#include "mtled/log.hpp"

namespace mtled {

namespace {

// 4-point rule on a tet, exact for quadratics: barycentric (a, b, b, b) and permutations, weight V/4.
constexpr double kQuadA = 0.5854101966249685;
constexpr double kQuadB = 0.1381966011250105;

std::string point_text(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g}) m", x[0], x[1], x[2]); }

struct RowFailure {
  Index row = std::numeric_limits<Index>::max();
  std::string message;
};

// F = I + sum_I u_I (x) grad N_I over one row, u 3 per node: for diagnostics and output, one point at a time.
Mat3 deformation_gradient_at(const GradientRows& rows, Index ip, const double* u) {
  Mat3 F = Mat3::Identity();
  for (int k = 0; k < rows.size(ip); ++k) {
    const double* ui = u + 3 * static_cast<std::size_t>(rows.node(ip, k));
    F += Vec3(ui[0], ui[1], ui[2]) * rows.gradient(ip, k).transpose();
  }
  return F;
}

// The largest eigenvalue of the first elasticity tensor dP/dF (P = F S) at F, a 9 x 9 matrix symmetrised (a
// hyperelastic law's is symmetric), by forward differences of the law's stress: the modulus that sets how fast the
// point's stiffest wave travels in the reference configuration. The ten stresses in two of the law's batches; the
// eigenvalue by power iteration from the volumetric direction, which the stiffest mode of a nearly incompressible
// solid is close to (a Rayleigh quotient: never above the eigenvalue). 0 where the law refuses F or a perturbation.
double largest_tangent_modulus(const Material& material, const Mat3& F) {
  const double h = 1e-6 * std::max(1.0, F.cwiseAbs().maxCoeff());
  std::array<StressBatch, 2> batches{};
  for (int lane = 0; lane < 2 * StressBatch::kCapacity; ++lane) {
    // Lanes 0-8: F + h e_c; lane 9: F; the rest F = I (a law may compute every lane).
    StressBatch& batch = batches[static_cast<std::size_t>(lane / StressBatch::kCapacity)];
    const int p = lane % StressBatch::kCapacity;
    Mat3 m = lane <= 9 ? F : Mat3::Identity();
    if (lane < 9) m(lane / 3, lane % 3) += h;
    batch.set_deformation_gradient(p, m);
  }
  batches[0].count = StressBatch::kCapacity;
  batches[1].count = 2;
  for (StressBatch& batch : batches) material.stress_batch(batch);
  auto first_piola = [&](int lane) -> std::optional<Mat3> {
    const StressBatch& batch = batches[static_cast<std::size_t>(lane / StressBatch::kCapacity)];
    const int p = lane % StressBatch::kCapacity;
    if (!batch.admissible[p]) return std::nullopt;
    return batch.deformation_gradient(p) * batch.stress(p);
  };
  const std::optional<Mat3> P = first_piola(9);
  if (!P) return 0.0;
  Eigen::Matrix<double, 9, 9> tangent;
  for (int c = 0; c < 9; ++c) {
    const std::optional<Mat3> perturbed = first_piola(c);
    if (!perturbed) return 0.0;
    const Mat3 dP = (*perturbed - *P) / h;
    for (int r = 0; r < 9; ++r) tangent(r, c) = dP(r / 3, r % 3);
  }
  const Eigen::Matrix<double, 9, 9> symmetric = 0.5 * (tangent + tangent.transpose());
  const Mat3 volumetric = F.inverse().transpose();
  Eigen::Matrix<double, 9, 1> x;
  for (int r = 0; r < 9; ++r) x[r] = volumetric(r / 3, r % 3);
  double eigenvalue = 0.0;
  for (int iteration = 0; iteration < 20; ++iteration) {
    x.normalize();
    const Eigen::Matrix<double, 9, 1> y = symmetric * x;
    eigenvalue = x.dot(y);
    x = y;
  }
  return eigenvalue;
}

// Morton (Z-order) keys of the tets' centroids, 21 bits per axis of the mesh's bounding box: sorting by them puts
// cells that are close in space close in the order.
std::vector<std::uint64_t> morton_keys(const TetMesh& mesh) {
  constexpr std::uint64_t kCells = (std::uint64_t{1} << 21) - 1;
  // Spreads the low 21 bits of x to every third bit.
  auto spread = [](std::uint64_t x) {
    x &= kCells;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
  };
  const auto [lo, hi] = bounding_box(mesh.points);
  const double extent = std::max((hi - lo).maxCoeff(), std::numeric_limits<double>::min());
  std::vector<std::uint64_t> key(mesh.tets.size());
  for (std::size_t t = 0; t < key.size(); ++t) {
    const Vec3 centroid = tet_centroid(mesh, static_cast<Index>(t));
    std::uint64_t code = 0;
    for (int c = 0; c < 3; ++c) {
      const double cell = (centroid[c] - lo[c]) / extent * static_cast<double>(kCells);
      code |= spread(static_cast<std::uint64_t>(std::clamp(cell, 0.0, static_cast<double>(kCells)))) << c;
    }
    key[t] = code;
  }
  return key;
}

}  // namespace

Model::Model(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
             std::vector<std::shared_ptr<const Material>> region_materials, Options options)
    : mesh_(std::move(mesh)), shape_functions_(std::move(shape_functions)), materials_(std::move(region_materials)) {
  if (materials_.size() != mesh_.region_names.size())
    throw std::logic_error("Model: one material per mesh region is required");
  if (materials_.size() > std::numeric_limits<std::uint16_t>::max())
    throw InputError(mesh_.source, "more than 65535 material regions");
  surface_ = surface_nodes(mesh_);
  spacing_ = mean_edge_length_at_nodes(mesh_);
  const double dilatation = shape_functions_->support_dilatation();
  radius_.resize(spacing_.size());
  for (std::size_t i = 0; i < spacing_.size(); ++i) radius_[i] = dilatation * spacing_[i];
  max_radius_ = *std::max_element(radius_.begin(), radius_.end());
  const auto [lo, hi] = bounding_box(mesh_.points);
  length_scale_ = (hi - lo).norm();
  node_search_ = std::make_unique<PointSearch>(mesh_.points);

  build_integration_points(options.integration_points_per_tet, options.cell_groups);
  build_supports(options.precision);
  build_time_steps();
  const std::size_t padded = 4 * (static_cast<std::size_t>(node_count()) + 1);
  xi_.assign(padded, 0.0);
  xi_mean_.assign(3 * static_cast<std::size_t>(integration_point_count()), 0.0);
  if (options.consistent_integration) build_integration_correction();
  padded_u_.assign(padded, 0.0);
  team_ = std::make_unique<ThreadTeam>(options.threads > 0 ? options.threads : omp_get_max_threads());
  thread_forces_.resize(static_cast<std::size_t>(team_->size()));
  for (auto& buffer : thread_forces_) buffer.assign(padded, 0.0);
  thread_first_bad_.assign(thread_forces_.size(), std::numeric_limits<Index>::max());
  volumetric_ = std::move(options.volumetric);
  view_ = std::make_unique<ModelView>(*this);
  if (volumetric_) volumetric_->setup(*this);
}

Model::~Model() = default;

void Model::build_integration_points(int points_per_tet, const std::vector<int>& cell_groups) {
  if (points_per_tet != 1 && points_per_tet != 4)
    throw InputError("/discretisation/integration_points_per_tet", "must be 1 or 4");
  if (!cell_groups.empty() && cell_groups.size() != mesh_.tets.size())
    throw std::logic_error("Model: one cell group per tet is required");
  const std::size_t count = mesh_.tets.size() * static_cast<std::size_t>(points_per_tet);
  ip_position_.reserve(count);
  ip_weight_.reserve(count);
  ip_tet_.reserve(count);
  ip_material_.reserve(count);
  std::vector<Index> order(mesh_.tets.size());
  std::iota(order.begin(), order.end(), Index{0});
  const int groups = cell_groups.empty() ? 1 : *std::max_element(cell_groups.begin(), cell_groups.end()) + 1;
  group_offsets_.assign(static_cast<std::size_t>(groups) + 1, 0);
  // Integration points follow their cells along a Morton curve (within a cell group and a region, so a group stays
  // one range of points and a region's points form long one-material batches): consecutive points then share most
  // of their support nodes, and the force kernel finds their records in cache. The mesh generator's order scatters
  // them (the brain phantom's force kernel took 1.47x as long in it, the default scene's 1.22x).
  const std::vector<std::uint64_t> key = morton_keys(mesh_);
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
    const int group_a = cell_groups.empty() ? 0 : cell_groups[a], group_b = cell_groups.empty() ? 0 : cell_groups[b];
    if (group_a != group_b) return group_a < group_b;
    if (mesh_.tet_region[a] != mesh_.tet_region[b]) return mesh_.tet_region[a] < mesh_.tet_region[b];
    return key[a] < key[b];
  });
  if (!cell_groups.empty()) {
    for (const int g : cell_groups) group_offsets_[static_cast<std::size_t>(g) + 1] += points_per_tet;
  } else {
    group_offsets_[1] = static_cast<Index>(count);
  }
  std::partial_sum(group_offsets_.begin(), group_offsets_.end(), group_offsets_.begin());
  for (const Index t : order) {
    const auto& tet = mesh_.tets[t];
    const double volume = tet_volume(mesh_, t);
    const Vec3* v[4] = {&mesh_.points[tet[0]], &mesh_.points[tet[1]], &mesh_.points[tet[2]], &mesh_.points[tet[3]]};
    const auto material = static_cast<std::uint16_t>(mesh_.tet_region[t]);
    if (points_per_tet == 1) {
      ip_position_.push_back((*v[0] + *v[1] + *v[2] + *v[3]) / 4.0);
      ip_weight_.push_back(volume);
      ip_tet_.push_back(t);
      ip_material_.push_back(material);
    } else {
      for (int k = 0; k < 4; ++k) {
        Vec3 x = Vec3::Zero();
        for (int j = 0; j < 4; ++j) x += (j == k ? kQuadA : kQuadB) * *v[j];
        ip_position_.push_back(x);
        ip_weight_.push_back(volume / 4.0);
        ip_tet_.push_back(t);
        ip_material_.push_back(material);
      }
    }
  }
  every_point_ = {0, integration_point_count()};
}

std::vector<std::vector<Index>> Model::find_supports(const std::vector<Vec3>& points, const char* what) const {
  const int needed = shape_functions_->minimum_support_size();
  const Index n = static_cast<Index>(points.size());
  std::vector<std::vector<Index>> support(points.size());
  std::vector<RowFailure> failures(static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel
  {
    std::vector<Index> candidates;
    RowFailure& failure = failures[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (Index r = 0; r < n; ++r) {
      node_search_->within(points[r], max_radius_, candidates);
      auto& s = support[r];
      for (Index i : candidates)
        if ((mesh_.points[i] - points[r]).norm() < radius_[i]) s.push_back(i);
      std::sort(s.begin(), s.end());
      if (static_cast<int>(s.size()) < needed && r < failure.row) {
        failure.row = r;
        failure.message = fmt::format(
            "{} {} at {} lies in the support of only {} nodes; the shape functions need at least {}. Increase "
            "/shape_function/support_dilatation (now {:g}) or use a finer, more even mesh",
            what, r, point_text(points[r]), s.size(), needed, shape_functions_->support_dilatation());
      }
    }
  }
  for (const auto& f : failures)
    if (f.row != std::numeric_limits<Index>::max()) throw InputError("/shape_function", f.message);
  return support;
}

template <class Store>
double Model::evaluate_rows(const std::vector<Vec3>& points, const std::vector<std::vector<Index>>& supports,
                            bool gradients, const char* what, Store store) const {
  const Index n = static_cast<Index>(points.size());
  std::vector<RowFailure> failures(static_cast<std::size_t>(omp_get_max_threads()));
  std::vector<double> min_condition(static_cast<std::size_t>(omp_get_max_threads()), 1.0);
#pragma omp parallel
  {
    std::vector<Vec3> coordinates, grads;
    std::vector<double> radii, values;
    RowFailure& failure = failures[static_cast<std::size_t>(omp_get_thread_num())];
    double& condition = min_condition[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (Index r = 0; r < n; ++r) {
      const auto& s = supports[r];
      coordinates.resize(s.size());
      radii.resize(s.size());
      values.resize(s.size());
      grads.resize(gradients ? s.size() : 0);
      for (std::size_t k = 0; k < s.size(); ++k) {
        coordinates[k] = mesh_.points[s[k]];
        radii[k] = radius_[s[k]];
      }
      const ShapeFunctionFit fit = shape_functions_->evaluate(points[r], coordinates, radii, values, grads);
      condition = std::min(condition, fit.reciprocal_condition);
      if (!fit.ok && r < failure.row) {
        failure.row = r;
        failure.message = fmt::format(
            "the shape functions cannot be built at {} {} at {}: its {} support nodes are too few or nearly "
            "coplanar (reciprocal condition {:.2g}). Increase /shape_function/support_dilatation (now {:g})",
            what, r, point_text(points[r]), s.size(), fit.reciprocal_condition, shape_functions_->support_dilatation());
      }
      for (std::size_t k = 0; k < s.size(); ++k)
        store(r, static_cast<int>(k), values[k], gradients ? grads[k] : Vec3::Zero());
    }
  }
  for (const auto& f : failures)
    if (f.row != std::numeric_limits<Index>::max()) throw InputError("/shape_function", f.message);
  return *std::min_element(min_condition.begin(), min_condition.end());
}

void Model::build_supports(RowPrecision precision) {
  {
    const auto supports = find_supports(ip_position_, "integration point");
    ip_rows_.assign(supports, node_count(), precision);
    ip_stats_.min_reciprocal_condition =
        evaluate_rows(ip_position_, supports, true, "integration point",
                      [&](Index r, int k, double, const Vec3& gradient) { ip_rows_.set_gradient(r, k, gradient); });
    ip_stats_.min = std::numeric_limits<Index>::max();
    ip_stats_.max = 0;
    for (Index r = 0; r < ip_rows_.rows(); ++r) {
      ip_stats_.min = std::min(ip_stats_.min, ip_rows_.size(r));
      ip_stats_.max = std::max(ip_stats_.max, ip_rows_.size(r));
    }
    ip_stats_.mean = static_cast<double>(ip_rows_.entries()) / std::max<Index>(ip_rows_.rows(), 1);
  }
  {
    const auto supports = find_supports(mesh_.points, "node");
    node_rows_.offsets.assign(supports.size() + 1, 0);
    for (std::size_t r = 0; r < supports.size(); ++r)
      node_rows_.offsets[r + 1] = node_rows_.offsets[r] + static_cast<std::int64_t>(supports[r].size());
    node_rows_.nodes.resize(static_cast<std::size_t>(node_rows_.offsets.back()));
    node_rows_.values.resize(node_rows_.nodes.size());
    for (std::size_t r = 0; r < supports.size(); ++r)
      std::copy(supports[r].begin(), supports[r].end(), node_rows_.nodes.begin() + node_rows_.offsets[r]);
    evaluate_rows(mesh_.points, supports, false, "node", [&](Index r, int k, double value, const Vec3&) {
      node_rows_.values[static_cast<std::size_t>(node_rows_.offsets[r] + k)] = value;
    });
  }

  // Every node must carry mass: it must lie in the support of some integration point.
  std::vector<char> used(mesh_.points.size(), 0);
  for (Index ip = 0; ip < ip_rows_.rows(); ++ip)
    for (int k = 0; k < ip_rows_.size(ip); ++k) used[ip_rows_.node(ip, k)] = 1;
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i])
      throw InputError("/shape_function",
                       fmt::format("node {} at {} is in the support of no integration point and would have no mass; "
                                   "increase /shape_function/support_dilatation",
                                   i, point_text(mesh_.points[i])));
  }
}

void Model::build_time_steps() {
  const Index n = integration_point_count();
  ip_dt_.resize(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Index ip = 0; ip < n; ++ip) {
    double sum = 0.0;
    for (int k = 0; k < ip_rows_.size(ip); ++k) {
      const Vec3 g = ip_rows_.gradient(ip, k);
      sum += g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    }
    const Material& material = ip_material(ip);
    const double wave_speed = std::sqrt(material.p_wave_modulus() / material.density());
    ip_dt_[ip] = 2.0 / (wave_speed * std::sqrt(static_cast<double>(ip_rows_.size(ip)) * sum));
  }
}

std::vector<double> Model::ip_stiffening(std::span<const double> u) const {
  std::vector<double> at_rest(materials_.size());
  for (std::size_t m = 0; m < materials_.size(); ++m)
    at_rest[m] = largest_tangent_modulus(*materials_[m], Mat3::Identity());
  std::vector<double> ratio(static_cast<std::size_t>(integration_point_count()), 1.0);
  team_->for_each_share(integration_point_count(), [&](Index begin, Index end) {
    for (Index ip = begin; ip < end; ++ip) {
      const double rest = at_rest[ip_material_[ip]];
      const double now = largest_tangent_modulus(ip_material(ip), deformation_gradient_at(ip_rows_, ip, u.data()));
      if (rest > 0.0 && now > rest) ratio[static_cast<std::size_t>(ip)] = now / rest;
    }
  });
  return ratio;
}

void Model::build_integration_correction() {
  // Boundary integral b_I = int_Gamma N_I n dGamma by vertex quadrature: each boundary triangle gives a third
  // of its area vector to each of its vertices K, and N_I is evaluated at the nodes (the rows used for
  // interpolation). With the same points as the nodal constraints, the boundary term P b_I of a homogeneous
  // stress is exactly sum_K N_I(X_K) (P A_K): reactions at the constrained nodes can balance it, so the patch
  // test holds to the steady-state tolerance (a Gauss rule on the faces leaves an O(h) mismatch).
  std::vector<Vec3> area(static_cast<std::size_t>(node_count()), Vec3::Zero());
  for (const auto& f : boundary_faces(mesh_)) {
    const Vec3& a = mesh_.points[f[0]];
    const Vec3 share = (mesh_.points[f[1]] - a).cross(mesh_.points[f[2]] - a) / 6.0;  // area / 3, outward
    for (Index v : f) area[v] += share;
  }
  // r_I = b_I - sum_ip w grad N_I: what the corrections must add to node I's gradient integral.
  std::vector<Vec3> residual(static_cast<std::size_t>(node_count()), Vec3::Zero());
  for (Index k = 0; k < node_count(); ++k) {
    if (area[k].squaredNorm() == 0.0) continue;  // interior node
    for (std::int64_t e = node_rows_.offsets[k]; e < node_rows_.offsets[k + 1]; ++e)
      residual[node_rows_.nodes[e]] += node_rows_.values[e] * area[k];
  }
  for (Index ip = 0; ip < integration_point_count(); ++ip)
    for (int k = 0; k < ip_rows_.size(ip); ++k) residual[ip_rows_.node(ip, k)] -= ip_weight_[ip] * ip_rows_.gradient(ip, k);
  const std::vector<Vec3> xi = solve_integration_correction(residual);
  for (Index i = 0; i < node_count(); ++i)
    for (int d = 0; d < 3; ++d) xi_[4 * static_cast<std::size_t>(ip_rows_.slot(i)) + d] = xi[i][d];
  for (Index ip = 0; ip < integration_point_count(); ++ip) {
    Vec3 mean = Vec3::Zero();
    for (int k = 0; k < ip_rows_.size(ip); ++k) mean += xi[ip_rows_.node(ip, k)];
    mean /= ip_rows_.size(ip);
    for (int d = 0; d < 3; ++d) xi_mean_[3 * static_cast<std::size_t>(ip) + d] = mean[d];
  }
  // Single-precision rows also store the scatter's test gradients: it then streams a second row per point instead
  // of reading every support node's correction and subtracting the mean (a third fewer of its instructions, and
  // 28 bytes per entry, as many as double rows without them). Double rows leave the kernel to form them: a stored
  // copy would bring them to 52 bytes per entry, and the brain phantom's kernel took 43% longer (performance.md).
  if (ip_rows_.precision() != RowPrecision::single_precision) return;
  ip_rows_.own_test_gradients();  // then each point writes its own entries, in parallel
#pragma omp parallel for schedule(static)
  for (Index ip = 0; ip < integration_point_count(); ++ip)
    for (int k = 0; k < ip_rows_.size(ip); ++k)
      ip_rows_.set_test_gradient(ip, k, test_gradient(ip, k));
}

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
        if (it == counts.end()) counts.emplace_back(a, 1); else ++it->second;
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
      const Eigen::Array3i c = (((nodes[i] - lo).array() / extent.array()) * divisions.cast<double>()).floor().cast<int>().min(divisions - 1);
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

}  // namespace

std::vector<Vec3> Model::solve_integration_correction(std::vector<Vec3> r) const {
  const auto start = std::chrono::steady_clock::now();
  const Index n = node_count(), points = integration_point_count();
  // Each node's integration points (the transpose of the rows), for the product in node order.
  const SupportRows node_points = transpose_rows(points, n, [&](Index ip, auto&& add) {
    for (int k = 0; k < ip_rows_.size(ip); ++k) add(ip_rows_.node(ip, k));
  });
  const std::vector<std::int64_t>& first = node_points.offsets;
  std::vector<double> W(static_cast<std::size_t>(n), 0.0), diagonal(static_cast<std::size_t>(n), 0.0);
  for (Index i = 0; i < n; ++i)
    for (auto e = first[i]; e < first[i + 1]; ++e) {
      const Index ip = node_points.nodes[e];
      W[i] += ip_weight_[ip];
      diagonal[i] += ip_weight_[ip] * (1.0 - 1.0 / ip_rows_.size(ip));
    }
  // w_p mean_p(x) per point, then summed per node: the weight goes in with the mean, so the second pass reads
  // one array at the scattered points instead of two.
  // x by the kernel's slots (GradientRows::slot) for the first pass: the rows' records name slots, which follow the
  // rows' order of first use, so the pass reads x nearly in order and without a slot-to-node lookup per entry.
  std::vector<Vec3> weighted_mean(static_cast<std::size_t>(points)), x_at_slot(static_cast<std::size_t>(n));
  const auto apply = [&](const std::vector<Vec3>& x, std::vector<Vec3>& y) {
    for (Index i = 0; i < n; ++i) x_at_slot[static_cast<std::size_t>(ip_rows_.slot(i))] = x[i];
#pragma omp parallel for schedule(static)
    for (Index ip = 0; ip < points; ++ip) {
      Vec3 sum = Vec3::Zero();
      for (int k = 0; k < ip_rows_.size(ip); ++k) sum += x_at_slot[ip_rows_.entry_slot(ip, k)];
      weighted_mean[ip] = (ip_weight_[ip] / ip_rows_.size(ip)) * sum;
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
  CoarseCorrection coarse(mesh_.points, W, ip_rows_, ip_weight_);
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
  log().debug("consistent integration: corrections solved in {} conjugate-gradient iterations ({} aggregates on the "
              "coarse level), {:.2f} s", iteration, coarse.aggregates(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return x;
}

std::vector<double> Model::lumped_mass(std::span<const double> density_scale) const {
  std::vector<double> mass(static_cast<std::size_t>(node_count()), 0.0);
  for (Index ip = 0; ip < integration_point_count(); ++ip) {
    const double scale = density_scale.empty() ? 1.0 : density_scale[ip];
    const double share = scale * ip_material(ip).density() * ip_weight_[ip] / static_cast<double>(ip_rows_.size(ip));
    for (int k = 0; k < ip_rows_.size(ip); ++k) mass[ip_rows_.node(ip, k)] += share;
  }
  return mass;
}

Mat3 Model::deformation_gradient(Index ip, std::span<const double> u) const {
  return deformation_gradient_at(ip_rows_, ip, u.data());
}

// A team task: thread `thread`'s share of the kernel's slots (GradientRows::slot), each filled from its node.
void Model::pad_displacement(std::span<const double> u, int thread) const {
  const auto [begin, end] = ThreadTeam::share(node_count(), thread, team_->size());
  for (std::int64_t s = begin; s < end; ++s) {
    const auto i = static_cast<std::size_t>(ip_rows_.node_at_slot(static_cast<Index>(s)));
    for (std::size_t c = 0; c < 3; ++c) padded_u_[4 * static_cast<std::size_t>(s) + c] = u[3 * i + c];
  }
}

std::span<const PointRange> Model::thread_slots(std::span<const PointRange> ranges) const {
  for (const auto& [asked, slots] : thread_slots_)
    if (std::equal(ranges.begin(), ranges.end(), asked.begin(), asked.end())) return slots;
  const int threads = team_->size();
  std::vector<PointRange> slots(static_cast<std::size_t>(threads), PointRange{0, 0});
  for (int thread = 0; thread < threads; ++thread) {
    Index lowest = std::numeric_limits<Index>::max(), highest = -1;
    ThreadTeam::for_each_piece_of_share(ranges, thread, threads, [&](Index begin, Index end) {
      for (Index row = begin; row < end; ++row)
        for (int k = 0; k < ip_rows_.size(row); ++k) {
          lowest = std::min(lowest, ip_rows_.entry_slot(row, k));
          highest = std::max(highest, ip_rows_.entry_slot(row, k));
        }
    });
    if (highest >= 0) slots[static_cast<std::size_t>(thread)] = {lowest, highest + 1};
  }
  thread_slots_.emplace_back(std::vector<PointRange>(ranges.begin(), ranges.end()), std::move(slots));
  return thread_slots_.back().second;
}

// A team task: sums the per-thread buffers in a fixed order over thread `thread`'s share of the nodes, each buffer
// only where its thread wrote (elsewhere it held zeros: the sums are those of every buffer, bit for bit).
void Model::reduce_thread_forces(std::span<double> f, int thread, std::span<const PointRange> slots) const {
  const auto [begin, end] = ThreadTeam::share(node_count(), thread, team_->size());
  for (std::int64_t i = begin; i < end; ++i) {
    const Index s = ip_rows_.slot(static_cast<Index>(i));
    double sum[3] = {0.0, 0.0, 0.0};
    for (std::size_t t = 0; t < thread_forces_.size(); ++t) {
      if (s < slots[t].first || s >= slots[t].second) continue;
      const double* record = thread_forces_[t].data() + 4 * static_cast<std::size_t>(s);
      for (std::size_t c = 0; c < 3; ++c) sum[c] += record[c];
    }
    for (std::size_t c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(i) + c] = sum[c];
  }
}

// Zeroes the slots a thread's share writes into (the padding's sink slot with them: its padded entries add there).
void Model::clear_thread_forces(int thread, std::span<const PointRange> slots) const {
  AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
  const PointRange range = slots[static_cast<std::size_t>(thread)];
  std::fill(local.begin() + 4 * range.first, local.begin() + 4 * range.second, 0.0);
  std::fill(local.end() - 4, local.end(), 0.0);
}

// The forces of integration points begin .. end - 1 into f4, in batches of consecutive points with one
// material. Returns the first inadmissible point, or the largest Index.
Index Model::accumulate_forces(Index begin, Index end, double* f4, const std::function<void()>* progress) const {
  constexpr int kCapacity = StressBatch::kCapacity;
  constexpr Index kPointsBetweenProgress = 2048;  // about a tenth of a millisecond of the kernel
  Index first_bad = std::numeric_limits<Index>::max();
  Index since_progress = 0;
  StressBatch batch{};
  double P[9][kCapacity];
  double weights[kCapacity];
  bool skip[kCapacity];
  for (Index first = begin; first < end; first += batch.count) {
    const std::uint16_t material = ip_material_[first];
    int count = 1;
    while (count < kCapacity && first + count < end && ip_material_[first + count] == material) ++count;
    batch.count = count;
    force_kernel::gather(ip_rows_, padded_u_.data(), first, batch);
    materials_[material]->stress_batch(batch);
    for (int p = 0; p < kCapacity; ++p) {
      weights[p] = p < count ? ip_weight_[first + p] : 0.0;
      skip[p] = p < count && !batch.admissible[p];
      if (skip[p]) first_bad = std::min(first_bad, first + p);
    }
    force_kernel::first_piola(batch, weights, P);
    force_kernel::scatter(ip_rows_, xi_.data(), xi_mean_.data(), first, count, P, skip, f4);
    if (progress != nullptr && (since_progress += count) >= kPointsBetweenProgress) {
      (*progress)();
      since_progress = 0;
    }
  }
  return first_bad;
}

Index Model::internal_forces(std::span<const double> u, std::span<double> f) const {
  if (volumetric_) return volumetric_->internal_forces(*this, u, f);
  return internal_forces(u, f, every_point());
}

std::vector<PointRange> Model::points_read(std::span<const PointRange> ranges) const {
  if (volumetric_) return volumetric_->points_read(*this, ranges);
  return {ranges.begin(), ranges.end()};
}

Index Model::internal_forces(std::span<const double> u, std::span<double> f, std::span<const PointRange> ranges,
                             const std::function<void()>& progress) const {
  if (volumetric_) {
    if (!volumetric_->sums_over_ranges())
      throw std::logic_error("Model::internal_forces over ranges of points with a volumetric treatment that sums "
                             "only over every point");
    return volumetric_->internal_forces(*this, u, f, ranges);
  }
  std::vector<Index>& first_bad = thread_first_bad_;
  const std::span<const PointRange> slots = thread_slots(ranges);
  team_->run([&](int thread) {
    AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
    clear_thread_forces(thread, slots);
    pad_displacement(u, thread);
    team_->barrier();
    // Contiguous shares of the ranges' points, so that each thread's batches are consecutive points.
    const std::function<void()>* calls = thread == 0 && progress ? &progress : nullptr;
    Index bad = std::numeric_limits<Index>::max();
    ThreadTeam::for_each_piece_of_share(ranges, thread, team_->size(), [&](Index begin, Index end) {
      bad = std::min(bad, accumulate_forces(begin, end, local.data(), calls));
    });
    first_bad[static_cast<std::size_t>(thread)] = bad;
    team_->barrier();
    reduce_thread_forces(f, thread, slots);
  });
  const Index bad = *std::min_element(first_bad.begin(), first_bad.end());
  return bad == std::numeric_limits<Index>::max() ? -1 : bad;
}

Index Model::stress_deformation_gradients(std::span<const double> u, std::span<Mat3> F) const {
  if (volumetric_) return volumetric_->stress_deformation_gradients(*this, u, F);
  return deformation_gradients(u, F);
}

Index Model::deformation_gradients(std::span<const double> u, std::span<Mat3> F) const {
  return deformation_gradients(u, F, every_point());
}

Index Model::deformation_gradients(std::span<const double> u, std::span<Mat3> F,
                                   std::span<const PointRange> ranges) const {
  std::vector<Index>& first_bad = thread_first_bad_;
  team_->run([&](int thread) {
    Index& thread_bad = first_bad[static_cast<std::size_t>(thread)];
    thread_bad = std::numeric_limits<Index>::max();
    pad_displacement(u, thread);
    team_->barrier();
    StressBatch batch{};
    ThreadTeam::for_each_piece_of_share(ranges, thread, team_->size(), [&](Index begin, Index end) {
      for (Index first = begin; first < end; first += batch.count) {
        batch.count = std::min<Index>(StressBatch::kCapacity, end - first);
        force_kernel::gather(ip_rows_, padded_u_.data(), first, batch);
        for (int p = 0; p < batch.count; ++p) {
          F[first + p] = batch.deformation_gradient(p);
          const double J = F[first + p].determinant();
          if (!(J > 0.0) || !std::isfinite(J) || !F[first + p].allFinite()) thread_bad = std::min(thread_bad, first + p);
        }
      }
    });
  });
  const Index bad = *std::min_element(first_bad.begin(), first_bad.end());
  return bad == std::numeric_limits<Index>::max() ? -1 : bad;
}

void Model::scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f) const {
  scatter_stresses(weighted_stress, f, every_point());
}

void Model::scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f,
                             std::span<const PointRange> ranges) const {
  const std::span<const PointRange> slots = thread_slots(ranges);
  team_->run([&](int thread) {
    AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
    clear_thread_forces(thread, slots);
    double P[9][StressBatch::kCapacity];
    const bool skip[StressBatch::kCapacity] = {};
    ThreadTeam::for_each_piece_of_share(ranges, thread, team_->size(), [&](Index begin, Index end) {
      for (Index first = begin; first < end; first += StressBatch::kCapacity) {
        const int count = std::min<Index>(StressBatch::kCapacity, end - first);
        for (int p = 0; p < count; ++p)
          for (int c = 0; c < 9; ++c) P[c][p] = weighted_stress[first + p](c / 3, c % 3);
        force_kernel::scatter(ip_rows_, xi_.data(), xi_mean_.data(), first, count, P, skip, local.data());
      }
    });
    team_->barrier();
    reduce_thread_forces(f, thread, slots);
  });
}

std::int64_t Model::streamed_bytes_per_force_evaluation() const {
  const std::int64_t real = ip_rows_.precision() == RowPrecision::single_precision ? 4 : 8;
  // Rows with their own test gradients stream them too, and read no corrections (xi per node, the mean per point).
  const bool stored_tests = ip_rows_.has_own_test_gradients();
  const std::int64_t gradients = (stored_tests ? 2 : 1) * 3 * real;
  const std::int64_t rows =
      ip_rows_.blocks() * GradientRows::kBlock * (static_cast<std::int64_t>(sizeof(Index)) + gradients);
  const std::int64_t points = integration_point_count() * (8 + (stored_tests ? 0 : 3 * 8) + 2);
  // u (and xi); the force buffers; u in, f out
  const std::int64_t per_node = 4 * 8 * ((stored_tests ? 1 : 2) + 3 * team_->size()) + 3 * 8 * 2;
  return rows + points + (static_cast<std::int64_t>(node_count()) + 1) * per_node;
}

double Model::strain_energy(std::span<const double> u) const {
  if (volumetric_) return volumetric_->strain_energy(*this, u);
  const Index n = integration_point_count();
  double energy = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : energy)
  for (Index ip = 0; ip < n; ++ip) energy += ip_weight_[ip] * ip_material(ip).energy(deformation_gradient(ip, u));
  return energy;
}

void Model::interpolate(std::span<const double> u, std::span<double> out) const {
  // On the time step's team, not OpenMP: monitors and writers call this between steps (every 100 steps by default),
  // and OpenMP's idle threads would then spin for milliseconds on the cores the team needs for the next step.
  constexpr std::int64_t kInterpolationGrain = 1024;  // nodes per thread at least (about 40 support entries each)
  team_->for_each_share(
      node_count(),
      [&](std::int64_t begin, std::int64_t end) {
        for (auto j = static_cast<Index>(begin); j < static_cast<Index>(end); ++j) {
          const Vec3 v = interpolate_node(j, u);
          for (int d = 0; d < 3; ++d) out[3 * static_cast<std::size_t>(j) + d] = v[d];
        }
      },
      kInterpolationGrain);
}

Vec3 Model::interpolate_node(Index node, std::span<const double> u) const {
  Vec3 v = Vec3::Zero();
  for (std::int64_t k = node_rows_.offsets[node]; k < node_rows_.offsets[node + 1]; ++k) {
    const double* ui = &u[3 * static_cast<std::size_t>(node_rows_.nodes[k])];
    v += node_rows_.values[k] * Vec3(ui[0], ui[1], ui[2]);
  }
  return v;
}

bool Model::shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values) const {
  std::vector<Index> candidates;
  node_search_->within(x, max_radius_, candidates);
  nodes.clear();
  for (Index i : candidates)
    if ((mesh_.points[i] - x).norm() < radius_[i]) nodes.push_back(i);
  std::sort(nodes.begin(), nodes.end());
  if (static_cast<int>(nodes.size()) < shape_functions_->minimum_support_size()) return false;
  std::vector<Vec3> coordinates(nodes.size());
  std::vector<double> radii(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    coordinates[k] = mesh_.points[nodes[k]];
    radii[k] = radius_[nodes[k]];
  }
  values.resize(nodes.size());
  return shape_functions_->evaluate(x, coordinates, radii, values, {}).ok;
}

}  // namespace mtled
