// Label maps in: the NRRD and NIfTI readers (io/src/nrrd.cpp, nifti.cpp) against what the writing script put in
// (sizes, voxel counts, frame, segment names), the mesher (label_map plugin) against the labelled volume, and bad
// input refused with the file and field. Every label map is written by scripts/label_maps/write_label_map.py, NRRD
// by hand as 3D Slicer writes it, NIfTI with nibabel.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <numbers>

#include "mesh_spacing.hpp"
#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/io/label_image.hpp"
#include "mtled/markups.hpp"
#include "mtled/mesh.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace mtled {
namespace {

fs::path write_label_map(const std::string& shape, const std::string& name, const std::string& options = "") {
  const fs::path out = test::scratch_dir("label_map") / name;
  const std::string command = std::string(MTLED_TEST_PYTHON) + " " +
                              (test::source_dir() / "scripts/label_maps/write_label_map.py").string() + " " + shape +
                              " " + out.string() + " " + options;
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  return out;
}

TetMesh mesh_label_map(const json& block, const MeshContext& context = {{}, 1, {}}) {
  return test::make<MeshSource>("label_map", block)->load(context);
}

double region_volume(const TetMesh& mesh, const std::string& region) {
  double volume = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t)
    if (mesh.region_names[static_cast<std::size_t>(mesh.tet_region[static_cast<std::size_t>(t)])] == region)
      volume += tet_volume(mesh, t);
  return volume;
}

// The sphere of radius 0.35 x 16 mm on a 40^3 grid (0.4 mm voxels), in every encoding and both formats: the same
// grid, the same labels, the frame each format states.
TEST(LabelMap, EveryFormatReadsTheSameSphere) {
  const double spacing = 0.4e-3;
  const std::int64_t expected = [&] {  // the voxel centres inside the sphere, counted here
    std::int64_t n = 0;
    for (int i = 0; i < 40; ++i)
      for (int j = 0; j < 40; ++j)
        for (int k = 0; k < 40; ++k) {
          const double x = (i - 19.5) / 40.0, y = (j - 19.5) / 40.0, z = (k - 19.5) / 40.0;
          n += x * x + y * y + z * z <= 0.35 * 0.35 ? 1 : 0;
        }
    return n;
  }();
  for (const std::string name : {"raw.nrrd", "gzip.nrrd", "short.nrrd", "sphere.seg.nrrd", "sphere.nii", "sphere.nii.gz"}) {
    const std::string options = std::string("--size 40") + (name == "raw.nrrd" ? " --encoding raw" : "") +
                                (name == "short.nrrd" ? " --type int16" : "");
    const LabelImage image = read_label_image(write_label_map("sphere", name, options));
    EXPECT_EQ(image.size, (std::array<std::int64_t, 3>{40, 40, 40})) << name;
    // NRRD writes its geometry as decimal text (17 digits); NIfTI stores it in float32 (7 digits of 7.8 mm).
    const double tolerance = name.find(".nii") != std::string::npos ? 1e-9 : 1e-12;
    EXPECT_NEAR((image.spacing() - Vec3::Constant(spacing)).norm(), 0.0, tolerance) << name;
    EXPECT_NEAR((image.origin - Vec3::Constant(-19.5 * spacing)).norm(), 0.0, tolerance) << name;
    EXPECT_EQ(image.voxel_counts().at(1), expected) << name;
    EXPECT_EQ(image.space, name.find(".nii") != std::string::npos ? "RAS" : "LPS") << name;
    if (name == "sphere.seg.nrrd") {
      EXPECT_EQ(image.segment_names.at(1), "tissue");
    }
  }
}

