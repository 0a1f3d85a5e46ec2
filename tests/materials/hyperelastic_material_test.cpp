// Tests specific to the neo_hookean and ogden plugins (the generic checks are in the conformance suite):
// Ogden with alpha = 2 is neo-Hookean, the stress is accurate to round-off at equal and nearly equal
// stretches, the homogeneous uniaxial state of the paper's Sylgard 527 material, parameter handling, and
// the cost of one stress evaluation.
#include <ostream>
#include <gtest/gtest.h>

#include <time.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <random>

#include "material_test_support.hpp"
#include "mtled/interfaces/material.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

// The paper's materials: Sylgard 527 (Ogden, section 2.2.2 and Table 1, Material 2) and the neo-Hookean
// comparison (Table 1, Material 4); both nu = 0.49, D = 3(1 - 2 nu) / (mu (1 + nu)).
const json kSylgard = {{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}};
const json kNeoHookean = {{"mu", 1000.0}, {"D", 4.02684e-5}};

json ogden_with(double mu, double alpha, double D) { return {{"mu", mu}, {"alpha", alpha}, {"D", D}}; }

// The one-term Ogden law in principal stretches, evaluated in long double straight from W, with no eigen
// decomposition: the reference for the tests below. dW/dlambda_i of
//   W = (2 mu / alpha^2)(J^(-alpha/3) sum_j lambda_j^alpha - 3) + (1/D)(J - 1)^2,  J = lambda_1 lambda_2 lambda_3.
struct PrincipalOgden {
  long double mu, alpha, D;
  using Vec3L = Eigen::Matrix<long double, 3, 1>;

  long double energy(const Vec3L& l) const {
    const long double J = l.prod();
    long double sum = 0;
    for (int i = 0; i < 3; ++i) sum += std::pow(l[i], alpha);
    return 2 * mu / (alpha * alpha) * (std::pow(J, -alpha / 3) * sum - 3) + (J - 1) * (J - 1) / D;
  }
  // Nominal (first Piola-Kirchhoff) principal stresses dW/dlambda_i.
  Vec3L nominal_stress(const Vec3L& l) const {
    const long double J = l.prod();
    long double sum = 0;
    for (int i = 0; i < 3; ++i) sum += std::pow(l[i], alpha);
    const long double deviatoric = 2 * mu / alpha * std::pow(J, -alpha / 3);
    Vec3L P;
    for (int i = 0; i < 3; ++i)
      P[i] = deviatoric * (std::pow(l[i], alpha - 1) - sum / (3 * l[i])) + 2 / D * (J - 1) * J / l[i];
    return P;
  }
};

// ------------------------------------------------------------------------------------- alpha = 2 is neo-H

// The two plugins evaluate the same W by different routes (C^-1 against an eigen decomposition). Each is
// accurate to a few tens of roundings of terms of size M (S is at most ~M here), so they agree to
// ~1e-14 M; the bound 1e-12 M leaves a factor 100.
TEST(OgdenMaterial, AlphaTwoIsNeoHookean) {
  double worst = 0.0;
  for (const auto& [mu, D] : {std::pair{1000.0, 4.02684e-5}, std::pair{722.0, 5.57738e-5}, std::pair{3.0e4, 1e-6}}) {
    const auto neo_hookean = test::make<Material>("neo_hookean", {{"mu", mu}, {"D", D}, {"density", 1100.0}});
    const auto ogden = test::make<Material>("ogden", {{"mu", mu}, {"alpha", 2.0}, {"D", D}, {"density", 1100.0}});
    const double M = neo_hookean->p_wave_modulus();
    EXPECT_DOUBLE_EQ(ogden->p_wave_modulus(), M);
    EXPECT_EQ(ogden->density(), neo_hookean->density());
    for (const auto& [name, F] : test::admissible_deformations(99)) {
      SCOPED_TRACE(name);
      Mat3 S_neo_hookean, S_ogden;
      ASSERT_TRUE(neo_hookean->stress(F, S_neo_hookean));
      ASSERT_TRUE(ogden->stress(F, S_ogden));
      EXPECT_LE((S_ogden - S_neo_hookean).cwiseAbs().maxCoeff(), 1e-12 * M);
      EXPECT_LE(std::abs(ogden->energy(F) - neo_hookean->energy(F)), 1e-12 * M);
      worst = std::max(worst, (S_ogden - S_neo_hookean).cwiseAbs().maxCoeff() / M);
    }
  }
  std::cout << "ogden(alpha = 2) against neo_hookean: max |dS| / M = " << worst << "\n";
}

