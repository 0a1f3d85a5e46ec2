// A brain-shaped body built from simple shapes (no scanned or licensed data), for the paper's brain-phantom
// insertion (section 3.3: 0.14 x 0.156 x 0.14 m, 73,926 nodes, 417,790 tets, inferior surface fixed, needle
// 100 mm along -z).
//
// Design, in metres at the default size with the bounding box centred on the origin (x left-right, y
// back-to-front, z up; every part is an ellipsoid, fused with an OpenCASCADE boolean union):
//   right cerebral hemisphere  centre (+0.025, 0.006, 0.015), semi-axes (0.045, 0.072, 0.055)
//   left cerebral hemisphere   centre (-0.025, 0.006, 0.015), semi-axes (0.045, 0.072, 0.055)
//   cerebellum (below-behind)  centre (0, -0.045, -0.030),    semi-axes (0.050, 0.033, 0.025)
//   brain stem (downwards)     centre (0, -0.012, -0.030),    semi-axes (0.014, 0.016, 0.040)
// The hemispheres overlap by 40 mm and leave a midline groove on top; their outer sides give x = +-0.07,
// their fronts y = +0.078 and their tops z = +0.07; the cerebellum's back gives y = -0.078 and the stem's
// lower end z = -0.07. Another `size` scales every part along each axis, so the bounding box is `size`
// about `center`. The top and bottom extremes are poles of the OCC ellipsoids, hence mesh nodes; the mesh
// reaches the other four to within the faceting error, at most L^2 / (2 rho) for boundary edges of length
// L, with curvature radii rho >= 18.9 mm there at the default size (the cerebellum's back: 0.025^2 / 0.033).
// (Embedding nodes at those points made Gmsh's Frontal-Delaunay fail on the hemisphere's B-spline face.)
//
// Node sets: "surface", every boundary node; "inferior", the surface nodes in the lowest inferior_fraction
// of the height (default 0.3: z <= -0.028 m at the default size, i.e. the brain stem, the underside of the
// cerebellum and the base of the hemispheres), the part a skull base supports and the paper fixes.
//
// Needle path: the vertical line through the right hemisphere's centre, x = center_x + 0.025 / 0.14 size_x,
// y = center_y + 0.006 / 0.156 size_y, enters the top surface at z = center_z + size_z / 2 (the
// hemisphere's top, a mesh node) and stays inside that hemisphere down to z = center_z - 0.04 / 0.14 size_z:
// 110 mm at the default size, more than the paper's 100 mm insertion.
#include <fmt/format.h>
#include <gmsh.h>

#include <array>
#include <cmath>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "support/generator.hpp"
#include "support/gmsh_session.hpp"

