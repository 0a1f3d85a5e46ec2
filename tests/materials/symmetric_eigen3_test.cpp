// The 3x3 symmetric eigensolver behind the Ogden law (mtled/law/arithmetic-inl.h, here with T = double): backward
// stable whatever the spacing of the eigenvalues. For a symmetric A built as R diag(w) R^T in double, a
// backward-stable solver gives |A V - V diag(values)| and |V^T V - I| of a few eps (|A|), and eigenvalues
// within a few eps |A| of the exact ones (Weyl); the bounds below allow 20 eps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "material_test_support.hpp"
#include "mtled/law/one_point.hpp"

namespace mtled {
namespace {

// The solver's result as Eigen matrices: vectors.col(i) belongs to values[i].
struct SymmetricEigen3 {
  Vec3 values;
  Mat3 vectors;
};

SymmetricEigen3 symmetric_eigen3(const Mat3& A) {
  const scalar::SymmetricEigen3<double> e = scalar::symmetric_eigen3(scalar::to_matrix3(A));
  SymmetricEigen3 out;
  for (int i = 0; i < 3; ++i) {
    out.values[i] = e.values[i];
    out.vectors.col(i) = Vec3(e.vectors[i].x, e.vectors[i].y, e.vectors[i].z);
  }
  return out;
}

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

Vec3 sorted(Vec3 v) {
  std::sort(v.data(), v.data() + 3);
  return v;
}

void expect_decomposes(const Mat3& A, const Vec3& exact_values, const std::string& what) {
  SCOPED_TRACE(what);
  const SymmetricEigen3 e = symmetric_eigen3(A);
  const double size = std::max(A.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  EXPECT_LE((e.vectors.transpose() * e.vectors - Mat3::Identity()).cwiseAbs().maxCoeff(), 20 * kEpsilon);
  EXPECT_LE((A * e.vectors - e.vectors * e.values.asDiagonal()).cwiseAbs().maxCoeff(), 20 * kEpsilon * size);
  EXPECT_LE((sorted(e.values) - sorted(exact_values)).cwiseAbs().maxCoeff(), 20 * kEpsilon * size)
      << e.values.transpose() << " against " << exact_values.transpose();
}

TEST(SymmetricEigen3, SpecialMatrices) {
  expect_decomposes(Mat3::Zero(), Vec3::Zero(), "zero");
  expect_decomposes(Mat3::Identity(), Vec3::Ones(), "identity");
  expect_decomposes(-3.5 * Mat3::Identity(), Vec3::Constant(-3.5), "negative multiple of I");
  expect_decomposes(Vec3(2.0, 1.0, 1.0).asDiagonal(), Vec3(2.0, 1.0, 1.0), "diag(2, 1, 1)");
  expect_decomposes(Vec3(1.0, 2.0, 1.0).asDiagonal(), Vec3(1.0, 2.0, 1.0), "diag(1, 2, 1)");
  expect_decomposes(Vec3(2000.0, 1.0, 0.0).asDiagonal(), Vec3(2000.0, 1.0, 0.0), "diag(2000, 1, 0)");
  expect_decomposes(Vec3(3.0, -1.0, 0.5).asDiagonal(), Vec3(3.0, -1.0, 0.5), "indefinite diagonal");
  Mat3 rank_one = Vec3(1.0, 2.0, -2.0) * Vec3(1.0, 2.0, -2.0).transpose();
  expect_decomposes(rank_one, Vec3(9.0, 0.0, 0.0), "rank one");
}

// Exactly and nearly repeated eigenvalues, random orientations, scales from 1e-150 to 1e150.
TEST(SymmetricEigen3, RepeatedAndNearlyRepeatedEigenvalues) {
  std::mt19937 random(17);
  for (const double scale : {1e-150, 1.0, 1e150})
    for (const double gap : {0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 0.3})
      for (int k = 0; k < 30; ++k) {
        const double a = 0.5 + k * 0.05;
        for (const Vec3& w : {Vec3(a, a * (1 + gap), 2.0), Vec3(a, a * (1 + gap), a * (1 - gap)),
                              Vec3(-a, a * (1 + gap), a), Vec3(0.1, a, a * (1 + gap))}) {
          const Mat3 R = test::random_rotation(random);
          const Mat3 A = R * (scale * w).asDiagonal() * R.transpose();
          expect_decomposes(A, scale * w, "gap " + std::to_string(gap));
        }
      }
}

// A deviator so small that its scale is subnormal (F = I plus round-off noise): still an orthonormal
// basis and eigenvalues equal to the mean to round-off, never NaN.
TEST(SymmetricEigen3, SubnormalDeviator) {
  Mat3 A = Mat3::Identity();
  A(0, 1) = A(1, 0) = 3e-310;
  A(1, 2) = A(2, 1) = -1e-315;
  const SymmetricEigen3 e = symmetric_eigen3(A);
  EXPECT_TRUE(e.values.allFinite() && e.vectors.allFinite());
  EXPECT_LE((e.vectors.transpose() * e.vectors - Mat3::Identity()).cwiseAbs().maxCoeff(), 20 * kEpsilon);
  EXPECT_LE((e.values - Vec3::Ones()).cwiseAbs().maxCoeff(), kEpsilon);
}

// Only the upper triangle is read (the caller may pass F^T F with rounding differences below).
TEST(SymmetricEigen3, ReadsTheUpperTriangleOnly) {
  Mat3 A;
  A << 2.0, 0.3, -0.1, 99.0, 1.5, 0.2, -42.0, 7.0, 0.7;
  Mat3 symmetric = A.selfadjointView<Eigen::Upper>();
  const SymmetricEigen3 from_upper = symmetric_eigen3(A), from_symmetric = symmetric_eigen3(symmetric);
  EXPECT_EQ(from_upper.values, from_symmetric.values);
  EXPECT_EQ(from_upper.vectors, from_symmetric.vectors);
}

// Agrees with Eigen's iterative (QR) solver, itself backward stable, on random symmetric matrices.
TEST(SymmetricEigen3, AgreesWithTheIterativeSolver) {
  std::mt19937 random(23);
  std::normal_distribution<double> normal;
  for (int k = 0; k < 2000; ++k) {
    Mat3 G;
    for (int i = 0; i < 9; ++i) G(i) = normal(random);
    const Mat3 A = G + G.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> iterative(A);
    expect_decomposes(A, iterative.eigenvalues(), "random " + std::to_string(k));
  }
}

}  // namespace
}  // namespace mtled
