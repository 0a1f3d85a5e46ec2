// The meshless discretisation, its force kernel and the essential-boundary-condition projection, on irregular
// clouds, through the real plugins: mass, forces, thread independence, discrete energy consistency, constraints to
// round-off.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include "mtled/constraints.hpp"
#include "mtled/force_kernel.hpp"
#include "simd_targets.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

constexpr double kMu = 1000.0;
constexpr double kD = 4.02684e-5;  // nu = 0.49

std::unique_ptr<test::Discretised> make_model(const std::string& shape_function = "mls", double jitter = 0.25,
                                              int n = 5, const std::string& material = "neo_hookean",
                                              bool consistent = true, bool nodal_average = false,
                                              RowPrecision precision = RowPrecision::double_precision) {
  TetMesh mesh = test::box_mesh(Vec3(0.01, 0.01, 0.01), n, n, n, jitter, 7);
  const auto sf = test::make<ShapeFunctions>(shape_function, json::object());
  json parameters = {{"mu", kMu}, {"D", kD}, {"density", 1000.0}};
  if (material == "ogden") parameters["alpha"] = -1.3;
  const auto m = test::make<Material>(material, parameters);
  Discretisation::Options options;
  options.consistent_integration = consistent;
  options.precision = precision;
  return std::make_unique<test::Discretised>(
      std::move(mesh), sf, std::vector<std::shared_ptr<const Material>>{m}, options,
      nodal_average ? test::make<VolumetricTreatment>("nodal_average", json::object()) : nullptr);
}

std::vector<double> random_field(Index nodes, double amplitude, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-amplitude, amplitude);
  std::vector<double> u(3 * static_cast<std::size_t>(nodes));
  for (auto& v : u) v = uniform(random);
  return u;
}

// The sum of the nodal forces (3 per node) and the sum of their magnitudes.
std::pair<Vec3, double> net_force(const std::vector<double>& f) {
  Vec3 sum = Vec3::Zero();
  double magnitude = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    sum[static_cast<int>(i % 3)] += f[i];
    magnitude += std::abs(f[i]);
  }
  return {sum, magnitude};
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

TEST(SupportRows, TransposeListsEachColumnsRowsInRowOrder) {
  // rows 0..3 name columns {2, 0}, {0, 3}, {}, {2}; columns 1 and 4 are named by none.
  const std::vector<std::vector<Index>> relation = {{2, 0}, {0, 3}, {}, {2}};
  const SupportRows t = transpose_rows(4, 5, [&](Index row, auto&& add) {
    for (Index column : relation[static_cast<std::size_t>(row)]) add(column);
  });
  EXPECT_EQ(t.offsets, (std::vector<std::int64_t>{0, 2, 2, 4, 5, 5}));
  EXPECT_EQ(t.nodes, (std::vector<Index>{0, 1, 0, 3, 1}));
  EXPECT_EQ(t.rows(), 5);
  EXPECT_EQ(t.size(1), 0);
}

// The VmFlags of the mapping that holds address p (/proc/self/smaps), empty where there is none.
std::string mapping_flags(const void* p) {
  std::ifstream smaps("/proc/self/smaps");
  const auto address = reinterpret_cast<std::uintptr_t>(p);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream header(line);
    if (header >> std::hex >> begin >> dash >> end && dash == '-' && line.find(':') > line.find(' ')) {
      inside = begin <= address && address < end;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  return {};
}

TEST(KernelArrays, LargeOnesSitOnWholeHugePagesAskedForAsSuch) {
  AlignedVector<double> small(1000, 1.0);
  AlignedVector<double> large((std::size_t{3} << 20) / sizeof(double), 2.0);  // 3 MiB
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(small.data()) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % (std::size_t{2} << 20), 0u);
  EXPECT_EQ(std::accumulate(large.begin(), large.end(), 0.0), 2.0 * static_cast<double>(large.size()));
  // Where the kernel offers transparent huge pages, the mapping carries the advice ("hg" in its VmFlags).
  if (std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled")) {
    const std::string flags = mapping_flags(large.data());
    ASSERT_FALSE(flags.empty()) << "no mapping found for the array";
    EXPECT_NE(flags.find(" hg"), std::string::npos) << flags;
  }
}

TEST(GradientRows, SlotsFollowTheRowsFirstUseAndEntriesStillNameTheirNodes) {
  // 9 nodes (8 is the padding node); rows name 5, 2, then 2, 7, 1, then nothing, then 7; 0, 3, 4 and 6 are unused.
  const std::vector<std::vector<Index>> supports = {{5, 2}, {2, 7, 1}, {}, {7}};
  for (const RowPrecision precision : {RowPrecision::double_precision, RowPrecision::single_precision}) {
    SCOPED_TRACE(precision == RowPrecision::single_precision ? "single" : "double");
    GradientRows rows;
    rows.assign(supports, 8, precision);
    // Entry k of row r in its block's records, as the kernel reads it.
    auto record = [&](Index r, int k) {
      const std::int64_t block = rows.block_begin(r) + k / GradientRows::kBlock;
      return precision == RowPrecision::single_precision ? rows.block<float>(block)->records[k % GradientRows::kBlock]
                                                         : rows.block<double>(block)->records[k % GradientRows::kBlock];
    };
    const std::vector<Index> expected_slot = {4, 3, 1, 5, 6, 0, 7, 2, 8};
    for (Index node = 0; node <= 8; ++node) {
      EXPECT_EQ(rows.slot(node), expected_slot[static_cast<std::size_t>(node)]) << "node " << node;
      EXPECT_EQ(rows.node_at_slot(rows.slot(node)), node);
    }
    for (Index r = 0; r < rows.rows(); ++r)
      for (int k = 0; k < rows.size(r); ++k) {
        EXPECT_EQ(rows.node(r, k), supports[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)]);
        EXPECT_EQ(record(r, k), 4 * rows.slot(rows.node(r, k)));
      }
    // The padding entries of a row's last block point at the padding node's own slot.
    EXPECT_EQ(record(1, 3), 4 * 8);
    // A single-precision block is one cache line (static_assert in the header), and the array starts on one.
    if (precision == RowPrecision::single_precision) {
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(rows.block<float>(0)) % 64, 0u);
    }
  }
}

