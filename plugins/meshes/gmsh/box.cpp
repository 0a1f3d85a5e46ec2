// A rectangular box meshed with Gmsh (OpenCASCADE box, Delaunay tets).
#include <fmt/format.h>
#include <gmsh.h>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/plugin.hpp"
#include "support/generator.hpp"
#include "support/gmsh_session.hpp"

namespace mtled {

class GmshBox final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Rectangular box [origin, origin + size] tet-meshed by Gmsh; node sets x0, x1, y0, y1, z0, z1 "
        "(the faces at the low and high end of each axis), region \"all\"");
    d.vector3("size")
        .at_least(kMinLength)
        .unit("m")
        .doc("edge lengths [a, b, c] along x, y, z, each >= 1e-5 m")
        .to<&Settings::size>();
    d.vector3("origin")
        .defaults({0.0, 0.0, 0.0})
        .unit("m")
        .doc("corner with the smallest coordinates")
        .to<&Settings::origin>();
    declare_mesh_size(d, 5000);
    d.example({{"size", {0.03, 0.02, 0.01}}, {"target_nodes", 1500}});
  }

  explicit GmshBox(const Parameters& p) : GmshBox(p, p.read<Settings>()) {}

  TetMesh load(const MeshContext& context) override {
    GeneratorRequest request;
    request.context = context;
    request.component = "box";
    request.description = fmt::format("Gmsh box, size {} m at {}", format_vector(size_), format_vector(origin_));
    request.build_geometry = [this] { return build(); };
    return generate_tet_mesh(parameters_, request);
  }

 private:
  struct Settings {
    Vec3 size = Vec3::Zero(), origin = Vec3::Zero();
  };
  GmshBox(const Parameters& p, const Settings& s)
      : parameters_(p), size_(positive_extent(s.size, p, "size")), origin_(s.origin) {}

  GeometryMeasure build() const {
    gmsh_checked([&] {
      const int box = gmsh::model::occ::addBox(origin_[0], origin_[1], origin_[2], size_[0], size_[1], size_[2]);
      gmsh::model::occ::synchronize();
      add_named_group(3, {box}, "all");
    });
    // Faces found by where they lie rather than by OCC's face numbering: the other faces' centres are half
    // an edge away from the plane.
    const double tolerance = 1e-6 * size_.minCoeff();
    static const char* const kFaceNames[3][2] = {{"x0", "x1"}, {"y0", "y1"}, {"z0", "z1"}};
    for (int axis = 0; axis < 3; ++axis) {
      add_named_group(2, surfaces_in_plane(axis, origin_[axis], tolerance), kFaceNames[axis][0]);
      add_named_group(2, surfaces_in_plane(axis, origin_[axis] + size_[axis], tolerance), kFaceNames[axis][1]);
    }
    return occ_geometry_measure();
  }

  Parameters parameters_;
  Vec3 size_;
  Vec3 origin_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshBox)