namespace mtled {

namespace {

struct Ellipsoid {
  Vec3 center;
  Vec3 semi_axes;
};

const Vec3 kDesignSize(0.14, 0.156, 0.14);
const std::array<Ellipsoid, 4> kDesign{{
    {Vec3(0.025, 0.006, 0.015), Vec3(0.045, 0.072, 0.055)},   // right hemisphere
    {Vec3(-0.025, 0.006, 0.015), Vec3(0.045, 0.072, 0.055)},  // left hemisphere
    {Vec3(0.0, -0.045, -0.030), Vec3(0.050, 0.033, 0.025)},   // cerebellum
    {Vec3(0.0, -0.012, -0.030), Vec3(0.014, 0.016, 0.040)},   // brain stem
}};
const Vec3 kDesignNeedleEntry(0.025, 0.006, 0.07);
constexpr double kDesignNeedleDepth = 0.11;  // inside the right hemisphere below the entry
constexpr double kMaxDistortion = 2.0;       // largest ratio between the axes' scale factors

}  // namespace

class GmshBrainPhantom final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Brain-like body (two fused cerebral hemispheres, cerebellum, brain stem; all ellipsoids) "
        "tet-meshed by Gmsh; node sets \"surface\" and \"inferior\"; region \"brain\". Needle path: the "
        "vertical line through center + (0.025/0.14 size_x, 0.006/0.156 size_y) enters the top at "
        "z = center_z + size_z/2 and stays inside for 110/140 size_z (110 mm by default)");
    d.vector3("size")
        .defaults({kDesignSize[0], kDesignSize[1], kDesignSize[2]})
        .at_least(kMinLength)
        .unit("m")
        .doc(
            "bounding box: left-right (x), back-front (y), inferior-superior (z) extent, each >= 1e-5 m; the paper's "
            "phantom is 0.14 x 0.156 x 0.14 m. Each axis scales the design; the scale factors of two axes may "
            "differ by a factor of 2 at most")
        .to<&Settings::size>();
    d.vector3("center").defaults({0.0, 0.0, 0.0}).unit("m").doc("centre of the bounding box").to<&Settings::center>();
    d.number("inferior_fraction")
        .defaults(0.3)
        .greater_than(0.0)
        .less_than(1.0)
        .unit("1")
        .doc(
            "node set \"inferior\" holds the surface nodes in the lowest inferior_fraction of the height (z): the "
            "part of the surface a skull base supports, fixed in the paper")
        .to<&Settings::inferior_fraction>();
    declare_mesh_size(d, 74000);
    d.example({{"target_nodes", 2000}});
  }

  explicit GmshBrainPhantom(const Parameters& p) : GmshBrainPhantom(p, p.read<Settings>()) {}

  TetMesh load(const MeshContext& context) override {
    GeneratorRequest request;
    request.context = context;
    request.component = "brain_phantom";
    const Vec3 size = kDesignSize.cwiseProduct(scale_);
    request.description =
        fmt::format("Gmsh brain phantom, size {} m about {}", format_vector(size), format_vector(center_));
    request.build_geometry = [this] { return build(); };
    // k of this shape measured on the pilot of the default cloud (18,795 nodes at 4.057 mm): the default
    // target_nodes then takes one generation, the same mesh the pilot led to.
    request.node_factor = 1.0159459459459463;
    TetMesh mesh = generate_tet_mesh(parameters_, request);

    const double lowest = center_[2] - 0.5 * size[2];
    const double limit = lowest + inferior_fraction_ * size[2];
    std::vector<Index>& inferior = mesh.node_sets["inferior"];
    for (const Index n : mesh.node_sets.at("surface"))
      if (mesh.points[static_cast<std::size_t>(n)][2] <= limit) inferior.push_back(n);
    log().info(
        "brain_phantom: needle entry {} m on the top surface; straight path along -z inside for {:.4g} m; "
        "\"inferior\": {} surface nodes with z <= {:.4g} m",
        format_vector(place(kDesignNeedleEntry)), kDesignNeedleDepth * scale_[2], inferior.size(), limit);
    return mesh;
  }

 private:
  struct Settings {
    Vec3 size = Vec3::Zero(), center = Vec3::Zero();
    double inferior_fraction = 0.0;
  };

  GmshBrainPhantom(const Parameters& p, const Settings& s)
      : parameters_(p),
        scale_(positive_extent(s.size, p, "size").cwiseQuotient(kDesignSize)),
        center_(s.center),
        inferior_fraction_(s.inferior_fraction) {
    // Squashed far enough, the ellipsoids' B-spline faces send Gmsh's surface mesher into minutes of
    // retries (at a tenth of the height); within a factor 2 it meshes as fast as the default shape.
    const double distortion = scale_.maxCoeff() / scale_.minCoeff();
    if (distortion > kMaxDistortion)
      throw InputError(p.pointer("size"),
                       fmt::format("size {} m stretches the brain's proportions (0.14 : 0.156 : 0.14) by a factor of "
                                   "{:.3g} between axes; at most {:.0f} is allowed: scale all three extents alike, "
                                   "e.g. {} m",
                                   format_vector(kDesignSize.cwiseProduct(scale_)), distortion, kMaxDistortion,
                                   format_vector(kDesignSize * std::cbrt(scale_.prod()))));
  }

  Vec3 place(const Vec3& design_point) const { return center_ + design_point.cwiseProduct(scale_); }

  GeometryMeasure build() const {
    gmsh_checked([&] {
      gmsh::vectorpair parts;
      for (const Ellipsoid& part : kDesign) {
        const Vec3 c = place(part.center);
        const Vec3 semi = part.semi_axes.cwiseProduct(scale_);
        const int sphere = gmsh::model::occ::addSphere(c[0], c[1], c[2], 1.0);
        gmsh::model::occ::dilate({{3, sphere}}, c[0], c[1], c[2], semi[0], semi[1], semi[2]);
        parts.emplace_back(3, sphere);
      }
      gmsh::vectorpair body;
      std::vector<gmsh::vectorpair> origin;
      gmsh::model::occ::fuse({parts.front()}, gmsh::vectorpair(parts.begin() + 1, parts.end()), body, origin);
      if (body.size() != 1) throw GmshError(fmt::format("the union of the parts gave {} volumes", body.size()));
      gmsh::model::occ::synchronize();
      add_named_group(3, {body.front().second}, "brain");
      add_named_group(2, entity_tags(2), "surface");
    });
    return occ_geometry_measure();
  }

  Parameters parameters_;
  Vec3 scale_;
  Vec3 center_;
  double inferior_fraction_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshBrainPhantom)
