#include "mtled/discretisation.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "integration_correction.hpp"

namespace mtled {

namespace {

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

void build_integration_points(MeshlessBasis& b, int points_per_tet, const std::vector<int>& cell_groups) {
  if (points_per_tet != 1 && points_per_tet != 4)
    throw InputError("/discretisation/integration_points_per_tet", "must be 1 or 4");
  if (!cell_groups.empty() && cell_groups.size() != b.mesh.tets.size())
    throw std::logic_error("Discretisation: one cell group per tet is required");
  const std::size_t count = b.mesh.tets.size() * static_cast<std::size_t>(points_per_tet);
  b.points.positions.reserve(count);
  b.points.weights.reserve(count);
  b.points.tets.reserve(count);
  b.points.material_index.reserve(count);
  std::vector<Index> order(b.mesh.tets.size());
  std::iota(order.begin(), order.end(), Index{0});
  const int groups = cell_groups.empty() ? 1 : *std::max_element(cell_groups.begin(), cell_groups.end()) + 1;
  b.points.group_offsets.assign(static_cast<std::size_t>(groups) + 1, 0);
  // Integration points follow their cells along a Morton curve (within a cell group and a region, so a group stays
  // one range of points and a region's points form long one-material batches): consecutive points then share most
  // of their support nodes, and the force kernel finds their records in cache. The mesh generator's order scatters
  // them (the brain phantom's force kernel took 1.47x as long in it, the default scene's 1.22x).
  const std::vector<std::uint64_t> key = morton_keys(b.mesh);
  const std::vector<Index>& region = b.mesh.tet_region;
  std::stable_sort(order.begin(), order.end(), [&](Index s, Index t) {
    const int group_s = cell_groups.empty() ? 0 : cell_groups[s], group_t = cell_groups.empty() ? 0 : cell_groups[t];
    if (group_s != group_t) return group_s < group_t;
    if (region[s] != region[t]) return region[s] < region[t];
    return key[s] < key[t];
  });
  if (!cell_groups.empty()) {
    for (const int g : cell_groups) b.points.group_offsets[static_cast<std::size_t>(g) + 1] += points_per_tet;
  } else {
    b.points.group_offsets[1] = static_cast<Index>(count);
  }
  std::partial_sum(b.points.group_offsets.begin(), b.points.group_offsets.end(), b.points.group_offsets.begin());
  for (const Index t : order) {
    const double volume = tet_volume(b.mesh, t);
    const auto material = static_cast<std::uint16_t>(b.mesh.tet_region[t]);
    if (points_per_tet == 1) {
      b.points.positions.push_back(tet_centroid(b.mesh, t));
      b.points.weights.push_back(volume);
      b.points.tets.push_back(t);
      b.points.material_index.push_back(material);
    } else {
      for (const Vec3& x : tet_quadrature_points(b.mesh, t)) {  // exact for quadratics, weight V/4 each
        b.points.positions.push_back(x);
        b.points.weights.push_back(volume / 4.0);
        b.points.tets.push_back(t);
        b.points.material_index.push_back(material);
      }
    }
  }
  b.points.all = {0, b.points.count()};
}

// Support lists of arbitrary points (at least the shape functions' minimum); throws InputError naming `what`.
std::vector<std::vector<Index>> find_supports(const MeshlessBasis& b, const std::vector<Vec3>& points,
                                              const char* what) {
  const int needed = b.shape_functions->minimum_support_size();
  const Index n = static_cast<Index>(points.size());
  std::vector<std::vector<Index>> support(points.size());
  std::vector<RowFailure> failures(static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel
  {
    std::vector<Index> candidates;
    RowFailure& failure = failures[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (Index r = 0; r < n; ++r) {
      b.cloud.search->within(points[r], b.cloud.max_support_radius, candidates);
      auto& s = support[r];
      for (Index i : candidates)
        if ((b.mesh.points[i] - points[r]).norm() < b.cloud.support_radius[i]) s.push_back(i);
      std::sort(s.begin(), s.end());
      if (static_cast<int>(s.size()) < needed && r < failure.row) {
        failure.row = r;
        failure.message = fmt::format(
            "{} {} at {} lies in the support of only {} nodes; the shape functions need at least {}. Increase "
            "/shape_function/support_dilatation (now {:g}) or use a finer, more even mesh",
            what, r, point_text(points[r]), s.size(), needed, b.shape_functions->support_dilatation());
      }
    }
  }
  for (const auto& f : failures)
    if (f.row != std::numeric_limits<Index>::max()) throw InputError("/shape_function", f.message);
  return support;
}

// Shape functions at the points on those supports: store(r, k, value, gradient) for each entry, gradients only when
// asked for; returns the smallest reciprocal condition number of the fits.
template <class Store>
double evaluate_rows(const MeshlessBasis& b, const std::vector<Vec3>& points,
                     const std::vector<std::vector<Index>>& supports, bool gradients, const char* what, Store store) {
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
        coordinates[k] = b.mesh.points[s[k]];
        radii[k] = b.cloud.support_radius[s[k]];
      }
      const ShapeFunctionFit fit = b.shape_functions->evaluate(points[r], coordinates, radii, values, grads);
      condition = std::min(condition, fit.reciprocal_condition);
      if (!fit.ok && r < failure.row) {
        failure.row = r;
        failure.message = fmt::format(
            "the shape functions cannot be built at {} {} at {}: its {} support nodes are too few or nearly "
            "coplanar (reciprocal condition {:.2g}). Increase /shape_function/support_dilatation (now {:g})",
            what, r, point_text(points[r]), s.size(), fit.reciprocal_condition,
            b.shape_functions->support_dilatation());
      }
      for (std::size_t k = 0; k < s.size(); ++k)
        store(r, static_cast<int>(k), values[k], gradients ? grads[k] : Vec3::Zero());
    }
  }
  for (const auto& f : failures)
    if (f.row != std::numeric_limits<Index>::max()) throw InputError("/shape_function", f.message);
  return *std::min_element(min_condition.begin(), min_condition.end());
}

void build_supports(MeshlessBasis& b, RowPrecision precision) {
  {
    const auto supports = find_supports(b, b.points.positions, "integration point");
    b.gradients.assign(supports, b.mesh.node_count(), precision);
    b.points.support.min_reciprocal_condition =
        evaluate_rows(b, b.points.positions, supports, true, "integration point",
                      [&](Index r, int k, double, const Vec3& gradient) { b.gradients.set_gradient(r, k, gradient); });
    b.points.support.min = std::numeric_limits<Index>::max();
    b.points.support.max = 0;
    for (Index r = 0; r < b.gradients.rows(); ++r) {
      b.points.support.min = std::min(b.points.support.min, b.gradients.size(r));
      b.points.support.max = std::max(b.points.support.max, b.gradients.size(r));
    }
    b.points.support.mean = static_cast<double>(b.gradients.entries()) / std::max<Index>(b.gradients.rows(), 1);
  }
  {
    const auto supports = find_supports(b, b.mesh.points, "node");
    b.interpolation.offsets.assign(supports.size() + 1, 0);
    for (std::size_t r = 0; r < supports.size(); ++r)
      b.interpolation.offsets[r + 1] = b.interpolation.offsets[r] + static_cast<std::int64_t>(supports[r].size());
    b.interpolation.nodes.resize(static_cast<std::size_t>(b.interpolation.offsets.back()));
    b.interpolation.values.resize(b.interpolation.nodes.size());
    for (std::size_t r = 0; r < supports.size(); ++r)
      std::copy(supports[r].begin(), supports[r].end(), b.interpolation.nodes.begin() + b.interpolation.offsets[r]);
    evaluate_rows(b, b.mesh.points, supports, false, "node", [&](Index r, int k, double value, const Vec3&) {
      b.interpolation.values[static_cast<std::size_t>(b.interpolation.offsets[r] + k)] = value;
    });
  }

  // Every node must carry mass: it must lie in the support of some integration point.
  std::vector<char> used(b.mesh.points.size(), 0);
  for (Index ip = 0; ip < b.gradients.rows(); ++ip)
    for (int k = 0; k < b.gradients.size(ip); ++k) used[b.gradients.node(ip, k)] = 1;
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i])
      throw InputError("/shape_function",
                       fmt::format("node {} at {} is in the support of no integration point and would have no mass; "
                                   "increase /shape_function/support_dilatation",
                                   i, point_text(b.mesh.points[i])));
  }
}