// ------------------------------------------------------------------------ equal and nearly equal stretches

// F = R1 diag(lambda) R2^T with stretches equal or within a relative gap of 1e-15 to 1e-2, against
// S = R2 diag(S_i) R2^T from the long-double principal formula, which needs no eigensolver. Rounding F
// to double moves S by ~eps M times a factor of order 10, so a correct evaluation is within ~1e-14 M;
// the bound 1e-12 M would fail an eigensolver that solves the characteristic cubic directly, whose
// errors near a double root are ~sqrt(eps) ~ 1e-8 (relative).
struct LawCase {
  std::string name;
  json block;
  double alpha;
};

void PrintTo(const LawCase& c, std::ostream* os) { *os << c.name; }

class PrincipalReference : public ::testing::TestWithParam<LawCase> {};

TEST_P(PrincipalReference, StressIsAccurateAtRepeatedStretches) {
  const LawCase& law = GetParam();
  const bool is_ogden = law.block.contains("alpha");
  const auto material = test::make<Material>(is_ogden ? "ogden" : "neo_hookean", law.block);
  const PrincipalOgden reference{law.block["mu"].get<double>(), law.alpha, law.block["D"].get<double>()};
  const double M = material->p_wave_modulus();
  using Vec3L = PrincipalOgden::Vec3L;
  using Mat3L = Eigen::Matrix<long double, 3, 3>;

  std::mt19937 random(5);
  double worst = 0.0;
  for (const double base : {0.7, 1.0, 1.3})
    for (const long double gap : {0.0L, 1e-15L, 1e-12L, 1e-9L, 1e-6L, 1e-3L, 1e-2L})
      for (int shape = 0; shape < 3; ++shape)
        for (int k = 0; k < 10; ++k) {
          const long double a = base;
          // a close pair with a distinct third stretch, a close triple, and a pair below a distinct one
          const Vec3L stretches = shape == 0   ? Vec3L(a, a * (1 + gap), 1.25L)
                                  : shape == 1 ? Vec3L(a, a * (1 + gap), a * (1 - gap))
                                               : Vec3L(0.8L, a, a * (1 - gap));
          const Mat3 R1 = test::random_rotation(random), R2 = test::random_rotation(random);
          const Mat3 F = (R1.cast<long double>() * stretches.asDiagonal() * R2.cast<long double>().transpose())
                             .cast<double>();
          // S_i = (1 / lambda_i) dW/dlambda_i along the columns of R2.
          const Vec3L P = reference.nominal_stress(stretches);
          const Vec3L principal(P[0] / stretches[0], P[1] / stretches[1], P[2] / stretches[2]);
          const Mat3L S_reference = R2.cast<long double>() * principal.asDiagonal() * R2.cast<long double>().transpose();
          Mat3 S;
          ASSERT_TRUE(material->stress(F, S));
          const double error = static_cast<double>((S.cast<long double>() - S_reference).cwiseAbs().maxCoeff());
          worst = std::max(worst, error / M);
          EXPECT_LE(error, 1e-12 * M) << "stretches " << stretches.transpose() << "\nS =\n" << S;
          // W needs the eigenvalues only; the same bound.
          EXPECT_LE(std::abs(material->energy(F) - static_cast<double>(reference.energy(stretches))), 1e-12 * M);
        }
  std::cout << law.name << ": max |S - S_reference| / M = " << worst << "\n";
}

