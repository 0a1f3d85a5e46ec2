// A run's displacement sampled on an image grid (analysis/include/mtled/analysis/grid_field.hpp), on an affine
// field, which MLS with a linear basis reproduces exactly: forward, each voxel centre inside the reference box holds
// u(X) = A X + b; resampling, each voxel centre x inside the moved box holds d with X = x + d solving X + u(X) = x.
// Which voxels are inside is known in closed form; outside the field is zero.
#include "mtled/analysis/grid_field.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <limits>

#include "test_support.hpp"

namespace mtled {
namespace {

const Vec3 kBox(0.010, 0.008, 0.012);

Mat3 gradient() {
  Mat3 A;
  A << -0.08, 0.05, 0.0,  //
      0.02, 0.10, -0.04,  //
      0.0, 0.03, -0.15;
  return A;
}
const Vec3 kShift(0.0005, -0.0003, 0.0002);

bool in_box(const Vec3& X) {
  constexpr double kMargin = 1e-9;  // centres within round-off of a face are left out of the count
  return (X.array() > kMargin).all() && (X.array() < kBox.array() - kMargin).all();
}
bool near_face(const Vec3& X) { return (X.array().abs() < 1e-7).any() || ((X - kBox).array().abs() < 1e-7).any(); }

struct Case {
  TetMesh mesh;
  std::vector<Vec3> displacement;
  VoxelGrid grid;
};

Case affine_case() {
  Case c{test::box_mesh(kBox, 5, 4, 6, 0.2, 7), {}, {}};
  for (const Vec3& X : c.mesh.points) c.displacement.push_back(gradient() * X + kShift);
  // A grid rotated about z by 20 degrees, voxels of 0.7 x 0.6 x 0.8 mm, covering the box and its moved image.
  const double angle = 20.0 * 3.14159265358979 / 180.0;
  Mat3 rotation;
  rotation << std::cos(angle), -std::sin(angle), 0, std::sin(angle), std::cos(angle), 0, 0, 0, 1;
  c.grid.axes = rotation * Vec3(0.0007, 0.0006, 0.0008).asDiagonal();
  c.grid.origin = Vec3(-0.004, -0.006, -0.003);
  c.grid.size = {30, 30, 22};
  return c;
}

// Checks every voxel: `reference(x)` is the reference point the voxel centre x stands for, `error(x, value)` how far
// the field's value there is from the exact one; inside the box it must be under `tolerance`, outside zero.
template <class Reference, class Error>
void check_every_voxel(const Case& c, const GridField& field, Reference&& reference, Error&& error, double tolerance) {
  std::int64_t expected_inside = 0, on_a_face = 0;
  for (std::int64_t k = 0; k < c.grid.size[2]; ++k)
    for (std::int64_t j = 0; j < c.grid.size[1]; ++j)
      for (std::int64_t i = 0; i < c.grid.size[0]; ++i) {
        const Vec3 x = c.grid.centre(i, j, k), X = reference(x);
        const Vec3& value = field.values[static_cast<std::size_t>(c.grid.index(i, j, k))];
        if (near_face(X)) {
          ++on_a_face;
        } else if (in_box(X)) {
          ++expected_inside;
          ASSERT_LT(error(x, value), tolerance) << i << " " << j << " " << k;
        } else {
          ASSERT_EQ(value, Vec3::Zero()) << "outside: " << i << " " << j << " " << k;
        }
      }
  EXPECT_GT(expected_inside, 1000);
  EXPECT_LE(std::abs(field.inside - expected_inside), on_a_face);
}

TEST(GridField, ForwardHoldsTheDisplacementAtEveryVoxelInsideTheReferenceBody) {
  const Case c = affine_case();
  const GridField field = displacement_on_grid({c.mesh.points, c.mesh.tets, c.displacement}, c.grid,
                                               FieldDirection::forward, test::catalog());
  check_every_voxel(
      c, field, [](const Vec3& x) { return x; },
      [](const Vec3& X, const Vec3& u) { return (u - (gradient() * X + kShift)).norm(); }, 1e-12);
}

TEST(GridField, ResamplingTakesEachVoxelOfTheMovedBodyBackToItsReferencePoint) {
  const Case c = affine_case();
  const GridField field = displacement_on_grid({c.mesh.points, c.mesh.tets, c.displacement}, c.grid,
                                               FieldDirection::resampling, test::catalog());
  const Mat3 back = (Mat3::Identity() + gradient()).inverse();  // x = (I + A) X + b
  const auto reference = [&](const Vec3& x) { return Vec3(back * (x - kShift)); };
  check_every_voxel(
      c, field, reference, [&](const Vec3& x, const Vec3& d) { return (x + d - reference(x)).norm(); }, 1e-9);
  EXPECT_EQ(field.overlapping, 0);
  EXPECT_EQ(field.not_converged, 0);
  EXPECT_LT(field.largest_residual, 1e-9);
}

// The extension outside the body against a search of every voxel inside: on a grid of unequal spacings, with a body
// of two pieces, each voxel outside holds s(t) times the value of a voxel inside at the least distance, t that
// distance over the decay, s(t) = 1 - 3t^2 + 2t^3; zero from the decay distance on.
TEST(GridField, TheExtensionOutsideIsTheNearestInsideValueFaded) {
  VoxelGrid grid;
  grid.size = {17, 13, 11};
  grid.axes = Vec3(0.5e-3, 0.7e-3, 0.9e-3).asDiagonal();
  GridField field;
  field.values.assign(static_cast<std::size_t>(grid.count()), Vec3::Zero());
  field.inside_body.assign(field.values.size(), 0);
  std::vector<std::int64_t> inside;
  for (std::int64_t k = 0; k < grid.size[2]; ++k)
    for (std::int64_t j = 0; j < grid.size[1]; ++j)
      for (std::int64_t i = 0; i < grid.size[0]; ++i) {
        const bool l_shape = (i >= 3 && i <= 8 && j >= 2 && j <= 4 && k >= 2 && k <= 6) ||
                             (i >= 3 && i <= 4 && j >= 2 && j <= 9 && k >= 2 && k <= 6);
        const bool blob = (i - 13) * (i - 13) + (j - 9) * (j - 9) + (k - 8) * (k - 8) <= 4;
        if (!l_shape && !blob) continue;
        const auto v = grid.index(i, j, k);
        field.inside_body[static_cast<std::size_t>(v)] = 1;
        field.values[static_cast<std::size_t>(v)] = 1e-4 * Vec3(double(i), double(2 * j), double(3 * k + 1));
        inside.push_back(v);
      }
  const GridField before = field;
  const double decay = 4e-3;
  extend_outside(grid, decay, field);
  int faded = 0, beyond = 0;
  for (std::int64_t k = 0; k < grid.size[2]; ++k)
    for (std::int64_t j = 0; j < grid.size[1]; ++j)
      for (std::int64_t i = 0; i < grid.size[0]; ++i) {
        const auto v = static_cast<std::size_t>(grid.index(i, j, k));
        if (before.inside_body[v]) {
          ASSERT_EQ(field.values[v], before.values[v]);
          continue;
        }
        double least = std::numeric_limits<double>::infinity();
        for (const std::int64_t w : inside)
          least = std::min(least, (grid.centre(i, j, k) - grid.centre(w % 17, (w / 17) % 13, w / (17 * 13))).norm());
        const double t = least / decay;
        if (t >= 1.0) {
          ASSERT_EQ(field.values[v], Vec3::Zero()) << i << " " << j << " " << k;
          ++beyond;
          continue;
        }
        const double weight = 1.0 - t * t * (3.0 - 2.0 * t);
        bool matched = false;  // some voxel inside at the least distance gives the value
        for (const std::int64_t w : inside) {
          const double d = (grid.centre(i, j, k) - grid.centre(w % 17, (w / 17) % 13, w / (17 * 13))).norm();
          if (d <= least * (1.0 + 1e-12) &&
              (field.values[v] - weight * before.values[static_cast<std::size_t>(w)]).norm() < 1e-15)
            matched = true;
        }
        ASSERT_TRUE(matched) << "voxel " << i << " " << j << " " << k << " at " << least << " m";
        ++faded;
      }
  EXPECT_GT(faded, 500);
  EXPECT_GT(beyond, 10);
}

}  // namespace
}  // namespace mtled