// One marked voxel (1, 2, 3) on a rotated, shifted grid: its centre is where the file's geometry puts it (origin +
// R diag(spacing) (1, 2, 3)), as 3D Slicer shows it, in both formats.
TEST(LabelMap, AMarkerVoxelLandsWhereTheFilePlacesIt) {
  const double c = std::cos(0.3), s = std::sin(0.3);
  const Mat3 rotation = (Mat3() << c, -s, 0, s, c, 0, 0, 0, 1).finished();
  const Vec3 origin(12.5e-3, -40e-3, 7e-3);
  const double spacing = 0.5e-3;
  const std::string options = fmt::format("--size 8 --spacing 0.5 --origin 12.5 -40 7 --directions {} {} 0 {} {} 0 0 0 1",
                                          c, s, -s, c);  // the axes' directions, one after another
  for (const std::string name : {"marker.nrrd", "marker.nii.gz"}) {
    const LabelImage image = read_label_image(write_label_map("marker", name, options));
    ASSERT_EQ(image.voxel_counts().at(1), 1) << name;
    EXPECT_EQ(image.at(1, 2, 3), 1) << name;
    const Vec3 expected = origin + rotation * (spacing * Vec3(1, 2, 3));
    EXPECT_NEAR((image.voxel_centre(1, 2, 3) - expected).norm(), 0.0, 1e-9) << name;
  }
}

// Meshed, each sphere's volume is its labelled voxels' volume to within what the surface criterion allows: facets at
// most surface_distance d from the labels' boundary, over the area, 3 d / r of the volume (spheres of r = 2.88 mm);
// and the error shrinks with d. The meshes are valid tets (check_mesh in the plugin).
TEST(LabelMap, TheMeshedVolumeIsTheLabelledVolume) {
  const fs::path file = write_label_map("two_spheres", "two.seg.nrrd", "--size 40");
  const LabelImage image = read_label_image(file);
  const double voxel = std::pow(0.4e-3, 3), radius = 0.18 * 16e-3;
  std::map<std::string, double> previous;
  for (const double d : {0.2e-3, 0.05e-3}) {
    const TetMesh mesh = mesh_label_map({{"path", file.string()}, {"mesh_size", 0.8e-3}, {"surface_distance", d}});
    ASSERT_EQ(mesh.region_names.size(), 2u);
    for (const auto& [label, name] : image.segment_names) {
      const double labelled = static_cast<double>(image.voxel_counts().at(label)) * voxel;
      const double error = std::abs(region_volume(mesh, name) / labelled - 1.0);
      EXPECT_LT(error, 3.0 * d / radius) << name << ", surface_distance " << d;
      if (previous.count(name) != 0) {
        EXPECT_LT(error, previous[name]) << name << " did not improve with d";
      }
      previous[name] = error;
      std::printf("%s d=%g: volume error %.4f (bound %.4f)\n", name.c_str(), d, error, 3.0 * d / radius);
    }
  }
  const TetMesh mesh = mesh_label_map({{"path", file.string()}, {"mesh_size", 0.8e-3}});
  EXPECT_EQ(mesh.coordinate_system, "LPS");
  EXPECT_FALSE(mesh.node_sets.at("surface").empty());
  // Only the segment asked for: the other is outside the body.
  const TetMesh right = mesh_label_map({{"path", file.string()}, {"mesh_size", 0.8e-3}, {"segments", {"right"}}});
  ASSERT_EQ(right.region_names, std::vector<std::string>{"right"});
  for (const auto& p : right.points) EXPECT_GT(p[0], -0.5e-3);
}