// test_gradient (discretisation.hpp) on a basis.
Vec3 test_gradient_at(const MeshlessBasis& b, Index ip, int k) {
  const double* xi = b.correction.at_slots.data() + 4 * static_cast<std::size_t>(b.gradients.entry_slot(ip, k));
  const double* mean = b.correction.means.data() + 3 * static_cast<std::size_t>(ip);
  return b.gradients.gradient(ip, k) + Vec3(xi[0] - mean[0], xi[1] - mean[1], xi[2] - mean[2]);
}

void build_integration_correction(MeshlessBasis& b) {
  const std::vector<Vec3> xi = integration_correction(b.mesh, b.gradients, b.interpolation, b.points.weights);
  for (Index i = 0; i < b.mesh.node_count(); ++i)
    for (int d = 0; d < 3; ++d) b.correction.at_slots[4 * static_cast<std::size_t>(b.gradients.slot(i)) + d] = xi[i][d];
  for (Index ip = 0; ip < b.points.count(); ++ip) {
    Vec3 mean = Vec3::Zero();
    for (int k = 0; k < b.gradients.size(ip); ++k) mean += xi[b.gradients.node(ip, k)];
    mean /= b.gradients.size(ip);
    for (int d = 0; d < 3; ++d) b.correction.means[3 * static_cast<std::size_t>(ip) + d] = mean[d];
  }
  // Single-precision rows also store the scatter's test gradients: it then streams a second row per point instead
  // of reading every support node's correction and subtracting the mean (a third fewer of its instructions, and
  // 28 bytes per entry, as many as double rows without them). Double rows leave the kernel to form them: a stored
  // copy would bring them to 52 bytes per entry, and the brain phantom's kernel took 43% longer (performance.md).
  if (b.gradients.precision() != RowPrecision::single_precision) return;
  b.gradients.own_test_gradients();  // then each point writes its own entries, in parallel
#pragma omp parallel for schedule(static)
  for (Index ip = 0; ip < b.points.count(); ++ip)
    for (int k = 0; k < b.gradients.size(ip); ++k) b.gradients.set_test_gradient(ip, k, test_gradient_at(b, ip, k));
}

