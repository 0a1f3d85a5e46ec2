// Conformance suite for every material plugin the catalog finds, each built from its declaration's
// example() block through the real loader: a new material is checked without touching this file.
//
// Stress scale: every tolerance below is relative to M = p_wave_modulus() (lambda + 2 mu), the largest
// small-strain modulus of an isotropic law, so that one number works for stiff and soft materials alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <new>
#include <random>
#include <thread>

#include <Eigen/SVD>

#include "material_test_support.hpp"
#include "mtled/interfaces/material.hpp"
#include "simd_targets.hpp"
#include "test_support.hpp"

// Counts every allocation through operator new in this executable and the plugins it loads (a plugin's
// undefined operator new binds to this definition), for the check that stress() and energy() allocate
// nothing: they run once per integration point per time step.
namespace {
std::atomic<long> allocation_count{0};
}  // namespace

// GCC 12 reports free() of memory from a replaced operator new as a mismatch; new and delete are replaced
// together here, so every pointer is freed by the allocator that made it.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  allocation_count.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace mtled {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

std::vector<std::string> material_names() { return test::catalog().names(Category::material); }

// Every material found, so that an empty plugin folder fails loudly instead of running nothing.
TEST(MaterialCatalog, FindsTheBuiltInMaterials) {
  const auto names = material_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "neo_hookean"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "ogden"), names.end());
}

class MaterialConformance : public ::testing::TestWithParam<std::string> {
 protected:
  const ComponentDeclaration& declaration() const { return test::catalog().load(Category::material, GetParam()); }
  std::shared_ptr<Material> make() const { return test::make<Material>(GetParam(), declaration().example()); }
};

// ------------------------------------------------------------------------------------------- declaration

TEST_P(MaterialConformance, DeclarationIsComplete) {
  const ComponentDeclaration& d = declaration();
  EXPECT_FALSE(d.summary().empty());
  for (const ParameterSpec& spec : d.parameters()) {
    SCOPED_TRACE(spec.name);
    EXPECT_FALSE(spec.doc.empty());
    EXPECT_FALSE(spec.unit.empty()) << "use \"1\" for a dimensionless parameter";
    if (spec.default_value && (spec.type == ParameterType::number || spec.type == ParameterType::integer)) {
      ASSERT_TRUE(spec.default_value->is_number());
      EXPECT_TRUE(spec.range.contains(spec.default_value->get<double>()))
          << "default " << spec.default_value->dump() << " is outside " << spec.range.describe();
    }
  }
  ASSERT_TRUE(d.example().is_object());
  EXPECT_FALSE(d.example().empty()) << "example() must give a working parameter block";
  EXPECT_FALSE(d.example().contains("type")) << "example() blocks are written without \"type\"";
  std::vector<Problem> problems;
  validate_parameters(d, d.example(), "/materials/0", problems);
  for (const auto& problem : problems) ADD_FAILURE() << "example does not validate: " << problem.format();
}

TEST_P(MaterialConformance, ModuliArePositiveAndFinite) {
  const auto material = make();
  EXPECT_TRUE(std::isfinite(material->density()) && material->density() > 0.0);
  EXPECT_TRUE(std::isfinite(material->p_wave_modulus()) && material->p_wave_modulus() > 0.0);
}