// region_mesh_size refines one region: flat facets inside a curved surface cut off a volume that falls as the facet
// size squared, so at a third of the body's size the right sphere's volume error must fall below a third of what it
// was (a ninth ideally; the voxels' staircase and the surface-distance criterion keep a floor), while the left sphere,
// left at the body's size, keeps its error. Regions are numbered in label order whatever the mesh.
TEST(LabelMap, ARegionMeshSizeRefinesThatRegionsBoundary) {
  const fs::path file = write_label_map("two_spheres", "two.seg.nrrd", "--size 40");
  const LabelImage image = read_label_image(file);
  const double voxel = std::pow(0.4e-3, 3);
  const auto error = [&](const TetMesh& mesh, std::int32_t label) {
    const double labelled = static_cast<double>(image.voxel_counts().at(label)) * voxel;
    return std::abs(region_volume(mesh, image.segment_names.at(label)) / labelled - 1.0);
  };
  const json block = {{"path", file.string()}, {"mesh_size", 1.5e-3}};
  const TetMesh coarse = mesh_label_map(block);
  json refined_block = block;
  refined_block["region_mesh_size"] = {{image.segment_names.at(2), 0.5e-3}};
  const TetMesh refined = mesh_label_map(refined_block);
  ASSERT_EQ(refined.region_names, (std::vector<std::string>{image.segment_names.at(1), image.segment_names.at(2)}));
  std::printf("volume errors: left %.4f -> %.4f, right %.4f -> %.4f; nodes %d -> %d\n", error(coarse, 1),
              error(refined, 1), error(coarse, 2), error(refined, 2), coarse.node_count(), refined.node_count());
  EXPECT_LT(error(refined, 2), error(coarse, 2) / 3.0);
  EXPECT_NEAR(error(refined, 1), error(coarse, 1), 0.25 * error(coarse, 1));

  refined_block["region_mesh_size"] = {{"rigth", 0.5e-3}};
  EXPECT_THROW(
      {
        try {
          mesh_label_map(refined_block);
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("/region_mesh_size/rigth"), std::string::npos) << e.what();
          EXPECT_NE(std::string(e.what()).find("did you mean \"right\""), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
}

// refine_from/refine_to with refine_size refine along a segment given in the image's physical frame, whatever the
// grid's rotation and origin: on a sphere meshed at 1.2 mm on a rotated, shifted grid, refined to 0.4 mm along a chord
// through its centre, the spacing by that chord is about a third of the spacing farther than 2 mm from it (CGAL's sizes
// are upper bounds: the spread is CGAL's, as the Gmsh generators' tests allow theirs).
TEST(LabelMap, RefinesAlongASegmentInTheImagesFrame) {
  const double c = std::cos(0.3), s = std::sin(0.3);
  const fs::path file =
      write_label_map("sphere", "rotated.nrrd",
                      fmt::format("--size 40 --origin 12.5 -40 7 --directions {} {} 0 {} {} 0 0 0 1", c, s, -s, c));
  const LabelImage image = read_label_image(file);
  const Vec3 centre = image.origin + image.axes * Vec3::Constant(19.5);
  const Vec3 along(1.0, 0.0, 0.0);  // a physical axis, not the grid's
  const auto point = [&](const Vec3& v, double t) { return centre + t * v; };
  json block = {{"path", file.string()},
                {"mesh_size", 1.2e-3},
                {"refine_from", {point(along, -4e-3)[0], point(along, -4e-3)[1], point(along, -4e-3)[2]}},
                {"refine_to", {point(along, 4e-3)[0], point(along, 4e-3)[1], point(along, 4e-3)[2]}},
                {"refine_size", 0.4e-3},
                {"refine_distance", 0.6e-3},
                {"refine_transition", 0.6e-3}};
  const TetMesh mesh = mesh_label_map(block);
  const auto from_chord = [&](const Vec3& x) { return (x - centre - (x - centre).dot(along) * along).norm(); };
  const test::Spacing refined = test::spacing_where(
      mesh, [&](const Vec3& x) { return std::abs((x - centre).dot(along)) < 3.5e-3 && from_chord(x) < 0.5e-3; });
  const test::Spacing bulk = test::spacing_where(mesh, [&](const Vec3& x) { return from_chord(x) > 2e-3; });
  std::printf("spacing by the refined chord %.3f mm (%d nodes), farther than 2 mm from it %.3f mm (%d nodes)\n",
              1e3 * refined.mean, refined.nodes, 1e3 * bulk.mean, bulk.nodes);
  ASSERT_GT(refined.nodes, 20);
  ASSERT_GT(bulk.nodes, 20);
  EXPECT_NEAR(refined.mean / bulk.mean, 1.0 / 3.0, 0.12);

  // The same segment as a needle's path planned in RAS (a Slicer markups file's other frame): placed in the image's
  // LPS frame, it gives the same mesh.
  ASSERT_EQ(image.space, "LPS");
  json from_needle = block;
  from_needle.erase("refine_from");
  from_needle.erase("refine_to");
  from_needle["refine_along_needle"] = true;
  MeshContext needle{{}, 1, {}};
  needle.needle_path = [&] {
    return PlannedPath{flip_lps_ras(point(along, -4e-3)), flip_lps_ras(point(along, 4e-3)), "RAS"};
  };
  EXPECT_EQ(mesh_label_map(from_needle, needle).points, mesh.points);

  block["refine_ratio"] = 0.5;  // and a size: one or the other
  EXPECT_THROW(
      {
        try {
          mesh_label_map(block);
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("/refine_size"), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
}

// "smooth" puts the boundary on a smooth surface through the voxels: on a sphere of 16.8 voxels' radius the surface
// nodes lie closer to the true sphere than the staircase-following mesh's do (the voxel centres inside it are the
// labels; the true surface is the sphere of radius 0.35 x 16 mm).
TEST(LabelMap, SmoothLabelsFollowTheShapeRatherThanTheVoxels) {
  const fs::path file = write_label_map("sphere", "smooth.nrrd", "--size 48");
  const double radius = 0.35 * 16e-3, voxel = 16e-3 / 48;
  std::map<bool, double> worst;
  for (const bool smooth : {false, true}) {
    const TetMesh mesh = mesh_label_map(
        {{"path", file.string()}, {"mesh_size", 0.6e-3}, {"surface_distance", 0.05e-3}, {"smooth", smooth}});
    for (const Index n : mesh.node_sets.at("surface"))
      worst[smooth] = std::max(worst[smooth], std::abs(mesh.points[static_cast<std::size_t>(n)].norm() - radius));
    std::printf("smooth %d: surface nodes within %.3f voxels of the sphere\n", smooth, worst[smooth] / voxel);
  }
  EXPECT_LT(worst[true], 0.5 * voxel);
  EXPECT_LT(worst[true], worst[false]);
}

// A label map a user would get wrong: each refused with exit 2 and the file and field named.
TEST(LabelMap, BadLabelMapsAreRefusedNamingTheFileAndField) {
  const fs::path good = write_label_map("sphere", "good.nrrd", "--size 16 --encoding raw");
  std::string text = test::read_text(good);
  const auto expect_refused = [&](const std::string& name, const std::string& content, const std::string& needle) {
    const fs::path file = test::scratch_dir("label_map") / name;
    test::write_text(file, content);
    try {
      read_label_image(file);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << name << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << name << ": " << e.what();
    }
  };
  expect_refused("truncated.nrrd", text.substr(0, text.size() - 100), "truncated");
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  expect_refused("bzip.nrrd", replaced("encoding: raw", "encoding: bzip2"), "encoding");
  expect_refused("sheared.nrrd", replaced("space directions: (1,0,0)", "space directions: (1,1,0)"), "not orthogonal");
  expect_refused("singular.nrrd", replaced("space directions: (1,0,0)", "space directions: (0,0,0)"), "singular");
  const fs::path gz = write_label_map("sphere", "good.nii.gz", "--size 16");
  const std::string gzip_text = test::read_text(gz);
  expect_refused("cut.nii.gz", gzip_text.substr(0, gzip_text.size() / 2), "gzip");
  expect_refused("noise.nii", std::string(400, '\x7f'), "sizeof_hdr");
  // A NIfTI-1 header whose vox_offset (the float at byte 108) is NaN (found by fuzz_label_map).
  std::string nifti = test::read_text(write_label_map("sphere", "good.nii", "--size 16"));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nifti.data() + 108, &nan, sizeof nan);
  expect_refused("nan_offset.nii", nifti, "vox_offset");
  expect_refused("image.png", "not an image", "unknown image format");
  // Labels the scene names that the image lacks, and an image with nothing labelled.
  EXPECT_THROW(mesh_label_map({{"path", good.string()}, {"mesh_size", 1e-3}, {"labels", {7}}}), InputError);
  EXPECT_THROW(mesh_label_map({{"path", good.string()}, {"mesh_size", 1e-3}, {"segments", {"tumor"}}}), InputError);
  const fs::path empty = write_label_map("marker", "empty.nrrd", "--size 4 --encoding raw");
  std::string blank = test::read_text(empty);
  std::fill(blank.end() - 64, blank.end(), '\0');
  test::write_text(empty, blank);
  try {
    mesh_label_map({{"path", empty.string()}, {"mesh_size", 1e-3}});
    ADD_FAILURE() << "an empty label map was meshed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mtled
