// mtled warp and mtled field against an exact solution: the shipped uniaxial cube (a 10 mm Ogden cube compressed to
// a stretch of 0.8 between frictionless ends; exact solution homogeneous, its lateral stretch from the strain energy
// written independently of the plugins) and a label map of that cube on 0.1 mm voxels. Moved by the run, the label
// map's box must have the exact deformed size within one voxel along each axis and the exact volume within 1% (the
// voxel count of a box whose sides lie anywhere between voxel centres is off by at most h / L per side, 0.9% here);
// the resampling field must equal the exact one within 1e-6 m. NRRD and NIfTI both ways. Bad input: exit 2 naming the
// file and the field, nothing written.
#include <gtest/gtest.h>

#include "hyperelastic_exact.hpp"
#include "mtled/io/image.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

constexpr double kVoxel = 0.1e-3, kSide = 0.01, kStretch = 0.8;
constexpr std::int64_t kLateral = 135, kHeight = 115;  // voxels: the grid from -0.95 mm holds both boxes

// The label map: 1 inside the reference cube [0, 10 mm]^3 (its faces on voxel faces), 0 elsewhere; LPS.
Image cube_label_map() {
  Image image;
  image.grid.size = {kLateral, kLateral, kHeight};
  image.grid.axes = kVoxel * Mat3::Identity();
  image.grid.origin = Vec3::Constant(-0.95e-3);
  image.space = "LPS";
  image.type = {VoxelKind::unsigned_integer, 1};
  image.values.resize(static_cast<std::size_t>(image.grid.count()));
  for (std::int64_t k = 0; k < kHeight; ++k)
    for (std::int64_t j = 0; j < kLateral; ++j)
      for (std::int64_t i = 0; i < kLateral; ++i) {
        const Vec3 x = image.grid.centre(i, j, k);
        image.values[static_cast<std::size_t>(image.grid.index(i, j, k))] =
            (x.array() > 0.0).all() && (x.array() < kSide).all() ? 1.0 : 0.0;
      }
  return image;
}

struct Fixture {
  fs::path folder = test::scratch_dir("image-warp");
  fs::path run = folder / "run";
  fs::path labels = folder / "cube.nrrd";
  double lateral = test::exact_uniaxial_lateral_stretch(test::ogden(722.0, -1.3, 5.57738e-5), kStretch);

  Fixture() {
    if (!fs::exists(run / "result.vtu")) {
      const auto made =
          test::run_mtled({"run", (fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/uniaxial_cube_ogden.json").string(),
                           "-o", run.string(), "--no-progress"});
      EXPECT_EQ(made.exit_code, 0) << made.output;
    }
    if (!fs::exists(labels)) write_image(labels, cube_label_map());
  }
};

// Labelled voxels, and the extent of the labelled voxels along the axes through the box's middle (m).
struct LabelledBox {
  std::int64_t voxels = 0;
  Vec3 size = Vec3::Zero();
};

LabelledBox measure(const Image& image) {
  LabelledBox box;
  const auto& n = image.grid.size;
  for (const double v : image.values) box.voxels += v == 1.0;
  const std::int64_t middle[3] = {n[0] / 3, n[1] / 3, n[2] / 3};  // inside the deformed box, which starts at 0
  for (int a = 0; a < 3; ++a) {
    std::int64_t count = 0;
    for (std::int64_t s = 0; s < n[static_cast<std::size_t>(a)]; ++s) {
      std::int64_t ijk[3] = {middle[0], middle[1], middle[2]};
      ijk[a] = s;
      count += image.values[static_cast<std::size_t>(image.grid.index(ijk[0], ijk[1], ijk[2]))] == 1.0;
    }
    box.size[a] = static_cast<double>(count) * kVoxel;
  }
  return box;
}

TEST(ImageWarp, TheCompressedCubesLabelMapTakesItsExactDeformedSize) {
  const Fixture f;
  const Vec3 exact(kSide * f.lateral, kSide * f.lateral, kSide * kStretch);
  const double exact_volume = exact.prod();
  for (const std::string name : {"warped.nrrd", "warped.nii.gz"}) {
    SCOPED_TRACE(name);
    const fs::path out = f.folder / name;
    const auto warped =
        test::run_mtled({"warp", f.labels.string(), f.run.string(), "-o", out.string(), "--frame", "LPS"});
    ASSERT_EQ(warped.exit_code, 0) << warped.output;
    EXPECT_NE(warped.output.find("nearest interpolation"), std::string::npos) << warped.output;
    const Image image = read_image(out);
    EXPECT_EQ(image.space, name == "warped.nrrd" ? "LPS" : "RAS");
    EXPECT_EQ(image.type.kind, VoxelKind::unsigned_integer);
    const LabelledBox box = measure(image);
    for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(box.size[a] - exact[a]), kVoxel) << "axis " << a;
    const double volume = static_cast<double>(box.voxels) * kVoxel * kVoxel * kVoxel;
    EXPECT_LT(std::abs(volume / exact_volume - 1.0), 0.01) << volume << " m^3 against " << exact_volume;
    std::printf("%s: %.3f x %.3f x %.3f mm (exact %.3f x %.3f x %.3f), volume %+.3f%%\n", name.c_str(),
                1e3 * box.size[0], 1e3 * box.size[1], 1e3 * box.size[2], 1e3 * exact[0], 1e3 * exact[1], 1e3 * exact[2],
                100.0 * (volume / exact_volume - 1.0));
  }
}

