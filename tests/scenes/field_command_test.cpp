// mtled field: a run's displacement on an image's grid as a displacement-field NRRD. The uniaxial cube's field is
// homogeneous (the run reproduces it to about 1e-9 m), so at every voxel the file must hold the affine map fitted to
// the run's nodes: forward u(X) inside the reference cube, resampling X - x with X + u(X) = x inside the moved one,
// within 1e-6 m (the file stores millimetres as float); zero outside. A run whose mesh records no frame needs one.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstring>

#include "mtled/analysis/result_file.hpp"
#include "mtled/io/label_image.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

// The voxel vectors of a field mtled wrote (metres), after checking its header says what Slicer needs.
std::vector<Vec3> read_field(const fs::path& file) {
  const std::string bytes = test::read_text(file);
  const std::size_t end = bytes.find("\n\n");
  const std::string header = bytes.substr(0, end);
  for (const char* line : {"dimension: 4", "kinds: vector domain domain domain", "sizes: 3 24 24 24",
                           "space: left-posterior-superior", "encoding: gzip", "type: float"})
    EXPECT_NE(header.find(line), std::string::npos) << line << " in\n" << header;
  const std::string raw = gunzip(bytes.substr(end + 2), file.string());
  std::vector<float> values(raw.size() / sizeof(float));
  std::memcpy(values.data(), raw.data(), raw.size());
  std::vector<Vec3> out;
  for (std::size_t v = 0; v + 2 < values.size(); v += 3)
    out.push_back(1e-3 * Vec3(values[v], values[v + 1], values[v + 2]));
  return out;
}

