#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>

#include "generated_mesh_checks.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "test_support.hpp"

namespace mtled::test {
namespace {

using Faces = std::vector<std::array<int, 3>>;

struct Polyhedron {
  std::vector<Vec3> vertices;
  Faces faces;  // counter-clockwise seen from outside
};

Polyhedron box(const Vec3& low, const Vec3& high) {
  Polyhedron p;
  for (int k = 0; k < 8; ++k)
    p.vertices.emplace_back(k & 1 ? high[0] : low[0], k & 2 ? high[1] : low[1], k & 4 ? high[2] : low[2]);
  p.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return p;
}

// A prism over an L-shaped base (non-convex), height h; corners of the base counter-clockwise.
Polyhedron l_prism(double h) {
  const std::vector<Eigen::Vector2d> base{{0, 0}, {20, 0}, {20, 8}, {8, 8}, {8, 20}, {0, 20}};
  Polyhedron p;
  const int n = static_cast<int>(base.size());
  for (const double z : {0.0, h})
    for (const auto& b : base) p.vertices.emplace_back(b[0], b[1], z);
  // Bottom and top as fans from corner 3 (the reflex corner sees every other corner).
  for (int k = 0; k < n; ++k) {
    const int a = (3 + 1 + k) % n, b = (3 + 2 + k) % n;
    if (b == 3) break;
    p.faces.push_back({3, b, a});
    p.faces.push_back({n + 3, n + a, n + b});
  }
  for (int k = 0; k < n; ++k) {
    const int a = k, b = (k + 1) % n;
    p.faces.push_back({a, b, n + b});
    p.faces.push_back({a, n + b, n + a});
  }
  return p;
}

// An icosahedron subdivided `levels` times with its vertices pushed onto the sphere of `radius`.
Polyhedron icosphere(double radius, int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Polyhedron p;
  p.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  p.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& v : p.vertices) v = v.normalized() * radius;
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      p.vertices.push_back((p.vertices[a] + p.vertices[b]).normalized() * radius);
      return middle[key] = static_cast<int>(p.vertices.size()) - 1;
    };
    Faces finer;
    for (const auto& f : p.faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    p.faces = std::move(finer);
  }
  return p;
}

double enclosed_volume(const Polyhedron& p) {
  double volume = 0.0;
  for (const auto& f : p.faces) volume += p.vertices[f[0]].dot(p.vertices[f[1]].cross(p.vertices[f[2]])) / 6.0;
  return volume;
}

