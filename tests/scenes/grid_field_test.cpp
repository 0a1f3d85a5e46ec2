// A run's displacement sampled on an image grid (analysis/include/mtled/analysis/grid_field.hpp), on an affine
// field, which MLS with a linear basis reproduces exactly: forward, each voxel centre inside the reference box holds
// u(X) = A X + b; resampling, each voxel centre x inside the moved box holds d with X = x + d solving X + u(X) = x.
// Which voxels are inside is known in closed form; outside the field is zero.
#include "mtled/analysis/grid_field.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>

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

}  // namespace
}  // namespace mtled