// Every bound a parameter declares is enforced by validation, at that parameter's JSON pointer, with the
// allowed range in the message; every required parameter is reported when missing.
TEST_P(MaterialConformance, ValidationRefusesOutOfRangeAndMissingParameters) {
  const ComponentDeclaration& d = declaration();
  for (const ParameterSpec& spec : d.parameters()) {
    if (spec.type != ParameterType::number && spec.type != ParameterType::integer) continue;
    std::vector<double> outside;
    if (spec.range.min) outside.push_back(spec.range.min_exclusive ? *spec.range.min : *spec.range.min - 1.0);
    if (spec.range.max) outside.push_back(spec.range.max_exclusive ? *spec.range.max : *spec.range.max + 1.0);
    if (spec.range.nonzero) outside.push_back(0.0);
    for (double value : outside) {
      SCOPED_TRACE(spec.name + " = " + std::to_string(value));
      json block = d.example();
      block[spec.name] = value;
      std::vector<Problem> problems;
      validate_parameters(d, block, "/materials/3", problems);
      ASSERT_EQ(problems.size(), 1u);
      EXPECT_EQ(problems[0].where, "/materials/3/" + spec.name);
      EXPECT_NE(problems[0].message.find(spec.range.describe()), std::string::npos) << problems[0].message;
    }
  }
  for (const ParameterSpec& spec : d.parameters()) {
    if (!spec.required) continue;
    SCOPED_TRACE(spec.name);
    json block = d.example();
    block.erase(spec.name);
    std::vector<Problem> problems;
    validate_parameters(d, block, "/materials/3", problems);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_EQ(problems[0].where, "/materials/3/" + spec.name);
    EXPECT_NE(problems[0].message.find("missing"), std::string::npos) << problems[0].message;
  }
}

// ------------------------------------------------------------------------------------------ stress/energy

// No stress and no energy in the undeformed state. The bound allows a few roundings of terms of size M.
TEST_P(MaterialConformance, UndeformedStateIsStressFree) {
  const auto material = make();
  const double M = material->p_wave_modulus();
  Mat3 S;
  ASSERT_TRUE(material->stress(Mat3::Identity(), S));
  EXPECT_LE(S.cwiseAbs().maxCoeff(), 10 * kEpsilon * M) << S;
  EXPECT_LE(std::abs(material->energy(Mat3::Identity())), 10 * kEpsilon * M);
}

// S is symmetric and W is finite at every admissible F of the test set. The bound: a few roundings of
// the largest stress component.
TEST_P(MaterialConformance, StressIsSymmetric) {
  const auto material = make();
  const double M = material->p_wave_modulus();
  for (const auto& [name, F] : test::admissible_deformations()) {
    SCOPED_TRACE(name);
    Mat3 S;
    ASSERT_TRUE(material->stress(F, S));
    ASSERT_TRUE(S.allFinite());
    ASSERT_TRUE(std::isfinite(material->energy(F)));
    EXPECT_LE((S - S.transpose()).cwiseAbs().maxCoeff(), 100 * kEpsilon * std::max(M, S.cwiseAbs().maxCoeff()));
  }
}

// S against the energy: P = F S must equal dW/dF, here by central differences of W.
// Step and tolerance from the error estimate of a central difference: truncation h^2/6 |d3W/dF3| plus
// round-off ~ eps |W| / h. Over this test set (stretches 0.5 to 2) W and its third derivatives are at most
// a few tens of M, so h = 1e-5 (near the optimum (3 eps)^(1/3) ~ 1e-5 for F entries of order 1) gives an
// error of order (1e-11 + 2e-11) x 50 M ~ 2e-9 M. The tolerance 1e-7 M sits well above that and far below
// any real defect: a wrong factor or term in S is at least ~1e-3 M at these strains.
TEST_P(MaterialConformance, StressIsTheDerivativeOfTheEnergy) {
  const auto material = make();
  const double M = material->p_wave_modulus();
  constexpr double h = 1e-5;
  double worst = 0.0;
  for (const auto& [name, F] : test::admissible_deformations()) {
    SCOPED_TRACE(name);
    Mat3 S;
    ASSERT_TRUE(material->stress(F, S));
    Mat3 P_fd;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        Mat3 plus = F, minus = F;
        plus(i, j) += h;
        minus(i, j) -= h;
        P_fd(i, j) = (material->energy(plus) - material->energy(minus)) / (2.0 * h);
      }
    const double error = (F * S - P_fd).cwiseAbs().maxCoeff();
    worst = std::max(worst, error / M);
    EXPECT_LE(error, 1e-7 * M) << "F S =\n" << F * S << "\ndW/dF =\n" << P_fd;
  }
  RecordProperty("worst_relative_error", std::to_string(worst));
  std::cout << GetParam() << ": max |F S - dW/dF| / M = " << worst << "\n";
}

