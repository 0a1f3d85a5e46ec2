// ITK reads mtled's displacement fields as mtled meant them. The compressed cube's fields (resampling and forward),
// written from a grid given in LPS and from the same grid given in RAS, as NRRD and as NIfTI, are read by
// itk_field_points (ITK's NRRD reader, the NIfTI reference library) as an itk::DisplacementFieldTransform, which maps
// every voxel centre inside the body. At each one the result must agree with mtled's own interpolation of the run
// (MLS, as the field was made) within 1e-6 m: forward, T(X) = X + u(X); resampling, T(x) = X with X + u(X) = x.
#include <gtest/gtest.h>

#include <fstream>

#include "mtled/analysis/mls_transfer.hpp"
#include "mtled/analysis/result_file.hpp"
#include "mtled/io/image.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

constexpr double kVoxel = 0.5e-3;
constexpr std::int64_t kSize = 26;  // from -1.25 mm: holds the 10 mm cube and the compressed one (11.2 mm wide)

// A blank grid over the cube, in `frame`; the same voxel centres either way.
Image grid_image(const std::string& frame) {
  Image image;
  image.grid.size = {kSize, kSize, kSize};
  image.grid.axes = kVoxel * Mat3::Identity();
  image.grid.origin = Vec3::Constant(-1.25e-3);
  if (frame == "RAS") {
    image.grid.axes = lps_ras_flip() * image.grid.axes;
    image.grid.origin = lps_ras_flip() * image.grid.origin;
  }
  image.space = frame;
  image.values.assign(static_cast<std::size_t>(image.grid.count()), 0.0);
  return image;
}

std::vector<Vec3> itk_transform(const fs::path& field, const std::vector<Vec3>& points, const fs::path& folder) {
  const fs::path in = folder / "points.txt", out = folder / "mapped.txt";
  {
    std::ofstream file(in);
    file.precision(17);
    for (const Vec3& p : points) file << 1e3 * p[0] << " " << 1e3 * p[1] << " " << 1e3 * p[2] << "\n";
  }
  const std::string command =
      std::string(MTLED_ITK_FIELD_POINTS) + " " + field.string() + " " + in.string() + " " + out.string();
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  std::vector<Vec3> mapped;
  std::ifstream file(out);
  for (Vec3 p; file >> p[0] >> p[1] >> p[2];) mapped.push_back(1e-3 * p);
  return mapped;
}

TEST(ItkReader, ReadsEveryFieldAsTheDisplacementMtledInterpolates) {
  const fs::path folder = test::scratch_dir("itk-field");
  const auto run =
      test::run_mtled({"run", (fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/uniaxial_cube_ogden.json").string(),
                       "-o", (folder / "run").string(), "--no-progress"});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const ResultField result = read_result_vtu(folder / "run" / "result.vtu");
  const MlsTransfer transfer(result.points, test::catalog());
  const auto u = [&](const Vec3& X) { return transfer.at(X, result.displacement); };
  const auto inside = [](const Vec3& X, double side) {
    return (X.array() > 1e-7).all() && (X.array() < side - 1e-7).all();
  };
  const Image lps = grid_image("LPS");
  std::vector<Vec3> centres;  // every voxel centre, LPS
  for (std::int64_t k = 0; k < kSize; ++k)
    for (std::int64_t j = 0; j < kSize; ++j)
      for (std::int64_t i = 0; i < kSize; ++i) centres.push_back(lps.grid.centre(i, j, k));

  for (const std::string frame : {"LPS", "RAS"}) {
    const fs::path like = folder / ("grid-" + frame + ".nrrd");
    write_image(like, grid_image(frame));
    for (const std::string direction : {"resampling", "forward"})
      for (const std::string format : {".nrrd", ".nii.gz"}) {
        SCOPED_TRACE(frame + " " + direction + " " + format);
        const fs::path field = folder / (frame + "-" + direction + format);
        const auto made = test::run_mtled({"field", (folder / "run").string(), "--like", like.string(), "-o",
                                           field.string(), "--frame", "LPS", "--direction", direction, "--decay", "0"});
        ASSERT_EQ(made.exit_code, 0) << made.output;
        // The points inside the body: the reference cube (forward) or the moved one (resampling, by the run's own
        // map: the moved cube spans [0, 10 lateral] x [0, 10 lateral] x [0, 8] mm).
        std::vector<Vec3> points;
        for (const Vec3& x : centres)
          if (direction == "forward" ? inside(x, 0.01)
                                     : inside(Vec3(x[0] / 1.115, x[1] / 1.115, x[2] / 0.8), 0.01) &&
                                           inside(Vec3(x[0] / 1.12, x[1] / 1.12, x[2] / 0.8), 0.01))
            points.push_back(x);
        const std::vector<Vec3> mapped = itk_transform(field, points, folder);
        ASSERT_EQ(mapped.size(), points.size());
        double worst = 0.0;
        for (std::size_t p = 0; p < points.size(); ++p) {
          const double difference = direction == "forward" ? (mapped[p] - (points[p] + u(points[p]))).norm()
                                                           : (mapped[p] + u(mapped[p]) - points[p]).norm();
          worst = std::max(worst, difference);
        }
        EXPECT_LT(worst, 1e-6);
        EXPECT_GT(points.size(), 5000u);
        std::printf("%s %s %s: %zu voxel centres, largest difference %.3g m\n", frame.c_str(), direction.c_str(),
                    format.c_str(), points.size(), worst);
      }
  }
}

}  // namespace
}  // namespace mtled