void write_ascii_stl(const std::filesystem::path& file, const Polyhedron& p) {
  std::ofstream out(file);
  out.precision(17);
  out << "solid test\n";
  for (const auto& f : p.faces) {
    out << "  facet normal 0 0 0\n    outer loop\n";
    for (const int v : f)
      out << "      vertex " << p.vertices[v][0] << ' ' << p.vertices[v][1] << ' ' << p.vertices[v][2] << '\n';
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid test\n";
}

void write_binary_stl(const std::filesystem::path& file, const Polyhedron& p) {
  std::ofstream out(file, std::ios::binary);
  const std::string header = "solid binary header that is not ASCII";  // binary files may start with "solid"
  char head[80] = {};
  std::memcpy(head, header.data(), header.size());
  out.write(head, 80);
  const auto count = static_cast<std::uint32_t>(p.faces.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& f : p.faces) {
    float record[12] = {};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) record[3 + 3 * c + k] = static_cast<float>(p.vertices[f[c]][k]);
    out.write(reinterpret_cast<const char*>(record), sizeof record);
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
}

TetMesh load_stl(const std::filesystem::path& folder, const json& block) {
  auto source = make<MeshSource>("stl_surface", block);
  return kernel_ready(source->load(MeshContext{folder, 1, {}}));
}

TEST(GmshStlSurface, BoxRoundTripKeepsTheVolumeAndHitsTheTarget) {
  const auto folder = scratch_dir("gmsh_stl_box");
  const Vec3 low(0.01, 0.02, -0.01), high(0.04, 0.04, 0.0);
  write_ascii_stl(folder / "box.stl", box(low, high));
  const TetMesh mesh = load_stl(folder, {{"path", "box.stl"}, {"target_nodes", 1500}});
  EXPECT_NEAR(mesh.node_count(), 1500, 0.03 * 1500);
  // Flat faces remeshed on themselves: the volume is exact up to round-off.
  EXPECT_NEAR(mesh_volume(mesh), (high - low).prod(), 1e-9 * (high - low).prod());
  EXPECT_EQ(mesh.region_names, std::vector<std::string>{"all"});
  std::vector<char> in_set(mesh.points.size(), 0);
  for (const Index n : node_set(mesh, "surface")) in_set[static_cast<std::size_t>(n)] = 1;
  EXPECT_EQ(in_set, surface_nodes(mesh));
  const Bounds b = bounding_box(mesh);
  EXPECT_LT((b.min - low).norm(), 1e-12);
  EXPECT_LT((b.max - high).norm(), 1e-12);
}

TEST(GmshStlSurface, NonConvexBinaryInMillimetres) {
  const auto folder = scratch_dir("gmsh_stl_l_prism");
  const Polyhedron prism = l_prism(10.0);
  write_binary_stl(folder / "l_prism.stl", prism);
  const TetMesh mesh = load_stl(folder, {{"path", "l_prism.stl"}, {"scale", 0.001}, {"target_nodes", 1200}});
  EXPECT_NEAR(mesh.node_count(), 1200, 0.03 * 1200);
  // 20 x 20 mm minus 12 x 12 mm, 10 mm high; float coordinates of small integers are exact.
  const double exact = (400.0 - 144.0) * 10.0 * 1e-9;
  EXPECT_NEAR(enclosed_volume(prism) * 1e-9, exact, 1e-12 * exact);  // the test's own polyhedron is right
  EXPECT_NEAR(mesh_volume(mesh), exact, 1e-9 * exact);
}

TEST(GmshStlSurface, SmoothSphereIsRemeshedInsideItsFacets) {
  const auto folder = scratch_dir("gmsh_stl_sphere");
  const double radius = 0.02;
  const Polyhedron sphere = icosphere(radius, 3);  // 1,280 facets
  write_ascii_stl(folder / "sphere.stl", sphere);
  const TetMesh mesh = load_stl(folder, {{"path", "sphere.stl"}, {"target_nodes", 2000}});
  EXPECT_NEAR(mesh.node_count(), 2000, 0.03 * 2000);
  // The remeshed surface has its nodes on the convex STL polyhedron, so the body lies inside it. Its nodes
  // are at least the polyhedron's inradius r_in from the centre, and any point of a face with edges <= L is
  // within L / sqrt(3) of a corner, so the body holds the ball of radius sqrt(r_in^2 - L^2 / 3).
  double inradius = radius;
  for (const auto& f : sphere.faces) {
    const Vec3 normal = (sphere.vertices[f[1]] - sphere.vertices[f[0]])
                            .cross(sphere.vertices[f[2]] - sphere.vertices[f[0]])
                            .normalized();
    inradius = std::min(inradius, normal.dot(sphere.vertices[f[0]]));
  }
  const double edge = longest_boundary_edge(mesh);
  const double inner = std::sqrt(inradius * inradius - edge * edge / 3);
  const double volume = mesh_volume(mesh);
  EXPECT_LE(volume, enclosed_volume(sphere) * (1 + 1e-9));
  EXPECT_GE(volume, 4.0 / 3.0 * std::numbers::pi * inner * inner * inner);
  for (const Vec3& x : mesh.points) EXPECT_LE(x.norm(), radius * (1 + 1e-9));
}

TEST(GmshStlSurface, IsDeterministic) {
  const auto folder = scratch_dir("gmsh_stl_determinism");
  write_ascii_stl(folder / "sphere.stl", icosphere(0.01, 2));
  const json block = {{"path", "sphere.stl"}, {"target_nodes", 800}};
  EXPECT_TRUE(identical(load_stl(folder, block), load_stl(folder, block)));
}

// The error cases: each names the file (with the line for ASCII) and says what to fix.
class GmshStlSurfaceErrors : public ::testing::Test {
 protected:
  void SetUp() override { folder_ = scratch_dir("gmsh_stl_errors"); }
  Problem error_for(const std::string& file) {
    return input_error([&] { load_stl(folder_, {{"path", file}, {"target_nodes", 500}}); });
  }
  std::string path(const std::string& file) const { return (folder_ / file).string(); }
  std::filesystem::path folder_;
};

TEST_F(GmshStlSurfaceErrors, MissingFile) {
  const Problem p = error_for("nowhere.stl");
  EXPECT_EQ(p.where, "/test/path");
  EXPECT_NE(p.message.find(path("nowhere.stl")), std::string::npos) << p.message;
  EXPECT_NE(p.message.find("not found"), std::string::npos) << p.message;
}

TEST_F(GmshStlSurfaceErrors, NotAnStlFile) {
  // A Gmsh script: mtled must never run it.
  write_text(folder_ / "model.stl", "Point(1) = {0, 0, 0};\nSystemCall \"touch ran\";\n");
  const Problem p = error_for("model.stl");
  EXPECT_EQ(p.where, path("model.stl"));
  EXPECT_NE(p.message.find("not an STL file"), std::string::npos) << p.message;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "ran"));
  const Problem folder = error_for(".");
  EXPECT_EQ(folder.where, "/test/path");
}