// The resampling field inside the moved cube is X - x with X = F^-1 x, F = diag(lateral, lateral, 0.8), in the
// file's frame (NIfTI: RAS, so x and y change sign), millimetres.
TEST(ImageWarp, TheResamplingFieldIsTheExactOneInEitherFormat) {
  const Fixture f;
  const Vec3 stretch(f.lateral, f.lateral, kStretch);
  for (const std::string name : {"field.nrrd", "field.nii"}) {
    SCOPED_TRACE(name);
    const fs::path out = f.folder / name;
    const auto made =
        test::run_mtled({"field", f.run.string(), "--like", f.labels.string(), "-o", out.string(), "--frame", "LPS"});
    ASSERT_EQ(made.exit_code, 0) << made.output;
    const Image field = read_image(out);
    ASSERT_EQ(field.components, 3);
    const Mat3 to_lps = field.space == "RAS" ? lps_ras_flip() : Mat3::Identity();
    EXPECT_EQ(field.space, name == "field.nrrd" ? "LPS" : "RAS");
    double worst = 0.0;
    std::int64_t checked = 0;
    for (std::int64_t k = 0; k < field.grid.size[2]; ++k)
      for (std::int64_t j = 0; j < field.grid.size[1]; ++j)
        for (std::int64_t i = 0; i < field.grid.size[0]; ++i) {
          const Vec3 x = to_lps * field.grid.centre(i, j, k);  // the grid itself is in the file's frame
          const Vec3 X = x.cwiseQuotient(stretch);
          if (!((X.array() > 1e-7).all() && (X.array() < kSide - 1e-7).all())) continue;
          const std::size_t v = 3 * static_cast<std::size_t>(field.grid.index(i, j, k));
          const Vec3 d = to_lps * Vec3(field.values[v], field.values[v + 1], field.values[v + 2]);
          worst = std::max(worst, (d - (X - x)).norm());
          ++checked;
        }
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(checked, 800000);
    std::printf("%s: %lld voxels inside, largest difference from the exact field %.3g m\n", name.c_str(),
                static_cast<long long>(checked), worst);
  }
}