// The uniaxial cube's run and a 24^3 grid of 0.6 mm voxels from (-1, -1, -1) mm (a label map of the cube): it holds
// the 10 mm cube and the cube compressed to 8 mm. Made for each test in its own folder (ctest runs them at once).
class FieldCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = test::scratch_dir(std::string("field-command-") +
                                ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const auto run =
        test::run_mtled({"run", (fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/uniaxial_cube_ogden.json").string(),
                         "-o", (folder_ / "run").string(), "--threads", "1", "--no-progress"});
    ASSERT_EQ(run.exit_code, 0) << run.output;
    grid_ = folder_ / "grid.nrrd";
    const std::string write = (fs::path(MTLED_TEST_SOURCE_DIR) / "scripts/label_maps/write_label_map.py").string() +
                              " cube " + grid_.string() + " --size 24 --spacing 0.6 --origin -1 -1 -1";
    ASSERT_EQ(std::system(write.c_str()), 0) << write;
  }
  // The cube scene meshed from the grid's label map, compressed 0.5 mm.
  json labelled_scene() const {
    json labelled =
        json::parse(test::read_text(fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/uniaxial_cube_ogden.json"));
    labelled["mesh"] = {{"type", "label_map"}, {"path", grid_.string()}, {"target_nodes", 400}};
    labelled["boundaries"] = {
        {{"type", "fixed"},
         {"name", "bottom"},
         {"nodes", {{"box", {{"min", {-1, -1, -1}}, {"max", {1, 1, 0.0028}}}}, {"surface_only", true}}}},
        {{"type", "prescribed_displacement"},
         {"name", "top"},
         {"nodes", {{"box", {{"min", {-1, -1, 0.009}}, {"max", {1, 1, 1}}}}, {"surface_only", true}}},
         {"displacement", {0, 0, -0.0005}}}};
    return labelled;
  }
  fs::path folder_, grid_;
};

TEST_F(FieldCommand, TheUniaxialCubesFieldIsTheAffineMapAtEveryVoxel) {
  const fs::path folder = folder_, grid = grid_;
  // The affine map u = A X + b that fits the run's nodes.
  const ResultField result = read_result_vtu(folder / "run" / "result.vtu");
  Eigen::MatrixXd design(result.points.size(), 4);
  Eigen::MatrixXd rhs(result.points.size(), 3);
  for (std::size_t n = 0; n < result.points.size(); ++n) {
    design.row(static_cast<Index>(n)) << result.points[n].transpose(), 1.0;
    rhs.row(static_cast<Index>(n)) = result.displacement[n].transpose();
  }
  const Eigen::MatrixXd fit = design.colPivHouseholderQr().solve(rhs);  // rows: A^T, then b^T
  const Mat3 A = fit.topRows(3).transpose();
  const Vec3 b = fit.row(3).transpose();
  EXPECT_LT((design * fit - rhs).cwiseAbs().maxCoeff(), 1e-8) << "the run is not homogeneous";

  const auto voxel = [](std::int64_t v) {
    return Vec3(-1e-3 + 0.6e-3 * static_cast<double>(v % 24), -1e-3 + 0.6e-3 * static_cast<double>((v / 24) % 24),
                -1e-3 + 0.6e-3 * static_cast<double>(v / 576));
  };
  const auto inside = [](const Vec3& X) { return (X.array() > 1e-9).all() && (X.array() < 0.01 - 1e-9).all(); };

  for (const std::string direction : {"forward", "resampling"}) {
    SCOPED_TRACE(direction);
    const fs::path file = folder / (direction + ".nrrd");
    const auto made = test::run_mtled({"field", (folder / "run").string(), "--like", grid.string(), "-o", file.string(),
                                       "--frame", "LPS", "--direction", direction, "--decay", "0"});
    ASSERT_EQ(made.exit_code, 0) << made.output;
    const std::vector<Vec3> field = read_field(file);
    ASSERT_EQ(field.size(), 24u * 24u * 24u);
    int checked = 0;
    for (std::int64_t v = 0; v < 24 * 24 * 24; ++v) {
      const Vec3 x = voxel(v), d = field[static_cast<std::size_t>(v)];
      // forward: X = x holds u(X); resampling: x is a point of the moved cube, X = x + d its reference point.
      const Vec3 X = direction == "forward" ? x : Vec3((Mat3::Identity() + A).inverse() * (x - b));
      if ((X.array().abs() < 1e-7).any() || ((X.array() - 0.01).abs() < 1e-7).any()) continue;  // on a face
      if (!inside(X)) {
        EXPECT_EQ(d, Vec3::Zero()) << "voxel " << v;
        continue;
      }
      ++checked;
      const Vec3 expected = direction == "forward" ? Vec3(A * X + b) : Vec3(X - x);
      ASSERT_LT((d - expected).norm(), 1e-6) << "voxel " << v;
    }
    EXPECT_GT(checked, 4000);
    // The same grid given by its numbers instead of an image: the same field.
    const fs::path numbers = folder / (direction + "-numbers.nrrd");
    const auto given = test::run_mtled({"field", (folder / "run").string(), "--origin", "-1", "-1", "-1", "--spacing",
                                        "0.6", "--size", "24", "24", "24", "--space", "LPS", "-o", numbers.string(),
                                        "--frame", "LPS", "--direction", direction, "--decay", "0"});
    ASSERT_EQ(given.exit_code, 0) << given.output;
    const std::vector<Vec3> same = read_field(numbers);
    ASSERT_EQ(same.size(), field.size());
    for (std::size_t v = 0; v < same.size(); ++v) ASSERT_LT((same[v] - field[v]).norm(), 1e-12) << "voxel " << v;
  }
  const auto neither = test::run_mtled(
      {"field", (folder / "run").string(), "-o", (folder / "neither.nrrd").string(), "--frame", "LPS"});
  EXPECT_EQ(neither.exit_code, 2) << neither.output;
  EXPECT_NE(neither.output.find("--like IMAGE"), std::string::npos) << neither.output;
}

// A mesh made from the label map records its frame (summary.json): no --frame needed; and the scene's output section
// asks for the same field the command writes.
TEST_F(FieldCommand, ALabelMapsMeshKnowsItsFrameAndTheSceneCanAskForTheField) {
  const fs::path folder = folder_, grid = grid_;
  json labelled = labelled_scene();
  test::write_text(folder / "labelled.json", labelled.dump(2));
  const auto labelled_run = test::run_mtled(
      {"run", (folder / "labelled.json").string(), "-o", (folder / "labelled").string(), "--no-progress"});
  ASSERT_EQ(labelled_run.exit_code, 0) << labelled_run.output;
  EXPECT_EQ(test::read_json(folder / "labelled" / "summary.json")["mesh"]["coordinate_system"], "LPS");
  const auto framed = test::run_mtled(
      {"field", (folder / "labelled").string(), "--like", grid.string(), "-o", (folder / "labelled.nrrd").string()});
  EXPECT_EQ(framed.exit_code, 0) << framed.output;

  // The scene's output section asks for the same field: written beside result.vtu, the same bytes.
  labelled["output"] = {{"displacement_field_like", grid.string()}};
  test::write_text(folder / "with-field.json", labelled.dump(2));
  const auto with_field = test::run_mtled(
      {"run", (folder / "with-field.json").string(), "-o", (folder / "with-field").string(), "--no-progress"});
  ASSERT_EQ(with_field.exit_code, 0) << with_field.output;
  const auto by_hand = test::run_mtled({"field", (folder / "with-field").string(), "--like", grid.string(), "-o",
                                        (folder / "by-hand.nrrd").string()});
  ASSERT_EQ(by_hand.exit_code, 0) << by_hand.output;
  EXPECT_EQ(test::read_text(folder / "with-field" / "displacement_field.nrrd"),
            test::read_text(folder / "by-hand.nrrd"));
}

TEST_F(FieldCommand, WithoutAPatientFrameTheFieldIsRefusedWithTheFix) {
  const fs::path folder = folder_, grid = grid_;
  // The cube's Gmsh mesh records no patient frame: the command says how to give one.
  const auto frameless = test::run_mtled(
      {"field", (folder / "run").string(), "--like", grid.string(), "-o", (folder / "no.nrrd").string()});
  EXPECT_EQ(frameless.exit_code, 2) << frameless.output;
  EXPECT_NE(frameless.output.find("--frame LPS"), std::string::npos) << frameless.output;
  EXPECT_FALSE(fs::exists(folder / "no.nrrd"));
  // ... and a scene whose mesh records no frame cannot ask for the field: refused before the run.
  json frameless_scene =
      json::parse(test::read_text(fs::path(MTLED_TEST_SOURCE_DIR) / "share/scenes/uniaxial_cube_ogden.json"));
  frameless_scene["output"]["displacement_field_like"] = grid.string();
  test::write_text(folder / "frameless.json", frameless_scene.dump(2));
  const auto refused = test::run_mtled(
      {"run", (folder / "frameless.json").string(), "-o", (folder / "frameless").string(), "--no-progress"});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("/output/displacement_field_like"), std::string::npos) << refused.output;
  EXPECT_FALSE(fs::exists(folder / "frameless" / "result.vtu"));
}

}  // namespace
}  // namespace mtled