// Objectivity: a rigid rotation after the deformation changes neither S (a material-frame tensor) nor W.
// Rounding Q F perturbs F by ~eps |F|, which moves S by ~eps M |F| times a factor of order 10 at these
// strains; 1e-12 M leaves two orders of magnitude for evaluation round-off.
TEST_P(MaterialConformance, StressAndEnergyAreObjective) {
  const auto material = make();
  const double M = material->p_wave_modulus();
  std::mt19937 random(7);
  double worst_stress = 0.0, worst_energy = 0.0;
  for (const auto& [name, F] : test::admissible_deformations()) {
    SCOPED_TRACE(name);
    Mat3 S;
    ASSERT_TRUE(material->stress(F, S));
    const double W = material->energy(F);
    for (int k = 0; k < 3; ++k) {
      const Mat3 Q = test::random_rotation(random);
      Mat3 S_rotated;
      ASSERT_TRUE(material->stress(Q * F, S_rotated));
      const double stress_change = (S_rotated - S).cwiseAbs().maxCoeff();
      const double energy_change = std::abs(material->energy(Q * F) - W);
      worst_stress = std::max(worst_stress, stress_change / M);
      worst_energy = std::max(worst_energy, energy_change / M);
      EXPECT_LE(stress_change, 1e-12 * M);
      EXPECT_LE(energy_change, 1e-12 * M);
    }
  }
  std::cout << GetParam() << ": max |S(QF) - S(F)| / M = " << worst_stress << ", max |W(QF) - W(F)| / M = " << worst_energy
            << "\n";
}

// At F = I + e e1 (x) e1 (uniaxial strain) the linearised law gives S_11 = (lambda + 2 mu) e. A central
// difference in e cancels the quadratic term: error ~ e^2 x (third-order coefficient, a few M) ~ 1e-8 M
// with e = 1e-4, round-off ~ eps M / e ~ 2e-12 M; tolerance 1e-6 (relative). A law whose p_wave_modulus()
// used K + mu instead of K + 4 mu / 3 would be off by 1e-2 for a nearly incompressible material.
TEST_P(MaterialConformance, LinearisedResponseMatchesPWaveModulus) {
  const auto material = make();
  constexpr double e = 1e-4;
  for (int axis = 0; axis < 3; ++axis) {
    SCOPED_TRACE(axis);
    Mat3 F_plus = Mat3::Identity(), F_minus = Mat3::Identity();
    F_plus(axis, axis) += e;
    F_minus(axis, axis) -= e;
    Mat3 S_plus, S_minus;
    ASSERT_TRUE(material->stress(F_plus, S_plus));
    ASSERT_TRUE(material->stress(F_minus, S_minus));
    const double modulus = (S_plus(axis, axis) - S_minus(axis, axis)) / (2.0 * e);
    EXPECT_NEAR(modulus / material->p_wave_modulus(), 1.0, 1e-6);
    if (axis == 0) std::cout << GetParam() << ": dS_11/de / p_wave_modulus - 1 = " << modulus / material->p_wave_modulus() - 1 << "\n";
  }
}