TEST(GradientRows, AssignedAgainEveryEntryStartsAtZeroWithPaddingOnThePaddingNode) {
  // The rows' arrays are resized without a zero-fill (UnfilledVector) and written in parallel by assign: a second
  // assign into the memory of a first, whose gradients were set, must still start every entry, padding included,
  // at zero, and the padding entries on the padding node.
  for (const RowPrecision precision : {RowPrecision::double_precision, RowPrecision::single_precision}) {
    SCOPED_TRACE(precision == RowPrecision::single_precision ? "single" : "double");
    GradientRows rows;
    rows.assign({{0, 1, 2, 3, 4}, {1, 2}}, 5, precision);
    for (Index r = 0; r < rows.rows(); ++r)
      for (int k = 0; k < rows.size(r); ++k) rows.set_gradient(r, k, Vec3(1.0, 2.0, 3.0));
    rows.set_test_gradient(0, 0, Vec3(4.0, 5.0, 6.0));
    rows.assign({{3}, {0, 4, 2}}, 5, precision);
    EXPECT_FALSE(rows.has_own_test_gradients());
    for (Index r = 0; r < rows.rows(); ++r) {
      const int padded = static_cast<int>(GradientRows::kBlock * (rows.block_end(r) - rows.block_begin(r)));
      for (int k = 0; k < padded; ++k) {
        EXPECT_EQ(rows.gradient(r, k), Vec3::Zero()) << "row " << r << " entry " << k;
        if (k >= rows.size(r)) {
          EXPECT_EQ(rows.node(r, k), 5) << "row " << r << " padding entry " << k;
        }
      }
    }
  }
}

// One component at a time and not inlined: GCC 12 at -O3 vectorised the three conversions of an inlined version and
// left the first two components unrounded (the double -> float -> double round trip of a pair dropped).
[[gnu::noinline]] double rounded_to_float(double x) { return static_cast<float>(x); }
Vec3 rounded_to_float(const Vec3& v) {
  return {rounded_to_float(v[0]), rounded_to_float(v[1]), rounded_to_float(v[2])};
}

TEST(GradientRows, TestGradientsAreTheGradientsUntilSetThenAStoredCopy) {
  for (const RowPrecision precision : {RowPrecision::double_precision, RowPrecision::single_precision}) {
    GradientRows rows;
    rows.assign({{0, 1}, {1, 2, 0}}, 3, precision);
    const Vec3 g(0.1, -0.2, 0.3), t(1.0 / 3.0, 2.0, -5.0);
    rows.set_gradient(0, 1, g);
    rows.set_gradient(1, 2, g);
    EXPECT_FALSE(rows.has_own_test_gradients());
    EXPECT_EQ(rows.stored_test_gradient(0, 1), rows.gradient(0, 1));
    rows.set_test_gradient(1, 2, t);
    EXPECT_TRUE(rows.has_own_test_gradients());
    // The one set holds its value in the rows' precision; the others are still the gradients.
    const Vec3 stored = precision == RowPrecision::single_precision ? rounded_to_float(t) : t;
    EXPECT_EQ(rows.stored_test_gradient(1, 2), stored);
    EXPECT_EQ(rows.stored_test_gradient(0, 1), rows.gradient(0, 1));
    EXPECT_EQ(rows.gradient(1, 2), rows.gradient(0, 1)) << "the gradients themselves are left as they were";
  }
}

// Single-precision rows store grad N + the correction of consistent integration once (the scatter then streams them);
// double rows leave the kernel to form it (a stored copy would double their bytes).
TEST(Discretisation, SinglePrecisionRowsStoreTheTestGradientsDoubleRowsFormThem) {
  const auto exact = make_model("mmls", 0.3, 4, "ogden", true);
  EXPECT_FALSE(exact->discretisation.gradients().has_own_test_gradients());
  const auto single = make_model("mmls", 0.3, 4, "ogden", true, false, RowPrecision::single_precision);
  const GradientRows& rows = single->discretisation.gradients();
  ASSERT_TRUE(rows.has_own_test_gradients());
  double largest_correction = 0.0;
  for (Index ip = 0; ip < rows.rows(); ++ip)
    for (int k = 0; k < rows.size(ip); ++k) {
      const Vec3 test = test_gradient(single->discretisation, ip, k);
      largest_correction = std::max(largest_correction, (test - rows.gradient(ip, k)).cwiseAbs().maxCoeff());
      const Vec3 expected = rounded_to_float(test);
      ASSERT_EQ(rows.stored_test_gradient(ip, k), expected) << "point " << ip << ", entry " << k;
    }
  EXPECT_GT(largest_correction, 0.0) << "the corrections took part";
  const auto uncorrected = make_model("mmls", 0.3, 4, "ogden", false, false, RowPrecision::single_precision);
  EXPECT_FALSE(uncorrected->discretisation.gradients().has_own_test_gradients())
      << "nothing to store without corrections";
}