// An intensity image that is linear in space, I(X) = X_1 + 2 X_2 + 3 X_3 (LPS mm), float, saved as NIfTI (RAS):
// trilinear interpolation reproduces it, so inside the moved cube the warped image must hold I(F^-1 x) at every
// voxel centre, to the thousandth of a voxel the resampling field is solved to, plus float round-off.
TEST(ImageWarp, ALinearIntensityImageIsReadWhereTheTissueCameFrom) {
  const Fixture f;
  Image ramp = cube_label_map();
  ramp.type = {VoxelKind::floating, 4};
  for (std::int64_t k = 0; k < kHeight; ++k)
    for (std::int64_t j = 0; j < kLateral; ++j)
      for (std::int64_t i = 0; i < kLateral; ++i) {
        const Vec3 x = 1e3 * ramp.grid.centre(i, j, k);
        ramp.values[static_cast<std::size_t>(ramp.grid.index(i, j, k))] = x[0] + 2.0 * x[1] + 3.0 * x[2];
      }
  const fs::path image = f.folder / "ramp.nii.gz", out = f.folder / "ramp-warped.nrrd";
  write_image(image, ramp);
  const auto warped = test::run_mtled({"warp", image.string(), f.run.string(), "-o", out.string(), "--frame", "LPS"});
  ASSERT_EQ(warped.exit_code, 0) << warped.output;
  EXPECT_NE(warped.output.find("linear interpolation"), std::string::npos) << warped.output;
  const Image result = read_image(out);
  ASSERT_EQ(result.space, "RAS");  // the NIfTI image's frame, kept
  const Vec3 stretch(f.lateral, f.lateral, kStretch);
  double worst = 0.0;
  std::int64_t checked = 0;
  for (std::int64_t k = 0; k < kHeight; ++k)
    for (std::int64_t j = 0; j < kLateral; ++j)
      for (std::int64_t i = 0; i < kLateral; ++i) {
        const Vec3 x = lps_ras_flip() * result.grid.centre(i, j, k);  // LPS, the run's frame
        const Vec3 X = x.cwiseQuotient(stretch);
        if (!((X.array() > 0.2e-3).all() && (X.array() < kSide - 0.2e-3).all())) continue;
        const double expected = 1e3 * (X[0] + 2.0 * X[1] + 3.0 * X[2]);  // the ramp was written in LPS mm
        worst =
            std::max(worst, std::abs(result.values[static_cast<std::size_t>(result.grid.index(i, j, k))] - expected));
        ++checked;
      }
  // |grad I| = sqrt(14) per mm times the 1e-4 mm the reference point may be off, and float round-off of values
  // up to 60.
  EXPECT_LT(worst, std::sqrt(14.0) * 1e-4 + 1e-5);
  EXPECT_GT(checked, 800000);
  std::printf("linear intensities: %lld voxels, largest difference %.3g (mm of the ramp)\n",
              static_cast<long long>(checked), worst);
}

TEST(ImageWarp, BadImagesAreRefusedNamingTheFileAndNothingIsWritten) {
  const Fixture f;
  // A displacement field given to warp.
  const fs::path field = f.folder / "a-field.nrrd";
  ASSERT_EQ(test::run_mtled({"field", f.run.string(), "--like", f.labels.string(), "-o", field.string(), "--frame",
                             "LPS", "--decay", "0"})
                .exit_code,
            0);
  Image frameless = cube_label_map();
  frameless.space.clear();
  write_image(f.folder / "frameless.nrrd", frameless);
  Image elsewhere = cube_label_map();
  elsewhere.grid.origin += Vec3(0.5, 0.0, 0.0);  // half a metre away
  write_image(f.folder / "elsewhere.nrrd", elsewhere);
  const struct {
    std::string image, needle;
  } cases[] = {{"a-field.nrrd", "vector per voxel"},
               {"frameless.nrrd", "names no patient frame"},
               {"elsewhere.nrrd", "do not overlap"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.image);
    const fs::path out = f.folder / ("bad-" + c.image);
    const auto refused =
        test::run_mtled({"warp", (f.folder / c.image).string(), f.run.string(), "-o", out.string(), "--frame", "LPS"});
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_NE(refused.output.find(c.needle), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find(c.image), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(out));
  }
  const auto wrong_name =
      test::run_mtled({"warp", f.labels.string(), f.run.string(), "-o", (f.folder / "out.png").string()});
  EXPECT_EQ(wrong_name.exit_code, 2) << wrong_name.output;
  EXPECT_NE(wrong_name.output.find(".nii.gz"), std::string::npos) << wrong_name.output;
}

}  // namespace
}  // namespace mtled
