#pragma once
// Deformation gradients the material tests share: seeded random rotations, F from principal stretches,
// and a set of admissible F that covers the hard cases for a constitutive law (equal and nearly equal
// stretches, strong compression and stretch, shear).
#include <Eigen/Geometry>

#include <random>
#include <string>
#include <vector>

#include "mtled/types.hpp"

namespace mtled::test {

// A uniformly distributed rotation: a normalised quaternion of four independent normal variates.
inline Mat3 random_rotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(random), normal(random), normal(random), normal(random));
  q.normalize();
  return q.toRotationMatrix();
}

// F = R1 diag(stretches) R2^T: principal stretches `stretches`, right eigenvectors the columns of R2.
inline Mat3 from_stretches(const Mat3& R1, const Vec3& stretches, const Mat3& R2) {
  return R1 * stretches.asDiagonal() * R2.transpose();
}

struct NamedDeformation {
  std::string name;
  Mat3 F;
};

// Admissible deformation gradients, seeded and repeatable, with principal stretches in [0.5, 2] and
// 0.4 <= J <= 2.2. Each stretch set is placed in random orientations, so no test sees only diagonal C.
inline std::vector<NamedDeformation> admissible_deformations(unsigned seed = 2024) {
  std::mt19937 random(seed);
  std::vector<NamedDeformation> out;
  const auto add = [&](const std::string& name, const Vec3& stretches) {
    out.push_back({name, from_stretches(random_rotation(random), stretches, random_rotation(random))});
  };
  // Small strain: every stretch within 1e-3 of 1 (the state of most of a body at the start of a run).
  std::uniform_real_distribution<double> small(-1e-3, 1e-3);
  for (int k = 0; k < 3; ++k) {
    Mat3 F = Mat3::Identity();
    for (int i = 0; i < 9; ++i) F(i) += small(random);
    out.push_back({"small strain " + std::to_string(k), F});
  }
  // Moderate random strain, general orientation and distinct stretches.
  std::uniform_real_distribution<double> stretch(0.6, 1.6);
  for (int k = 0; k < 6; ++k) {
    Vec3 s(stretch(random), stretch(random), stretch(random));
    while (s.prod() < 0.4 || s.prod() > 2.2) s = Vec3(stretch(random), stretch(random), stretch(random));
    add("random " + std::to_string(k), s);
  }
  // Equal stretches, exactly: uniaxial states and pure dilation.
  add("uniaxial compression (1.1, 1.1, 0.8)", Vec3(1.1, 1.1, 0.8));
  add("uniaxial stretch (0.75, 0.75, 2)", Vec3(0.75, 0.75, 2.0));
  add("pure dilation 1.05", Vec3::Constant(1.05));
  add("pure compression 0.9", Vec3::Constant(0.9));
  // Nearly equal stretches, where a characteristic-cubic eigensolver loses half its digits.
  add("near pair 1e-12", Vec3(1.2, 1.2 * (1.0 + 1e-12), 0.9));
  add("near pair 1e-8", Vec3(0.85, 0.85 * (1.0 + 1e-8), 1.3));
  add("near pair 1e-5", Vec3(1.4, 1.4 * (1.0 + 1e-5), 0.7));
  add("near triple 1e-6", Vec3(0.95, 0.95 * (1.0 + 1e-6), 0.95 * (1.0 - 1e-6)));
  add("near triple 1e-3", Vec3(1.02, 1.02 * (1.0 + 1e-3), 1.02 * (1.0 - 2e-3)));
  // Strong compression (J about 0.5) and strong stretch (2).
  add("compression J=0.5 (0.8, 0.8, 0.78125)", Vec3(0.8, 0.8, 0.78125));
  add("compression J=0.5 (0.5, 1, 1)", Vec3(0.5, 1.0, 1.0));
  add("compression J=0.5 (0.6, 0.9, 0.9259)", Vec3(0.6, 0.9, 0.5 / 0.54));
  add("isochoric stretch 2 (2, 0.7071, 0.7071)", Vec3(2.0, std::sqrt(0.5), std::sqrt(0.5)));
  add("stretch 2 (2, 1, 0.5)", Vec3(2.0, 1.0, 0.5));
  add("stretch 2 (2, 1.05, 1)", Vec3(2.0, 1.05, 1.0));
  // Simple shear (J = 1, C not diagonal in any axis-aligned frame).
  for (double gamma : {0.3, 1.0}) {
    Mat3 F = Mat3::Identity();
    F(0, 1) = gamma;
    out.push_back({"simple shear " + std::to_string(gamma), F});
  }
  return out;
}

}  // namespace mtled::test