TEST(Discretisation, IntegrationPointsFollowTheirCellsThroughSpace) {
  // A mesh whose cells come in random order: the model must still visit them so that consecutive points are
  // neighbours (the force kernel's cache depends on it), every cell's points together.
  const int n = 12;
  TetMesh mesh = test::box_mesh(Vec3(0.012, 0.012, 0.012), n, n, n, 0.2, 3);
  std::mt19937 random(5);
  std::shuffle(mesh.tets.begin(), mesh.tets.end(), random);
  const double cell = 0.012 / n;
  auto centroid = [&](Index t) {
    Vec3 c = Vec3::Zero();
    for (Index v : mesh.tets[static_cast<std::size_t>(t)]) c += mesh.points[static_cast<std::size_t>(v)];
    return Vec3(c / 4.0);
  };
  auto mean_jump = [&](const std::vector<Index>& order) {
    double sum = 0.0;
    for (std::size_t i = 1; i < order.size(); ++i) sum += (centroid(order[i]) - centroid(order[i - 1])).norm();
    return sum / static_cast<double>(order.size() - 1);
  };
  std::vector<Index> generator_order(mesh.tets.size());
  std::iota(generator_order.begin(), generator_order.end(), Index{0});
  const double shuffled = mean_jump(generator_order);
  const auto sf = test::make<ShapeFunctions>("mls", json::object());
  const auto m = test::make<Material>("neo_hookean", {{"mu", kMu}, {"D", kD}, {"density", 1000.0}});
  const Discretisation::Options four_points_per_cell = [] {
    Discretisation::Options o;
    o.integration_points_per_tet = 4;
    return o;
  }();
  const Discretisation model(mesh, sf, {m}, four_points_per_cell);
  const auto& ip_tet = model.points().tets;
  ASSERT_EQ(ip_tet.size(), 4 * mesh.tets.size());
  std::vector<Index> visited;
  for (std::size_t p = 0; p < ip_tet.size(); p += 4) {
    for (std::size_t k = 1; k < 4; ++k) EXPECT_EQ(ip_tet[p + k], ip_tet[p]) << "a cell's points lie apart";
    visited.push_back(ip_tet[p]);
  }
  std::vector<Index> sorted = visited;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, generator_order) << "every cell once";
  // Random order: a jump of about half the box (0.66 of its side on average). A space-filling order moves about one
  // cell at a time, with rare longer jumps between the curve's blocks.
  const double ordered = mean_jump(visited);
  std::cout << "mean distance between consecutive cells: " << ordered / cell << " cell sides (generator's order "
            << shuffled / cell << ")\n";
  EXPECT_GT(shuffled, 4.0 * cell);
  EXPECT_LT(ordered, 2.0 * cell);
}

TEST(Discretisation, LumpedMassIsTheBodyMass) {
  const auto model = make_model();
  const auto mass = model->discretisation.lumped_mass();
  double total = 0.0;
  for (double m : mass) {
    EXPECT_GT(m, 0.0);
    total += m;
  }
  EXPECT_NEAR(total, 1000.0 * 1e-6, 1e-15);  // rho V; every integration point gives away exactly rho w
}

TEST(Discretisation, RigidMotionsCarryNoForce) {
  // Linear reproduction makes F exactly the rotation, so S = 0 and f = 0 up to round-off, at any angle.
  const auto model = make_model("mls");
  const Eigen::AngleAxisd rotation(0.7, Vec3(1, 2, 3).normalized());
  std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count()));
  for (Index i = 0; i < model->discretisation.node_count(); ++i) {
    const Vec3 x = model->discretisation.nodes()[i];
    const Vec3 d = rotation * x - x + Vec3(0.003, -0.001, 0.002);
    for (int c = 0; c < 3; ++c) u[3 * i + c] = d[c];
  }
  std::vector<double> f(u.size());
  ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
  // Force scale of a 1% strain: mu * 0.01 * area of an integration cell.
  const double scale = kMu * 0.01 * 4e-6;
  EXPECT_LT(max_abs(f), 1e-9 * scale);
  EXPECT_NEAR(model->kernel.strain_energy(u), 0.0, 1e-18);
}

// The field anywhere (what the fold check reads between integration points, and Python's Run.field_at): exact for an
// affine field (linear reproduction); elsewhere its displacement is the shape functions' sum, equal at a node to the
// node's interpolation row, and its F the integration point's own at its position and the central difference of the
// interpolated field between, to the difference's truncation error (h = 1e-6 m on 2.5 mm supports: relative O(1e-7)).
TEST(Discretisation, TheFieldAnywhereIsItsInterpolationAndFItsDerivative) {
  const auto model = make_model("mmls");
  const Discretisation& d = model->discretisation;
  Mat3 H;
  H << 0.1, -0.2, 0.05, 0.3, -0.1, 0.02, -0.04, 0.15, 0.2;
  std::vector<double> affine(3 * static_cast<std::size_t>(d.node_count()));
  for (Index i = 0; i < d.node_count(); ++i) {
    const Vec3 u = H * d.nodes()[i] + Vec3(0.001, 0.002, -0.001);
    for (int c = 0; c < 3; ++c) affine[3 * static_cast<std::size_t>(i) + c] = u[c];
  }
  const std::vector<double> wavy = random_field(d.node_count(), 2e-4, 11);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> inside(0.001, 0.009);
  const auto interpolated = [&](const Vec3& x, const std::vector<double>& u) {
    std::vector<Index> nodes;
    std::vector<double> values;
    EXPECT_TRUE(d.shape_functions_at(x, nodes, values));
    Vec3 sum = Vec3::Zero();
    for (std::size_t k = 0; k < nodes.size(); ++k)
      sum += values[k] * Vec3(u[3 * static_cast<std::size_t>(nodes[k])], u[3 * static_cast<std::size_t>(nodes[k]) + 1],
                              u[3 * static_cast<std::size_t>(nodes[k]) + 2]);
    return sum;
  };
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 x(inside(random), inside(random), inside(random));
    const auto exact = field_at(d, x, affine);
    ASSERT_TRUE(exact);
    EXPECT_LT((exact->deformation_gradient - Mat3::Identity() - H).norm(), 1e-10) << exact->deformation_gradient;
    EXPECT_LT((exact->displacement - H * x - Vec3(0.001, 0.002, -0.001)).norm(), 1e-12) << exact->displacement;
    const auto sample = field_at(d, x, wavy);
    ASSERT_TRUE(sample);
    EXPECT_LT((sample->displacement - interpolated(x, wavy)).norm(), 1e-12 * 2e-4) << x;
    const Mat3& G = sample->deformation_gradient;
    constexpr double h = 1e-6;
    Mat3 difference = Mat3::Identity();
    for (int j = 0; j < 3; ++j)
      difference.col(j) +=
          (interpolated(x + h * Vec3::Unit(j), wavy) - interpolated(x - h * Vec3::Unit(j), wavy)) / (2 * h);
    EXPECT_LT((G - difference).norm(), 1e-6 * (G - Mat3::Identity()).norm()) << G << "\n" << difference;
  }
  for (Index ip = 0; ip < d.points().count(); ip += 37) {
    const auto sample = field_at(d, d.points().positions[ip], wavy);
    ASSERT_TRUE(sample);
    EXPECT_LT((sample->deformation_gradient - d.deformation_gradient(ip, wavy)).norm(), 1e-12) << ip;
  }
  // At a node, the displacement its interpolation row gives (the one result.vtu holds).
  for (Index node = 0; node < d.node_count(); node += 11) {
    const auto sample = field_at(d, d.nodes()[node], wavy);
    ASSERT_TRUE(sample);
    EXPECT_LT((sample->displacement - d.interpolate_node(node, wavy)).norm(), 1e-12 * 2e-4) << node;
  }
  EXPECT_FALSE(field_at(d, Vec3(0.5, 0.5, 0.5), wavy));  // far outside every support
}