INSTANTIATE_TEST_SUITE_P(
    Laws, PrincipalReference,
    ::testing::Values(LawCase{"neo_hookean", kNeoHookean, 2.0}, LawCase{"ogden_sylgard", kSylgard, -1.3},
                      LawCase{"ogden_alpha_2", ogden_with(722.0, 2.0, 5.57738e-5), 2.0},
                      LawCase{"ogden_alpha_8", ogden_with(500.0, 8.0, 1e-4), 8.0},
                      LawCase{"ogden_alpha_minus_4_7", ogden_with(350.0, -4.7, 2e-4), -4.7}),
    [](const ::testing::TestParamInfo<LawCase>& param_info) { return param_info.param.name; });

// ------------------------------------------------------------------------------------- uniaxial compression

// A cube compressed to lambda_z = 0.8 with free lateral faces: homogeneous, F = diag(t, t, 0.8) with the
// lateral stretch t making S_xx = 0. The test finds t from the plugin's stress by bisection, then checks
//  - t against the root of the closed-form dW/dlambda_x = 0 (long double);
//  - the nominal stress P_zz = 0.8 S_zz against the closed-form dW/dlambda_z;
//  - P_zz against a central difference of the plugin's own W along the uniaxial path,
//    d/dlambda_z W(diag(t(lambda_z), t(lambda_z), lambda_z)): with P_xx = 0 at t, the total and partial
//    derivatives agree. Step 1e-5: error ~ (h^2/6) W''' + eps W / h ~ 1e-10 M, bound 1e-7 M as in the
//    conformance suite.
struct UniaxialCase {
  std::string name;
  std::string material;
  json block;
  double alpha;
  double incompressible_nominal_stress;  // Pa, the same state with J = 1 (see below)
};

void PrintTo(const UniaxialCase& c, std::ostream* os) { *os << c.name; }

class UniaxialCompression : public ::testing::TestWithParam<UniaxialCase> {};

// Bisection for a root of a function with f(low) < 0 < f(high), to the last bit.
template <class Real, class Function>
Real bisect(Function f, Real low, Real high) {
  for (int k = 0; k < 200; ++k) {
    const Real middle = (low + high) / 2;
    if (middle == low || middle == high) break;
    (f(middle) < 0 ? low : high) = middle;
  }
  return (low + high) / 2;
}

TEST_P(UniaxialCompression, NominalStressMatchesTheEnergy) {
  const UniaxialCase& c = GetParam();
  const auto material = test::make<Material>(c.material, c.block);
  const PrincipalOgden reference{c.block["mu"].get<double>(), c.alpha, c.block["D"].get<double>()};
  const double M = material->p_wave_modulus();
  constexpr double lambda_z = 0.8;

  // Lateral stretch from the plugin: S_xx(diag(t, t, lambda_z)) = 0; compressed in z, the sides bulge (t > 1).
  const auto lateral_stress = [&](double lambda_z_, double t) {
    Mat3 S;
    EXPECT_TRUE(material->stress(Vec3(t, t, lambda_z_).asDiagonal(), S));
    return S(0, 0);
  };
  const auto lateral_stretch = [&](double lambda_z_) {
    return bisect<double>([&](double t) { return lateral_stress(lambda_z_, t); }, 1.0, 1.5);
  };
  ASSERT_LT(lateral_stress(lambda_z, 1.0), 0.0);
  ASSERT_GT(lateral_stress(lambda_z, 1.5), 0.0);
  const double t = lateral_stretch(lambda_z);

  // Closed form: dW/dlambda_x = 0 in long double.
  using Vec3L = PrincipalOgden::Vec3L;
  const long double t_reference = bisect<long double>(
      [&](long double s) { return reference.nominal_stress(Vec3L(s, s, lambda_z))[0]; }, 1.0L, 1.5L);
  // The root moves by (error of S_xx) / (dS_xx/dt) ~ 1e-14 M / M.
  EXPECT_NEAR(t, static_cast<double>(t_reference), 1e-12);

  Mat3 S;
  ASSERT_TRUE(material->stress(Vec3(t, t, lambda_z).asDiagonal(), S));
  const double P_zz = lambda_z * S(2, 2);
  const double P_reference = static_cast<double>(reference.nominal_stress(Vec3L(t_reference, t_reference, lambda_z))[2]);
  EXPECT_NEAR(P_zz, P_reference, 1e-12 * M);

  constexpr double h = 1e-5;
  const auto path_energy = [&](double l) {
    const double s = lateral_stretch(l);
    return material->energy(Vec3(s, s, l).asDiagonal());
  };
  const double P_path = (path_energy(lambda_z + h) - path_energy(lambda_z - h)) / (2 * h);
  EXPECT_NEAR(P_path, P_zz, 1e-7 * M);

  // Plausibility against the incompressible law (J = 1, t = lambda_z^(-1/2)): with nu = 0.49 the material
  // differs from it at order mu/K = 0.02, so within 10 % here.
  EXPECT_NEAR(P_zz / c.incompressible_nominal_stress, 1.0, 0.1);

  std::cout << std::setprecision(9) << c.name << ": lambda_z = 0.8, lateral stretch " << t << ", J = " << t * t * lambda_z
            << ", nominal stress P_zz = " << P_zz << " Pa (closed form " << P_reference << ", from W along the path "
            << P_path << ", incompressible " << c.incompressible_nominal_stress << ")\n";
  RecordProperty("nominal_stress_Pa", std::to_string(P_zz));
}