TEST_F(GmshStlSurfaceErrors, TruncatedAndMalformedAscii) {
  write_text(folder_ / "cut.stl", "solid cut\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0");
  const Problem cut = error_for("cut.stl");
  EXPECT_EQ(cut.where, path("cut.stl") + ":5");
  EXPECT_NE(cut.message.find("cut off"), std::string::npos) << cut.message;
  write_text(folder_ / "word.stl", "solid w\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zero\n");
  const Problem word = error_for("word.stl");
  EXPECT_EQ(word.where, path("word.stl") + ":4");
  EXPECT_NE(word.message.find("\"zero\" is not a finite number"), std::string::npos) << word.message;
}

TEST_F(GmshStlSurfaceErrors, BodyTooSmallForTheScale) {
  // A 1 mm cube read as micrometres.
  write_ascii_stl(folder_ / "cube.stl", box(Vec3::Zero(), Vec3::Ones()));
  const Problem p = input_error([&] {
    load_stl(folder_, {{"path", "cube.stl"}, {"scale", 1e-6}, {"target_nodes", 500}});
  });
  EXPECT_EQ(p.where, "/test/scale");
  EXPECT_NE(p.message.find("check scale"), std::string::npos) << p.message;
}

TEST_F(GmshStlSurfaceErrors, OpenSurface) {
  Polyhedron open = box(Vec3::Zero(), Vec3::Ones());
  open.faces.pop_back();
  write_ascii_stl(folder_ / "open.stl", open);
  const Problem p = error_for("open.stl");
  EXPECT_EQ(p.where.rfind(path("open.stl") + ":", 0), 0u) << p.where;
  EXPECT_NE(p.message.find("not closed"), std::string::npos) << p.message;
}

TEST_F(GmshStlSurfaceErrors, SelfIntersectingSurface) {
  // A corner of the cube pushed through the opposite corner: the surface stays closed and manifold but
  // crosses itself.
  Polyhedron crossing = box(Vec3::Zero(), Vec3::Ones());
  crossing.vertices[7] = Vec3(-0.5, -0.5, -0.5);
  write_binary_stl(folder_ / "crossing.stl", crossing);
  const Problem p = error_for("crossing.stl");
  EXPECT_EQ(p.where.rfind(path("crossing.stl") + " (facet ", 0), 0u) << p.where;
  EXPECT_NE(p.message.find("intersects itself"), std::string::npos) << p.message;
}

TEST_F(GmshStlSurfaceErrors, InconsistentOrientationTwoPiecesAndDegenerateFacets) {
  Polyhedron flipped = box(Vec3::Zero(), Vec3::Ones());
  std::swap(flipped.faces[3][1], flipped.faces[3][2]);
  write_ascii_stl(folder_ / "flipped.stl", flipped);
  EXPECT_NE(error_for("flipped.stl").message.find("not consistently oriented"), std::string::npos);

  Polyhedron two = box(Vec3::Zero(), Vec3::Ones());
  const Polyhedron other = box(Vec3(2, 0, 0), Vec3(3, 1, 1));
  for (auto f : other.faces) two.faces.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
  two.vertices.insert(two.vertices.end(), other.vertices.begin(), other.vertices.end());
  write_ascii_stl(folder_ / "two.stl", two);
  const Problem pieces = error_for("two.stl");
  EXPECT_EQ(pieces.where, path("two.stl"));
  EXPECT_NE(pieces.message.find("2 separate closed pieces"), std::string::npos) << pieces.message;

  Polyhedron degenerate = box(Vec3::Zero(), Vec3::Ones());
  degenerate.faces.push_back({0, 1, 1});
  write_ascii_stl(folder_ / "degenerate.stl", degenerate);
  EXPECT_NE(error_for("degenerate.stl").message.find("zero area"), std::string::npos);
}

}  // namespace
}  // namespace mtled::test