// Largest |dE/du_i - f_i| over every `stride`-th unknown, by central differences with h = 1e-8 m on u ~ 1e-4 m
// (truncation error O(h^2) times the third derivative of E, round-off O(eps E / h)).
double worst_gradient_error(const ForceKernel& model, std::vector<double> u, std::span<const double> f,
                            std::size_t stride) {
  const double h = 1e-8;
  double worst = 0.0;
  for (std::size_t i = 0; i < u.size(); i += stride) {
    const double saved = u[i];
    u[i] = saved + h;
    const double plus = model.strain_energy(u);
    u[i] = saved - h;
    const double minus = model.strain_energy(u);
    u[i] = saved;
    worst = std::max(worst, std::abs((plus - minus) / (2 * h) - f[i]));
  }
  return worst;
}

TEST(Discretisation, InternalForcesAreTheGradientOfTheDiscreteEnergy) {
  // Without the integration correction (a Bubnov-Galerkin method), f_I = sum w F S grad N_I must equal
  // dE/du_I, E = sum w W(F(u)): checks the assembly, the CSR storage and the materials together.
  for (const std::string material : {"neo_hookean", "ogden"}) {
    const auto model = make_model("mls", 0.25, 4, material, /*consistent=*/false);
    const auto u = random_field(model->discretisation.node_count(), 2e-4, 3);
    std::vector<double> f(u.size());
    ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
    EXPECT_LT(worst_gradient_error(model->kernel, u, f, 17), 1e-6 * max_abs(f)) << material;
  }
}

TEST(Discretisation, AveragedDilatationForcesAreTheGradientOfTheirEnergy) {
  // With nodal volumetric averaging the energy is sum w W(F_bar), F_bar = (J_bar / J)^(1/3) F, and J_bar couples
  // neighbouring points: the forces must still be its exact gradient (what makes relaxation and the energy
  // monitor sound). Same finite-difference check as above; a strong random field so that J varies.
  for (const std::string material : {"neo_hookean", "ogden"}) {
    const auto model = make_model("mmls", 0.25, 4, material, /*consistent=*/false, /*nodal_average=*/true);
    const auto u = random_field(model->discretisation.node_count(), 4e-4, 5);
    std::vector<double> f(u.size());
    ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
    EXPECT_LT(worst_gradient_error(model->kernel, u, f, 13), 1e-6 * max_abs(f)) << material;
  }
}

TEST(Discretisation, AveragedDilatationChangesNothingForAHomogeneousDeformation) {
  // J is the same everywhere, so J_bar = J and F_bar = F: forces equal the per-point ones to round-off.
  const auto plain = make_model("mmls", 0.25, 5, "ogden", true, false);
  const auto averaged = make_model("mmls", 0.25, 5, "ogden", true, true);
  Mat3 G;
  G << -0.08, 0.02, 0.01, 0.03, 0.05, -0.02, 0.0, 0.04, -0.12;
  std::vector<double> u(3 * static_cast<std::size_t>(plain->discretisation.node_count()));
  for (Index i = 0; i < plain->discretisation.node_count(); ++i) {
    const Vec3 d = G * plain->discretisation.nodes()[i];
    for (int c = 0; c < 3; ++c) u[3 * i + c] = d[c];
  }
  std::vector<double> one(u.size()), two(u.size());
  ASSERT_EQ(plain->kernel.internal_forces(u, one), -1);
  ASSERT_EQ(averaged->kernel.internal_forces(u, two), -1);
  double difference = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(one[i] - two[i]));
  EXPECT_LT(difference, 1e-10 * max_abs(one));
  EXPECT_NEAR(averaged->kernel.strain_energy(u), plain->kernel.strain_energy(u),
              1e-12 * plain->kernel.strain_energy(u));
}

TEST(Discretisation, ConsistentIntegrationBalancesAHomogeneousStressWithNodalBoundaryTerms) {
  // With the correction, sum_ip w (grad N_I + xi_I) = sum_K N_I(X_K) A_K (A_K: a third of the outward area of
  // the boundary faces at node K). So for an affine field (uniform P), f_I = sum_K N_I(X_K) P A_K: nodal
  // boundary terms that reactions or zero tractions balance exactly. This is the discrete patch test.
  for (const std::string& sf : test::catalog().names(Category::shape_function)) {
    const auto model = make_model(sf, 0.3, 4);
    Mat3 G;
    G << 0.02, 0.01, -0.03, 0.0, -0.05, 0.01, 0.02, 0.0, 0.04;
    std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count()));
    for (Index i = 0; i < model->discretisation.node_count(); ++i) {
      const Vec3 d = G * model->discretisation.nodes()[i];
      for (int c = 0; c < 3; ++c) u[3 * i + c] = d[c];
    }
    std::vector<double> f(u.size());
    ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
    Mat3 S;
    const Mat3 F = Mat3::Identity() + G;
    ASSERT_TRUE(model->discretisation.material(0).stress(F, S));
    const Mat3 P = F * S;
    std::vector<Vec3> area(static_cast<std::size_t>(model->discretisation.node_count()), Vec3::Zero());
    for (const auto& face : boundary_faces(model->discretisation.mesh())) {
      const Vec3& a = model->discretisation.nodes()[face[0]];
      const Vec3 share =
          (model->discretisation.nodes()[face[1]] - a).cross(model->discretisation.nodes()[face[2]] - a) / 6.0;
      for (Index v : face) area[v] += share;
    }
    std::vector<double> expected(u.size(), 0.0);
    const SupportRows& psi = model->discretisation.basis()->interpolation;
    for (Index k = 0; k < model->discretisation.node_count(); ++k) {
      for (std::int64_t e = psi.offsets[k]; e < psi.offsets[k + 1]; ++e) {
        const Vec3 term = psi.values[e] * (P * area[k]);
        for (int c = 0; c < 3; ++c) expected[3 * static_cast<std::size_t>(psi.nodes[e]) + c] += term[c];
      }
    }
    double difference = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(f[i] - expected[i]));
    EXPECT_LT(difference, 1e-10 * max_abs(f)) << sf;
  }
}