// Incompressible uniaxial nominal stress: Ogden (2 mu / alpha)(l^(alpha-1) - l^(-alpha/2-1)),
// neo-Hookean mu (l - l^-2).
double incompressible_ogden(double mu, double alpha, double l) {
  return 2 * mu / alpha * (std::pow(l, alpha - 1) - std::pow(l, -alpha / 2 - 1));
}

INSTANTIATE_TEST_SUITE_P(
    PaperMaterials, UniaxialCompression,
    ::testing::Values(UniaxialCase{"ogden_sylgard_527", "ogden", kSylgard, -1.3, incompressible_ogden(722, -1.3, 0.8)},
                      UniaxialCase{"neo_hookean_1000", "neo_hookean", kNeoHookean, 2.0, 1000.0 * (0.8 - 1 / 0.64)}),
    [](const ::testing::TestParamInfo<UniaxialCase>& param_info) { return param_info.param.name; });

// ------------------------------------------------------------------------------------------- parameters

TEST(HyperelasticParameters, ModuliAndDensityFollowTheParameters) {
  const auto neo_hookean = test::make<Material>("neo_hookean", kNeoHookean);
  EXPECT_EQ(neo_hookean->density(), 1000.0) << "the documented default";
  // K = 2/D, lambda + 2 mu = K + 4 mu / 3
  EXPECT_DOUBLE_EQ(neo_hookean->p_wave_modulus(), 2 / 4.02684e-5 + 4 * 1000.0 / 3);
  const auto ogden = test::make<Material>("ogden", {{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 970.0}});
  EXPECT_EQ(ogden->density(), 970.0);
  EXPECT_DOUBLE_EQ(ogden->p_wave_modulus(), 2 / 5.57738e-5 + 4 * 722.0 / 3);
  // nu = 0.49: K / mu = 2 (1 + nu) / (3 (1 - 2 nu)) = 49.67 for both of the paper's sets.
  EXPECT_NEAR(2 / 5.57738e-5 / 722.0, 2 * 1.49 / (3 * 0.02), 1e-3);
}

// A GPU backend runs a law only through the device code its plugin exports: built with CUDA, both shipped laws
// export theirs (the law's single source compiled for the device); without CUDA neither does, and the backend would
// refuse the scene by the material's region.
TEST(HyperelasticDeviceCode, ExportedExactlyWhenBuiltWithCuda) {
  for (const auto& [name, parameters] : {std::pair{"neo_hookean", kNeoHookean}, std::pair{"ogden", kSylgard}}) {
    const DeviceLaw law = test::make<Material>(name, parameters)->device_law();
    EXPECT_EQ(law.stress_pass != nullptr, MTLED_TEST_HAS_CUDA != 0) << name;
    EXPECT_EQ(law.law != nullptr, MTLED_TEST_HAS_CUDA != 0) << name;
  }
}

struct BadParameter {
  std::string material;
  std::string key;
  double value;
  std::string allowed;  // what the message must quote
};