// An inverted (J < 0), collapsed (J = 0) or non-finite F is refused: stress() returns false and leaves S
// as it was, energy() is NaN. A law that used |J| would accept the reflections.
TEST_P(MaterialConformance, InadmissibleDeformationIsRefused) {
  const auto material = make();
  std::mt19937 random(11);
  const Mat3 R = test::random_rotation(random);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<test::NamedDeformation> refused = {
      {"reflection diag(-1, 1, 1)", Vec3(-1.0, 1.0, 1.0).asDiagonal()},
      {"rotated reflection", R * Vec3(1.0, 1.0, -1.0).asDiagonal()},
      {"point inversion -I", -Mat3::Identity()},
      {"inverted, stretched", R * Vec3(1.3, -0.7, 0.9).asDiagonal() * test::random_rotation(random).transpose()},
      {"collapsed plane diag(1, 1, 0)", Vec3(1.0, 1.0, 0.0).asDiagonal()},
      {"collapsed, rank 1", Vec3(1.0, 2.0, 3.0) * Vec3(0.5, -1.0, 2.0).transpose()},
      {"zero", Mat3::Zero()},
  };
  for (int entry : {0, 4, 7}) {
    Mat3 F = Mat3::Identity();
    F(entry) = nan;
    refused.push_back({"NaN entry " + std::to_string(entry), F});
    F(entry) = inf;
    refused.push_back({"infinite entry " + std::to_string(entry), F});
    F = Mat3::Identity();
    F(entry) = -inf;
    refused.push_back({"-infinite entry " + std::to_string(entry), F});
  }
  for (const auto& [name, F] : refused) {
    SCOPED_TRACE(name);
    Mat3 S = Mat3::Constant(42.0);
    EXPECT_FALSE(material->stress(F, S));
    EXPECT_EQ(S, Mat3::Constant(42.0)) << "S must be left untouched";
    EXPECT_TRUE(std::isnan(material->energy(F)));
  }
}

// Far outside any physical state but still J > 0: a law may refuse these (its arithmetic can overflow or
// lose C's smallest eigenvalue to round-off), but when it accepts one the stress must be finite, or the
// solver would carry NaN forward as if it were a state.
TEST_P(MaterialConformance, ExtremeDeformationGivesFiniteStressOrIsRefused) {
  const auto material = make();
  std::mt19937 random(13);
  const std::vector<Vec3> stretches = {Vec3(1e-3, 1.0, 1.0), Vec3(1e3, 1e-3, 1.0), Vec3(1e-8, 1e4, 1e4),
                                       Vec3(1e100, 1.0, 1.0), Vec3(1e-100, 1e50, 1e50), Vec3(1e-200, 1.0, 1.0)};
  for (const Vec3& s : stretches) {
    SCOPED_TRACE(::testing::Message() << "stretches " << s.transpose());
    const Mat3 F = test::from_stretches(test::random_rotation(random), s, test::random_rotation(random));
    Mat3 S = Mat3::Constant(42.0);
    if (material->stress(F, S)) {
      EXPECT_TRUE(S.allFinite()) << S;
    } else {
      EXPECT_EQ(S, Mat3::Constant(42.0)) << "S must be left untouched";
    }
  }
}

// The hot path allocates nothing (the Material interface's rule): no counted allocation while evaluating
// stress and energy over the whole test set, inadmissible F included.
TEST_P(MaterialConformance, EvaluationDoesNotAllocate) {
  const auto material = make();
  std::vector<Mat3> deformations;
  for (const auto& named : test::admissible_deformations()) deformations.push_back(named.F);
  deformations.push_back(-Mat3::Identity());
  deformations.push_back(Mat3::Constant(std::numeric_limits<double>::quiet_NaN()));
  Mat3 S;
  double sink = 0.0;
  const long before = allocation_count.load();
  for (const Mat3& F : deformations) {
    if (material->stress(F, S)) sink += S(0, 0);
    sink += material->energy(F);
  }
  const long allocations = allocation_count.load() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_TRUE(std::isnan(sink)) << "the NaN F's energy is NaN";
}

// const and stateless: two threads evaluating at once get bit-for-bit what one thread gets.
TEST_P(MaterialConformance, ConcurrentEvaluationGivesTheSameResults) {
  const auto material = make();
  const auto deformations = test::admissible_deformations();
  std::vector<Mat3> serial(deformations.size());
  std::vector<double> serial_energy(deformations.size());
  for (std::size_t k = 0; k < deformations.size(); ++k) {
    ASSERT_TRUE(material->stress(deformations[k].F, serial[k]));
    serial_energy[k] = material->energy(deformations[k].F);
  }
  std::array<int, 2> mismatches{};
  const auto work = [&](int thread) {
    for (int repeat = 0; repeat < 2000; ++repeat)
      for (std::size_t k = 0; k < deformations.size(); ++k) {
        Mat3 S;
        const bool ok = material->stress(deformations[k].F, S);
        if (!ok || S != serial[k] || material->energy(deformations[k].F) != serial_energy[k]) ++mismatches[thread];
      }
  };
  std::thread first(work, 0), second(work, 1);
  first.join();
  second.join();
  EXPECT_EQ(mismatches[0], 0);
  EXPECT_EQ(mismatches[1], 0);
}