TEST(Discretisation, InternalForcesSumToZeroForAnyDeformation) {
  // Momentum balance of the discrete equations: the internal forces of any state sum to zero, so the
  // reactions of a body at rest balance its external loads. With consistent integration this needs the
  // corrections at each integration point to sum to zero (Discretisation::Options); the earlier per-node constant
  // correction left |sum f| at 0.4-0.6% of sum |f| here. Bound: round-off of sums of about 4,000 terms.
  for (const std::string& sf : test::catalog().names(Category::shape_function))
    for (const bool consistent : {true, false})
      for (const bool nodal_average : {false, true}) {
        const auto model = make_model(sf, 0.3, 5, "ogden", consistent, nodal_average);
        const auto u = random_field(model->discretisation.node_count(), 3e-4, 13);
        std::vector<double> f(u.size());
        ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
        const auto [sum, magnitude] = net_force(f);
        EXPECT_LE(sum.norm(), 1e-12 * magnitude)
            << sf << " consistent " << consistent << " nodal_average " << nodal_average << ": sum " << sum.transpose();
      }
  // Single-precision rows: each point's gradients, rounded to float, no longer sum to exactly zero but to their
  // rounding (2^-24 of each), which mostly cancels over a support: the imbalance stays under one float rounding of
  // the total.
  const auto single = make_model("mmls", 0.3, 5, "ogden", true, false, RowPrecision::single_precision);
  const auto u = random_field(single->discretisation.node_count(), 3e-4, 13);
  std::vector<double> f(u.size());
  ASSERT_EQ(single->kernel.internal_forces(u, f), -1);
  const auto [sum, magnitude] = net_force(f);
  EXPECT_LE(sum.norm(), 0x1p-24 * magnitude) << "single precision: sum " << sum.transpose();
}

TEST(Discretisation, ForcesDoNotDependOnTheThreadCount) {
  // A model sizes its per-thread buffers (and so its team) for the thread count when it is built, and ctest
  // runs with OMP_NUM_THREADS=1: build one model per thread count. The rule holds within each precision of the rows.
  for (const auto& [nodal_average, precision] :
       {std::pair{false, RowPrecision::double_precision}, std::pair{true, RowPrecision::double_precision},
        std::pair{false, RowPrecision::single_precision}}) {
    const int saved = omp_get_max_threads();
    omp_set_num_threads(1);
    const auto serial = make_model("mls", 0.3, 6, "neo_hookean", true, nodal_average, precision);
    omp_set_num_threads(2);
    const auto parallel = make_model("mls", 0.3, 6, "neo_hookean", true, nodal_average, precision);
    omp_set_num_threads(saved);
    ASSERT_EQ(parallel->discretisation.team().size(), 2);
    const auto u = random_field(serial->discretisation.node_count(), 3e-4, 11);
    std::vector<double> one(u.size()), two(u.size());
    serial->kernel.internal_forces(u, one);
    parallel->kernel.internal_forces(u, two);
    // Summation order differs only across the two per-thread buffers: a few ulps of the largest force.
    double difference = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(one[i] - two[i]));
    EXPECT_LE(difference, 1e-13 * max_abs(one))
        << "nodal_average " << nodal_average << ", single " << (precision == RowPrecision::single_precision);
    EXPECT_GT(difference, 0.0) << "expected different summation orders: did the second model run on 2 threads?";
    EXPECT_GT(max_abs(one), 0.0);
  }
}