void PrintTo(const BadParameter& b, std::ostream* os) { *os << b.material << " " << b.key << " = " << b.value; }

class RefusedParameter : public ::testing::TestWithParam<BadParameter> {};

TEST_P(RefusedParameter, ValidationNamesTheKeyAndTheRange) {
  const BadParameter& bad = GetParam();
  const ComponentDeclaration& declaration = test::catalog().load(Category::material, bad.material);
  json block = bad.material == "ogden" ? kSylgard : kNeoHookean;
  block[bad.key] = bad.value;
  std::vector<Problem> problems;
  validate_parameters(declaration, block, "/materials/1", problems);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].where, "/materials/1/" + bad.key);
  EXPECT_NE(problems[0].message.find("allowed " + bad.allowed), std::string::npos) << problems[0].message;
}

INSTANTIATE_TEST_SUITE_P(
    MuDAlphaDensity, RefusedParameter,
    ::testing::Values(BadParameter{"neo_hookean", "mu", 0.0, "> 0"}, BadParameter{"neo_hookean", "mu", -1000.0, "> 0"},
                      BadParameter{"neo_hookean", "D", 0.0, "> 0"}, BadParameter{"neo_hookean", "D", -4e-5, "> 0"},
                      BadParameter{"neo_hookean", "density", 0.0, "> 0"},
                      BadParameter{"neo_hookean", "density", -1000.0, "> 0"}, BadParameter{"ogden", "mu", 0.0, "> 0"},
                      BadParameter{"ogden", "mu", -722.0, "> 0"}, BadParameter{"ogden", "D", 0.0, "> 0"},
                      BadParameter{"ogden", "alpha", 0.0, "!= 0"}, BadParameter{"ogden", "density", 0.0, "> 0"}),
    [](const ::testing::TestParamInfo<BadParameter>& param_info) {
      return param_info.param.material + "_" + param_info.param.key + "_" + std::to_string(param_info.index);
    });

// --------------------------------------------------------------------------------------------------- cost

// ns per stress() call through the interface, as the model's hot loop calls it, over F with moderate
// random strain (stretches roughly 0.7 to 1.3). Reported, not asserted. The machine is shared, so this
// counts the thread's CPU time (not wall time) and keeps the best of three rounds.
double thread_cpu_ns() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return 1e9 * static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec);
}

TEST(MaterialCost, NanosecondsPerStressCall) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> strain(-0.2, 0.2);
  std::vector<Mat3> deformations(1000);
  for (auto& F : deformations) {
    do {
      F = Mat3::Identity();
      for (int i = 0; i < 9; ++i) F(i) += strain(random);
    } while (F.determinant() < 0.5);
  }
  constexpr int repeats = 300;
  const double calls = repeats * static_cast<double>(deformations.size());
  for (const auto& [name, block] :
       {std::pair{std::string("neo_hookean"), kNeoHookean}, std::pair{std::string("ogden"), kSylgard}}) {
    const auto material = test::make<Material>(name, block);
    double checksum = 0.0, stress_ns = 1e300, energy_ns = 1e300;
    int failures = 0;
    for (int round = 0; round < 3; ++round) {
      double start = thread_cpu_ns();
      for (int r = 0; r < repeats; ++r)
        for (const Mat3& F : deformations) {
          Mat3 S;
          failures += material->stress(F, S) ? 0 : 1;
          checksum += S(0, 1);
        }
      stress_ns = std::min(stress_ns, (thread_cpu_ns() - start) / calls);
      start = thread_cpu_ns();
      for (int r = 0; r < repeats; ++r)
        for (const Mat3& F : deformations) checksum += material->energy(F);
      energy_ns = std::min(energy_ns, (thread_cpu_ns() - start) / calls);
    }
    EXPECT_EQ(failures, 0);
    EXPECT_TRUE(std::isfinite(checksum));
    std::cout << name << ": stress " << stress_ns << " ns/call, energy " << energy_ns << " ns/call\n";
    RecordProperty(name + "_stress_ns_per_call", std::to_string(stress_ns));
  }
}

}  // namespace
}  // namespace mtled