// stress_batch() is what the force kernel calls: a vectorised law must agree with its one-point stress() on
// every instruction set the CPU has and on the portable baseline, in every lane: the admissible set (equal and
// nearly equal stretches included), the identity, refused F, and extreme F, mixed within one batch so that a
// refused lane cannot spoil its neighbours. Bound: the two compute the same formulas with different roundings
// (fused multiply-adds, a vectorised exp/log/acos/cos accurate to a few ulp): a few hundred roundings of M, times
// the condition number of C (the smallest eigenvalue of C carries an absolute error of about eps |C|, and the
// stress divides by it: 1 to 16 over the admissible set, 1e6 for the stretch of 1e-3).
TEST_P(MaterialConformance, BatchedStressEqualsOnePointStress) {
  const auto material = make();
  const double M = material->p_wave_modulus();
  std::vector<Mat3> deformations;
  for (const auto& named : test::admissible_deformations()) deformations.push_back(named.F);
  std::mt19937 random(17);
  deformations.push_back(Mat3::Identity());
  deformations.push_back(-Mat3::Identity());
  deformations.push_back(test::from_stretches(test::random_rotation(random), Vec3(1e-3, 1.0, 1.0), test::random_rotation(random)));
  deformations.push_back(Mat3::Constant(std::numeric_limits<double>::quiet_NaN()));
  deformations.push_back(Vec3(1.0, 1.0, 0.0).asDiagonal());
  deformations.push_back(test::from_stretches(test::random_rotation(random), Vec3(1e-100, 1e50, 1e50), test::random_rotation(random)));
  test::for_each_simd_target([&](const std::string& target) {
    SCOPED_TRACE(target);
    double worst = 0.0;
    for (std::size_t first = 0; first < deformations.size(); first += StressBatch::kCapacity) {
      StressBatch batch;
      batch.count = static_cast<int>(std::min<std::size_t>(StressBatch::kCapacity, deformations.size() - first));
      for (int p = 0; p < StressBatch::kCapacity; ++p) {
        const Mat3 F = p < batch.count ? deformations[first + p] : Mat3::Identity();
        batch.set_deformation_gradient(p, F);
      }
      material->stress_batch(batch);
      for (int p = 0; p < batch.count; ++p) {
        const Mat3& F = deformations[first + p];
        SCOPED_TRACE(::testing::Message() << "F =\n" << F);
        Mat3 S;
        const bool admissible = material->stress(F, S);
        ASSERT_EQ(batch.admissible[p], admissible);
        if (!admissible) continue;
        const Mat3 S_batch = batch.stress(p);
        const Vec3 singular = Eigen::JacobiSVD<Mat3>(F).singularValues();
        const double condition = std::pow(singular.maxCoeff() / singular.minCoeff(), 2);
        const double error = (S_batch - S).cwiseAbs().maxCoeff() / std::max(M, S.cwiseAbs().maxCoeff());
        worst = std::max(worst, error / condition);
        EXPECT_LE(error, 256 * kEpsilon * condition) << "batched\n" << S_batch << "\none point\n" << S;
      }
    }
    std::cout << GetParam() << " on " << target << ": max |S_batch - S| / (max(M, |S|) cond(C)) = " << worst / kEpsilon
              << " eps\n";
  });
}

INSTANTIATE_TEST_SUITE_P(EveryMaterial, MaterialConformance, ::testing::ValuesIn(material_names()),
                         [](const ::testing::TestParamInfo<std::string>& param_info) { return param_info.param; });

}  // namespace
}  // namespace mtled