// The sum over ranges of points (what the mpi backend computes, the points at a partition boundary and the rest in
// two calls): two complementary lists of ranges, one of them out of order and ending mid-batch, add up to the
// whole sum on one and on two threads, with and without the averaged dilatation (whose points' stresses need the
// points around them, inside the ranges or not); the progress call comes only from the calling thread, between
// points. Bound: the same terms summed in another grouping (a few ulps of the largest force).
TEST(Discretisation, ForcesOverRangesOfPointsAddUpToTheWhole) {
  for (const bool nodal_average : {false, true})
    for (const int threads : {1, 2}) {
      const int saved = omp_get_max_threads();
      omp_set_num_threads(threads);
      const auto model = make_model("mmls", 0.3, 18, "ogden", true, nodal_average);
      omp_set_num_threads(saved);
      const std::string label = std::to_string(threads) + " threads, nodal_average " + std::to_string(nodal_average);
      const Index n = model->discretisation.points().count();
      ASSERT_GT(n, 14 * 2048) << "too few points for the progress calls to be tested";
      const auto u = random_field(model->discretisation.node_count(), 5e-5, 17);  // a spacing of 0.6 mm
      std::vector<double> whole(u.size()), first(u.size(), 1.0), second(u.size(), 1.0);
      ASSERT_EQ(model->kernel.internal_forces(u, whole), -1);
      const std::vector<PointRange> some = {{n / 2 + 3, n - 5}, {0, n / 5}};
      const std::vector<PointRange> rest = {{n / 5, n / 2 + 3}, {n - 5, n}};
      int calls = 0;
      const auto caller = std::this_thread::get_id();
      bool other_thread = false;
      ASSERT_EQ(model->kernel.internal_forces(u, first, some), -1);
      ASSERT_EQ(model->kernel.internal_forces(u, second, rest,
                                              [&] {
                                                ++calls;
                                                other_thread = other_thread || std::this_thread::get_id() != caller;
                                              }),
                -1);
      double difference = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i)
        difference = std::max(difference, std::abs(first[i] + second[i] - whole[i]));
      EXPECT_LE(difference, 1e-13 * max_abs(whole)) << label;
      EXPECT_GT(max_abs(first), 0.1 * max_abs(whole)) << label;
      // A range's points alone: a node no point of the range supports gets zero, not what f held.
      std::vector<double> none(u.size(), 1.0);
      ASSERT_EQ(model->kernel.internal_forces(u, none, std::vector<PointRange>{}), -1);
      EXPECT_EQ(max_abs(none), 0.0) << label;
      if (nodal_average) continue;  // the treatment's passes take no progress call
      // The calling thread's share of `rest` (about half of it on two threads) in steps of 2,048 points.
      const Index share = (n / 2 + 3 - n / 5 + 5) / threads;
      EXPECT_GE(calls, share / 2048 - 1) << label;
      EXPECT_LE(calls, share / 2048 + 1) << label;
      EXPECT_FALSE(other_thread);
    }
}

// The vectorised kernel on every instruction set this CPU has, and on the portable baseline, against the
// definition evaluated one point at a time with the laws' one-point stress(): f_I = sum_ip w F S (grad N_I + the
// correction of node I at ip).
// Bound: the same sums in other orders and the laws' vectorised arithmetic (a few ulp per stress): measured
// about 2e-15 of the largest force; 1e-13 leaves room for other clouds while any missing term (the gradient
// correction is about 1e-3 of the gradients) would be far above it. The averaged-dilatation path shares the kernel's gather and scatter:
// it must give the baseline's forces on every instruction set.
TEST(Discretisation, VectorisedForcesEqualTheOnePointDefinitionOnEveryInstructionSet) {
  for (const std::string material : {"neo_hookean", "ogden"}) {
    const auto model = make_model("mmls", 0.3, 5, material);
    const auto u = random_field(model->discretisation.node_count(), 3e-4, 5);
    std::vector<double> reference(u.size(), 0.0);
    const GradientRows& rows = model->discretisation.gradients();
    for (Index ip = 0; ip < model->discretisation.points().count(); ++ip) {
      const Mat3 F = model->discretisation.deformation_gradient(ip, u);
      Mat3 S;
      ASSERT_TRUE(model->discretisation.material(ip).stress(F, S));
      const Mat3 P = model->discretisation.points().weights[ip] * F * S;
      for (int k = 0; k < rows.size(ip); ++k) {
        const Index node = rows.node(ip, k);
        const Vec3 f = P * test_gradient(model->discretisation, ip, k);
        for (int c = 0; c < 3; ++c) reference[3 * static_cast<std::size_t>(node) + c] += f[c];
      }
    }
    int targets = 0;
    test::for_each_simd_target([&](const std::string& target) {
      ++targets;
      std::vector<double> f(u.size());
      ASSERT_EQ(model->kernel.internal_forces(u, f), -1);
      double difference = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(f[i] - reference[i]));
      EXPECT_LE(difference, 1e-13 * max_abs(reference)) << material << " on " << target;
      std::cout << material << " on " << target << ": max difference / max force " << difference / max_abs(reference) << "\n";
    });
    EXPECT_GE(targets, 2) << "at least the CPU's best and the baseline";
  }
  const auto averaged = make_model("mls", 0.3, 5, "ogden", true, true);
  const auto u = random_field(averaged->discretisation.node_count(), 3e-4, 6);
  std::vector<double> baseline(u.size());
  test::for_each_simd_target([&](const std::string& target) {
    std::vector<double> f(u.size());
    ASSERT_EQ(averaged->kernel.internal_forces(u, f), -1);
    if (target == "EMU128" || target == "SCALAR") baseline = f;
  });
  ASSERT_GT(max_abs(baseline), 0.0);
  test::for_each_simd_target([&](const std::string& target) {
    std::vector<double> f(u.size());
    averaged->kernel.internal_forces(u, f);
    double difference = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(f[i] - baseline[i]));
    EXPECT_LE(difference, 1e-13 * max_abs(baseline)) << "averaged dilatation on " << target;
  });
}

// Single-precision rows round each stored gradient once, by at most 2^-24 of itself; the forces are linear in the
// gradients (through F and through the test gradients), so they move by about that fraction of the forces' own size
// (measured 0.35 of it on this cloud), far under what the discretisation resolves. 4 x 2^-24 leaves room for other clouds; any
// gradient stored wrongly would be orders above it. The difference must not be zero: the precision took effect.
TEST(Discretisation, SinglePrecisionRowsChangeTheForcesByTheirRoundingOnly) {
  for (const bool nodal_average : {false, true}) {
    const auto exact = make_model("mmls", 0.3, 5, "ogden", true, nodal_average);
    const auto single = make_model("mmls", 0.3, 5, "ogden", true, nodal_average, RowPrecision::single_precision);
    const auto u = random_field(exact->discretisation.node_count(), 3e-4, 9);
    std::vector<double> a(u.size()), b(u.size());
    ASSERT_EQ(exact->kernel.internal_forces(u, a), -1);
    ASSERT_EQ(single->kernel.internal_forces(u, b), -1);
    double difference = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i) difference = std::max(difference, std::abs(a[i] - b[i]));
    std::cout << "nodal_average " << nodal_average << ": single against double, max difference / max force "
              << difference / max_abs(a) << "\n";
    EXPECT_LE(difference, 4.0 * 0x1p-24 * max_abs(a)) << "nodal_average " << nodal_average;
    EXPECT_GT(difference, 0.0) << "nodal_average " << nodal_average;
  }
}

