#pragma once
// Eigen decomposition of a symmetric 3x3 matrix, closed form and accurate when eigenvalues are equal or
// nearly equal, for the principal-stretch form of the Ogden law (ogden.cpp).
//
// Why not Eigen's SelfAdjointEigenSolver: its iterative solver is accurate but costs about twice as much,
// and its computeDirect() takes every eigenvalue from the trigonometric solution of the characteristic
// cubic, which is ill-conditioned at a double root: with two stretches within 1e-6 of each other (uniaxial
// load, F near I) the Ogden stress came out wrong by ~1e-7 of the P-wave modulus, against ~1e-14 here.
//
// The method (the non-iterative scheme of Scherzinger & Dohrmann, CMAME 197 (2008) 4007, also described
// in D. Eberly, "A Robust Eigensolver for 3x3 Symmetric Matrices", Geometric Tools, 2014):
//  1. shift by the mean eigenvalue and scale, B = (A - m I) / s with max |B_ij| = 1;
//  2. take from the cubic only the eigenvalue farthest from the other two: there the cubic is well
//     conditioned, and that eigenvalue is separated from the others by at least ~0.87 after scaling;
//  3. its eigenvector from the best-conditioned cross product of two rows of B - eta I (the columns of
//     the adjugate of a rank-2 symmetric matrix are multiples of its kernel);
//  4. the other two from the 2x2 matrix B restricted to the orthogonal complement, diagonalised by one
//     Jacobi rotation (exact and backward stable for 2x2), so a close pair is resolved to round-off.
// The result is backward stable: |A - V diag(w) V^T| ~ eps |A| and V is orthonormal to ~eps, whatever the
// spacing of the eigenvalues. No allocation, no iteration, no exception.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "mtled/types.hpp"

namespace mtled {

struct SymmetricEigen3 {
  Vec3 values;   // in no particular order
  Mat3 vectors;  // orthonormal columns, vectors.col(i) belongs to values[i]
};

// Reads the upper triangle of `A` only.
inline SymmetricEigen3 symmetric_eigen3(const Mat3& A) noexcept {
  SymmetricEigen3 result;
  const double mean = (A(0, 0) + A(1, 1) + A(2, 2)) / 3.0;
  Mat3 B = A.selfadjointView<Eigen::Upper>();
  B.diagonal().array() -= mean;
  const double scale = B.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) {  // a multiple of the identity (F = I, pure dilation): every basis is an eigenbasis
    result.values.setConstant(mean);
    result.vectors.setIdentity();
    return result;
  }
  B /= scale;  // not a multiplication by 1/scale: that overflows for a subnormal scale

  // Invariants of the (nearly) traceless B: eigenvalues rho cos(theta + 2 pi k / 3) with
  // rho = 2 sqrt(j2 / 3) and cos(3 theta) = 4 det(B) / rho^3. After scaling j2 >= 3/4, so rho >= 1.
  const double j2 = 0.5 * (B(0, 0) * B(0, 0) + B(1, 1) * B(1, 1) + B(2, 2) * B(2, 2)) + B(0, 1) * B(0, 1) +
                    B(0, 2) * B(0, 2) + B(1, 2) * B(1, 2);
  const double rho = 2.0 * std::sqrt(j2 / 3.0);
  const double cos_3theta = std::clamp(4.0 * B.determinant() / (rho * rho * rho), -1.0, 1.0);
  const double theta = std::acos(cos_3theta) / 3.0;  // in [0, pi/3]
  // theta < pi/6: the largest eigenvalue is the isolated one (a close pair sits at theta -> 0);
  // otherwise the smallest is (a close pair at theta -> pi/3).
  const double eta = theta < std::numbers::pi / 6.0 ? rho * std::cos(theta)
                                                    : rho * std::cos(theta + 2.0 * std::numbers::pi / 3.0);

  Mat3 shifted = B;
  shifted.diagonal().array() -= eta;
  const Vec3 c01 = shifted.row(0).cross(shifted.row(1));
  const Vec3 c02 = shifted.row(0).cross(shifted.row(2));
  const Vec3 c12 = shifted.row(1).cross(shifted.row(2));
  const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
  Vec3 v1;
  if (n01 >= n02 && n01 >= n12) {
    v1 = c01 * (1.0 / std::sqrt(n01));
  } else if (n02 >= n12) {
    v1 = c02 * (1.0 / std::sqrt(n02));
  } else {
    v1 = c12 * (1.0 / std::sqrt(n12));
  }

  // An orthonormal basis (u, w) of the plane normal to v1, built from v1's two largest components.
  Vec3 u = std::abs(v1.x()) > std::abs(v1.y()) ? Vec3(-v1.z(), 0.0, v1.x()) : Vec3(0.0, v1.z(), -v1.y());
  u *= 1.0 / std::sqrt(u.squaredNorm());
  const Vec3 w = v1.cross(u);
  const Vec3 Bu = B * u, Bw = B * w;
  const double b_uu = u.dot(Bu), b_uw = u.dot(Bw), b_ww = w.dot(Bw);
  double eta2 = b_uu, eta3 = b_ww;
  Vec3 v2 = u, v3 = w;
  if (b_uw != 0.0) {
    // Jacobi rotation that zeroes b_uw, with the smaller of the two angles (Golub & Van Loan, sec. 8.5).
    const double tau = (b_ww - b_uu) / (2.0 * b_uw);
    const double t = std::copysign(1.0, tau) / (std::abs(tau) + std::sqrt(1.0 + tau * tau));
    const double c = 1.0 / std::sqrt(1.0 + t * t), s = t * c;
    eta2 = b_uu - t * b_uw;
    eta3 = b_ww + t * b_uw;
    v2 = c * u - s * w;
    v3 = s * u + c * w;
  }
  // The Rayleigh quotient of v1 is more accurate than eta from the cubic (second order in v1's error).
  const double eta1 = v1.dot(B * v1);

  result.values = Vec3(eta1, eta2, eta3) * scale + Vec3::Constant(mean);
  result.vectors.col(0) = v1;
  result.vectors.col(1) = v2;
  result.vectors.col(2) = v3;
  return result;
}

}  // namespace mtled