// The basis: the cloud, the integration points, the shape functions' rows at them and at the nodes, and the
// integration correction.
std::shared_ptr<const MeshlessBasis> build_basis(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
                                                 const Discretisation::Options& options) {
  auto basis = std::make_shared<MeshlessBasis>();
  MeshlessBasis& b = *basis;
  b.mesh = std::move(mesh);
  b.shape_functions = std::move(shape_functions);
  if (b.mesh.region_names.size() > std::numeric_limits<std::uint16_t>::max())
    throw InputError(b.mesh.source, "more than 65535 material regions");
  NodeCloud& cloud = b.cloud;
  cloud.surface = surface_nodes(b.mesh);
  cloud.spacing = mean_edge_length_at_nodes(b.mesh);
  const double dilatation = b.shape_functions->support_dilatation();
  cloud.support_radius.resize(cloud.spacing.size());
  for (std::size_t i = 0; i < cloud.spacing.size(); ++i) cloud.support_radius[i] = dilatation * cloud.spacing[i];
  cloud.max_support_radius = *std::max_element(cloud.support_radius.begin(), cloud.support_radius.end());
  const auto [lo, hi] = bounding_box(b.mesh.points);
  cloud.length_scale = (hi - lo).norm();
  cloud.search = std::make_unique<PointSearch>(b.mesh.points);

  build_integration_points(b, options.integration_points_per_tet, options.cell_groups);
  build_supports(b, options.precision);
  const std::size_t padded = 4 * (static_cast<std::size_t>(b.mesh.node_count()) + 1);
  b.correction.at_slots.assign(padded, 0.0);
  b.correction.means.assign(3 * static_cast<std::size_t>(b.points.count()), 0.0);
  if (options.consistent_integration) build_integration_correction(b);
  return basis;
}

}  // namespace

Discretisation::Discretisation(TetMesh mesh, std::shared_ptr<const ShapeFunctions> shape_functions,
                               std::vector<std::shared_ptr<const Material>> region_materials, Options options)
    : Discretisation(build_basis(std::move(mesh), std::move(shape_functions), options), std::move(region_materials),
                     options.threads) {}

Discretisation::Discretisation(std::shared_ptr<const MeshlessBasis> basis,
                               std::vector<std::shared_ptr<const Material>> region_materials, int threads)
    : basis_(std::move(basis)), materials_(std::move(region_materials)) {
  if (materials_.size() != basis_->mesh.region_names.size())
    throw std::logic_error("Discretisation: one material per mesh region is required");
  build_time_steps();
  team_ = std::make_unique<ThreadTeam>(threads > 0 ? threads : omp_get_max_threads());
}

Discretisation::~Discretisation() = default;

void Discretisation::build_time_steps() {
  const Index n = points().count();
  critical_time_steps_.resize(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Index ip = 0; ip < n; ++ip) {
    double sum = 0.0;
    for (int k = 0; k < gradients().size(ip); ++k) {
      const Vec3 g = gradients().gradient(ip, k);
      sum += g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    }
    const Material& law = material(ip);
    const double wave_speed = std::sqrt(law.p_wave_modulus() / law.density());
    critical_time_steps_[ip] = 2.0 / (wave_speed * std::sqrt(static_cast<double>(gradients().size(ip)) * sum));
  }
}