TEST(Discretisation, InvertedMaterialIsReportedNotHidden) {
  const auto model = make_model();
  std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count()));
  for (Index i = 0; i < model->discretisation.node_count(); ++i)
    u[3 * i + 2] = -2.0 * model->discretisation.nodes()[i][2];  // F_zz = -1
  std::vector<double> f(u.size());
  EXPECT_EQ(model->kernel.internal_forces(u, f), 0);  // the first integration point, whatever the thread count
}

// A discretisation made from another's basis with another material is the one built from scratch with that material:
// nothing that depends on the material lives in the basis (a fit's forward runs share it). Compared to the last bit:
// the same arithmetic on the same rows.
TEST(Discretisation, ASharedBasisWithAnotherMaterialIsTheDiscretisationBuiltForIt) {
  const auto neo_hookean = make_model("mls", 0.25, 5, "neo_hookean");
  // Stiffer and denser than make_model's: other critical steps and masses.
  const auto material =
      test::make<Material>("ogden", {{"mu", 3 * kMu}, {"D", kD}, {"density", 1200.0}, {"alpha", -1.3}});
  const test::Discretised built(test::box_mesh(Vec3(0.01, 0.01, 0.01), 5, 5, 5, 0.25, 7),
                                test::make<ShapeFunctions>("mls", json::object()), {material}, {});
  const Discretisation shared(neo_hookean->discretisation.basis(), {material}, 0);
  EXPECT_EQ(shared.basis().get(), neo_hookean->discretisation.basis().get());  // not a copy
  EXPECT_EQ(shared.critical_time_steps(), built.discretisation.critical_time_steps());
  EXPECT_NE(shared.critical_time_steps(), neo_hookean->discretisation.critical_time_steps());
  EXPECT_EQ(shared.lumped_mass(), built.discretisation.lumped_mass());
  const ForceKernel kernel(shared, nullptr);
  const std::vector<double> u = random_field(shared.node_count(), 2e-4, 3);
  std::vector<double> f_shared(u.size()), f_built(u.size());
  ASSERT_LT(kernel.internal_forces(u, f_shared), 0);
  ASSERT_LT(built.kernel.internal_forces(u, f_built), 0);
  EXPECT_EQ(f_shared, f_built);
}

TEST(Discretisation, StableTimeStepScalesWithNodeSpacing) {
  // dt = 2 / (c sqrt(n sum |grad N|^2)) ~ h / c: halving the spacing halves the step.
  const auto coarse = make_model("mls", 0.0, 4);
  const auto fine = make_model("mls", 0.0, 8);
  const auto min_of = [](const test::Discretised& m) {
    const auto& dt = m.discretisation.critical_time_steps();
    return *std::min_element(dt.begin(), dt.end());
  };
  const double ratio = min_of(*coarse) / min_of(*fine);
  EXPECT_NEAR(ratio, 2.0, 0.1);
  // And it is below the dilatational wave's transit time across one cell.
  const double c = std::sqrt((2.0 / kD + 4.0 / 3.0 * kMu) / 1000.0);
  EXPECT_LT(min_of(*coarse), 0.01 / 4 / c);
}

// stiffening() against an independent computation: under an affine field (reproduced exactly by the shape functions)
// every point has the same F0, and its stiffening is the largest eigenvalue of the Hessian of the strain energy
// d2W/dF2 at F0 over that at F = I, here by central second differences of W (the model's from forward differences of
// the stress, by power iteration). Those forward differences (step 1e-6) are off by about 1e-6 of the eigenvalue (3e-7
// measured), the energy's second differences by about 1e-8: 1e-5 allows for both.
TEST(Discretisation, StiffeningIsTheLargestTangentModulusOverItsValueAtRest) {
  for (const std::string law : {"neo_hookean", "ogden"}) {
    const auto model = make_model("mls", 0.25, 4, law);
    Mat3 F0;
    F0 << 1.0, 1.0, 0.0, 0.0, 1.05, 0.1, 0.0, 0.0, 0.98;  // a shear of 1 and a small volume change
    std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count()));
    for (Index i = 0; i < model->discretisation.node_count(); ++i) {
      const Vec3 x = (F0 - Mat3::Identity()) * model->discretisation.nodes()[i];
      for (int c = 0; c < 3; ++c) u[3 * static_cast<std::size_t>(i) + c] = x[c];
    }
    const Material& material = model->discretisation.material(0);
    auto largest_hessian_eigenvalue = [&](const Mat3& F) {
      constexpr double kDelta = 1e-4;
      Eigen::Matrix<double, 9, 9> hessian;
      auto energy = [&](int a, double da, int b, double db) {
        Mat3 G = F;
        G(a / 3, a % 3) += da;
        G(b / 3, b % 3) += db;
        return material.energy(G);
      };
      for (int a = 0; a < 9; ++a)
        for (int b = 0; b < 9; ++b)
          hessian(a, b) = (energy(a, kDelta, b, kDelta) - energy(a, kDelta, b, -kDelta) -
                           energy(a, -kDelta, b, kDelta) + energy(a, -kDelta, b, -kDelta)) /
                          (4.0 * kDelta * kDelta);
      return Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>>(hessian).eigenvalues()[8];
    };
    const double expected = largest_hessian_eigenvalue(F0) / largest_hessian_eigenvalue(Mat3::Identity());
    EXPECT_GT(expected, 1.2) << law;  // a deformation that stiffens the law measurably
    const std::vector<double> ratio = mtled::stiffening(model->discretisation, u);
    ASSERT_EQ(ratio.size(), static_cast<std::size_t>(model->discretisation.points().count()));
    for (std::size_t ip = 0; ip < ratio.size(); ++ip)
      ASSERT_NEAR(ratio[ip], expected, 1e-5 * expected) << law << " point " << ip;
    const std::vector<double> at_rest = mtled::stiffening(model->discretisation, std::vector<double>(u.size(), 0.0));
    for (double s : at_rest) ASSERT_EQ(s, 1.0) << law;
  }
}

class ConstraintsTest : public ::testing::TestWithParam<std::string> {};

// Checked on every instruction set the CPU runs (the solves with the factor are vectorised), for blocks of 1, 2 and 3
// components: "all" with "some" gives x and y one block (the rows of "all") and z another; "all" alone, one of three.
TEST_P(ConstraintsTest, InterpolatedDisplacementEqualsThePrescribedOneToRoundOff) {
  const auto model = make_model(GetParam(), 0.3, 5);
  const auto start = random_field(model->discretisation.node_count(), 1e-3, 5);
  const auto mass = model->discretisation.lumped_mass();
  NodalConstraints all, some;
  all.name = "all";
  some.name = "some";
  some.set_components({false, false, true});
  std::mt19937 random(9);
  std::uniform_real_distribution<double> uniform(-1e-3, 1e-3);
  for (Index i = 0; i < model->discretisation.node_count(); i += 5) {
    NodalConstraints& set = (i % 2 == 0) ? all : some;
    set.add_node(i, Vec3(uniform(random), uniform(random), uniform(random)));
  }
  for (const std::vector<NodalConstraints*>& sets : {std::vector{&all, &some}, std::vector{&all}}) {
    ConstraintSystem constraints(model->discretisation);
    constraints.update(sets, mass, true);
    test::for_each_simd_target([&](const std::string& target) {
      auto u = start;
      constraints.enforce(u, 1.0);
      for (const NodalConstraints* set : sets) {
        for (std::size_t k = 0; k < set->size(); ++k) {
          const Vec3 v = model->discretisation.interpolate_node(set->nodes()[k], u);
          for (int c = 0; c < 3; ++c) {
            if (!set->components()[c]) continue;
            EXPECT_NEAR(v[c], set->values[k][c], 1e-15) << set->name << " node " << set->nodes()[k] << " on " << target;
          }
        }
      }
      // Unconstrained components of "some" are not forced to anything: x and y keep their own interpolant.
      // The correction is the M-orthogonal projection: the reactions lambda satisfy M du = Phi^T lambda.
      std::vector<double> force(u.size(), 0.0);
      constraints.add_constraint_forces(force);
      for (std::size_t i = 0; i < u.size(); ++i)
        EXPECT_NEAR(mass[i / 3] * (u[i] - start[i]), force[i], 1e-18) << "on " << target;
    });
  }
}

// A fixed bottom face and a few nodes of the top face (a needle's captured nodes) whose supports share no node: two
// independent parts of the constraint matrix. When the top set changes, only its part is factorised again, and the
// projection equals, to the last bits, that of a system built afresh; a set that couples the parts joins them.
TEST_P(ConstraintsTest, AChangedSetRefactorisesOnlyItsOwnPart) {
  const auto model = make_model(GetParam(), 0.3, 8);
  const auto mass = model->discretisation.lumped_mass();
  NodalConstraints bottom, top;
  bottom.name = "bottom";
  top.name = "top";
  std::vector<Index> upper;
  for (Index i = 0; i < model->discretisation.node_count(); ++i) {
    if (model->discretisation.nodes()[i][2] < 1e-9) bottom.add_node(i, Vec3::Zero());
    if (model->discretisation.nodes()[i][2] > 0.01 - 1e-9) upper.push_back(i);
  }
  ASSERT_GE(upper.size(), 4u);
  for (std::size_t k = 0; k < 2; ++k) top.add_node(upper[k], Vec3(1e-4, 0.0, -2e-4));
  ConstraintSystem constraints(model->discretisation);
  constraints.update({&bottom, &top}, mass, true);
  ASSERT_EQ(constraints.parts(), 2u) << "the bottom and top sets were meant to be uncoupled";
  ASSERT_EQ(constraints.parts_factorised(), 2);

  const auto projected = [&](ConstraintSystem& system) {
    auto u = random_field(model->discretisation.node_count(), 1e-3, 11);
    system.enforce(u, 1.0);
    return u;
  };
  const auto expect_same_as_afresh = [&](const std::vector<double>& u) {
    ConstraintSystem afresh(model->discretisation);
    afresh.update({&bottom, &top}, mass, true);
    const auto reference = projected(afresh);
    for (std::size_t i = 0; i < u.size(); ++i) ASSERT_EQ(u[i], reference[i]) << "unknown " << i;
    for (const NodalConstraints* set : {&bottom, &top})
      for (std::size_t k = 0; k < set->size(); ++k)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(model->discretisation.interpolate_node(set->nodes()[k], u)[c], set->values[k][c], 1e-15)
              << set->name;
  };
  top.add_node(upper[2], Vec3(0.0, 1e-4, -2e-4));
  constraints.update({&bottom, &top}, mass, false);
  EXPECT_EQ(constraints.parts_factorised(), 3);  // the top's part only
  expect_same_as_afresh(projected(constraints));

  // A column of nodes from the bottom face to the top one couples the two: one part, factorised.
  for (Index i = 0; i < model->discretisation.node_count(); ++i)
    if (std::abs(model->discretisation.nodes()[i][0] - model->discretisation.nodes()[upper[0]][0]) < 1e-3 &&
        std::abs(model->discretisation.nodes()[i][1] - model->discretisation.nodes()[upper[0]][1]) < 1e-3 &&
        model->discretisation.nodes()[i][2] > 1e-9 && model->discretisation.nodes()[i][2] < 0.01 - 1e-9)
      top.add_node(i, Vec3(0.0, 0.0, -1e-4));
  constraints.update({&bottom, &top}, mass, false);
  EXPECT_EQ(constraints.parts(), 1u);
  EXPECT_EQ(constraints.parts_factorised(), 4);
  expect_same_as_afresh(projected(constraints));
}

INSTANTIATE_TEST_SUITE_P(EveryShapeFunction, ConstraintsTest,
                         ::testing::ValuesIn(test::catalog().names(Category::shape_function)));

}  // namespace
}  // namespace mtled