std::vector<double> Discretisation::lumped_mass(std::span<const double> density_scale) const {
  std::vector<double> mass(static_cast<std::size_t>(node_count()), 0.0);
  for (Index ip = 0; ip < points().count(); ++ip) {
    const double scale = density_scale.empty() ? 1.0 : density_scale[ip];
    const double share =
        scale * material(ip).density() * points().weights[ip] / static_cast<double>(gradients().size(ip));
    for (int k = 0; k < gradients().size(ip); ++k) mass[gradients().node(ip, k)] += share;
  }
  return mass;
}

Mat3 Discretisation::deformation_gradient(Index ip, std::span<const double> u) const {
  return deformation_gradient_at(gradients(), ip, u.data());
}

void Discretisation::interpolate(std::span<const double> u, std::span<double> out) const {
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

Vec3 Discretisation::interpolate_node(Index node, std::span<const double> u) const {
  Vec3 v = Vec3::Zero();
  for (std::int64_t k = basis_->interpolation.offsets[node]; k < basis_->interpolation.offsets[node + 1]; ++k) {
    const double* ui = &u[3 * static_cast<std::size_t>(basis_->interpolation.nodes[k])];
    v += basis_->interpolation.values[k] * Vec3(ui[0], ui[1], ui[2]);
  }
  return v;
}

bool Discretisation::shape_functions_at(const Vec3& x, std::vector<Index>& nodes, std::vector<double>& values,
                                        std::vector<Vec3>* gradients) const {
  std::vector<Index> candidates;
  basis_->cloud.search->within(x, basis_->cloud.max_support_radius, candidates);
  nodes.clear();
  for (Index i : candidates)
    if ((basis_->mesh.points[i] - x).norm() < basis_->cloud.support_radius[i]) nodes.push_back(i);
  std::sort(nodes.begin(), nodes.end());
  if (static_cast<int>(nodes.size()) < basis_->shape_functions->minimum_support_size()) return false;
  std::vector<Vec3> coordinates(nodes.size());
  std::vector<double> radii(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    coordinates[k] = basis_->mesh.points[nodes[k]];
    radii[k] = basis_->cloud.support_radius[nodes[k]];
  }
  values.resize(nodes.size());
  if (gradients) gradients->resize(nodes.size());
  return basis_->shape_functions
      ->evaluate(x, coordinates, radii, values, gradients ? std::span<Vec3>(*gradients) : std::span<Vec3>())
      .ok;
}

std::optional<FieldSample> field_at(const Discretisation& discretisation, const Vec3& X, std::span<const double> u) {
  std::vector<Index> nodes;
  std::vector<double> values;
  std::vector<Vec3> gradients;
  if (!discretisation.shape_functions_at(X, nodes, values, &gradients)) return std::nullopt;
  FieldSample sample{Vec3::Zero(), Mat3::Identity()};
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const double* u_k = u.data() + 3 * static_cast<std::size_t>(nodes[k]);
    const Vec3 u_node(u_k[0], u_k[1], u_k[2]);
    sample.displacement += values[k] * u_node;
    sample.deformation_gradient += u_node * gradients[k].transpose();
  }
  return sample;
}

Vec3 test_gradient(const Discretisation& discretisation, Index ip, int k) {
  return test_gradient_at(*discretisation.basis(), ip, k);
}

std::vector<double> stiffening(const Discretisation& discretisation, std::span<const double> u) {
  const IntegrationPoints& points = discretisation.points();
  // Each region's modulus at rest, from the first of its points.
  std::vector<double> at_rest;
  for (Index ip = 0; ip < points.count(); ++ip) {
    const std::size_t region = points.material_index[ip];
    if (region >= at_rest.size()) at_rest.resize(region + 1, -1.0);
    if (at_rest[region] < 0.0) at_rest[region] = largest_tangent_modulus(discretisation.material(ip), Mat3::Identity());
  }
  std::vector<double> ratio(static_cast<std::size_t>(points.count()), 1.0);
  discretisation.team().for_each_share(points.count(), [&](Index begin, Index end) {
    for (Index ip = begin; ip < end; ++ip) {
      const double rest = at_rest[points.material_index[ip]];
      const double now = largest_tangent_modulus(discretisation.material(ip),
                                                 deformation_gradient_at(discretisation.gradients(), ip, u.data()));
      if (rest > 0.0 && now > rest) ratio[static_cast<std::size_t>(ip)] = now / rest;
    }
  });
  return ratio;
}

}  // namespace mtled
