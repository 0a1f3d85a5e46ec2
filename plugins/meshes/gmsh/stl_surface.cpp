// The volume inside a closed triangulated surface (an STL file), tet-meshed by Gmsh after remeshing the
// surface at the requested size.
#include <fmt/format.h>
#include <gmsh.h>

#include <numbers>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/plugin.hpp"
#include "stl/stl_file.hpp"
#include "support/generator.hpp"
#include "support/gmsh_session.hpp"

namespace mtled {

namespace {

// Facets meeting at more than this angle start a new CAD face, so sharp edges (a box's) are kept as curves;
// smooth parts become faces that Gmsh re-parametrises and remeshes.
constexpr double kFeatureAngle = 40.0 * std::numbers::pi / 180.0;

// The surface's own triangles as a discrete Gmsh surface, classified into faces that Gmsh can parametrise,
// and the volume they enclose. Nodes of the STL are not kept: the faces are remeshed at the mesh size.
GeometryMeasure build_from_surface(const StlSurface& surface) {
  gmsh_checked([&] {
    const int discrete = gmsh::model::addDiscreteEntity(2);
    std::vector<std::size_t> node_tags(surface.vertices.size());
    std::vector<double> coordinates;
    coordinates.reserve(3 * surface.vertices.size());
    for (std::size_t i = 0; i < surface.vertices.size(); ++i) {
      node_tags[i] = i + 1;
      for (int k = 0; k < 3; ++k) coordinates.push_back(surface.vertices[i][k]);
    }
    gmsh::model::mesh::addNodes(2, discrete, node_tags, coordinates);
    std::vector<std::size_t> triangle_nodes;
    triangle_nodes.reserve(3 * surface.triangles.size());
    for (const auto& t : surface.triangles)
      for (const Index i : t) triangle_nodes.push_back(static_cast<std::size_t>(i) + 1);
    constexpr int kTriangle = 2;  // Gmsh element type of a 3-node triangle
    gmsh::model::mesh::addElementsByType(discrete, kTriangle, {}, triangle_nodes);

    gmsh::model::mesh::classifySurfaces(kFeatureAngle, /*boundary=*/true, /*forReparametrization=*/true,
                                        /*curveAngle=*/std::numbers::pi);
    gmsh::model::mesh::createGeometry();
    const std::vector<int> faces = entity_tags(2);
    const int shell = gmsh::model::geo::addSurfaceLoop(faces);
    const int volume = gmsh::model::geo::addVolume({shell});
    gmsh::model::geo::synchronize();
    add_named_group(3, {volume}, "all");
    add_named_group(2, faces, "surface");
  });
  return {surface.volume, surface.area};
}

}  // namespace

class GmshStlSurface final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The volume inside a closed triangulated surface (ASCII or binary STL): the surface is remeshed "
        "and the inside tet-meshed by Gmsh; node set \"surface\", region \"all\". The surface must be "
        "closed, one piece, consistently oriented and not cross itself");
    d.string("path")
        .unit("1")
        .doc(
            "STL file; a relative path is resolved against the scene's folder. Each generation re-classifies the "
            "surface (about 5 s per 100,000 facets here): decimate large scans first")
        .to<&Settings::path>();
    d.number("scale")
        .defaults(1.0)
        .positive()
        .unit("m")
        .doc("metres per STL unit: 1 for a file in metres, 0.001 for one in millimetres")
        .to<&Settings::scale>();
    declare_mesh_size(d, 10000);
    d.example({{"path", "brain_surface.stl"}, {"scale", 0.001}, {"target_nodes", 2000}});
  }

  explicit GmshStlSurface(const Parameters& p)
      : parameters_(p), path_(p.read<Settings>().path), scale_(p.read<Settings>().scale) {}

  TetMesh load(const MeshContext& context) override {
    const std::filesystem::path file = resolve(context.scene_directory);
    const StlSurface surface = read_closed_stl(file, scale_);
    check_extent(surface);
    GeneratorRequest request;
    request.context = context;
    request.component = "stl_surface";
    request.description = fmt::format("Gmsh volume inside {} (scale {:.6g})", file.string(), scale_);
    request.build_geometry = [&surface] { return build_from_surface(surface); };
    request.rebuild_each_generation = true;
    request.failure_where = file.string();
    request.failure_advice =
        "check that the surface bounds one solid without overlapping parts, or try another "
        "target_nodes or mesh_size";
    return generate_tet_mesh(parameters_, request);
  }

 private:
  struct Settings {
    std::string path;
    double scale = 0.0;
  };
  // Gmsh's and OpenCASCADE's tolerances are absolute (1e-8 to 1e-7 m): a body this small is most likely a
  // wrong scale.
  void check_extent(const StlSurface& surface) const {
    Eigen::AlignedBox3d box;
    for (const Vec3& v : surface.vertices) box.extend(v);
    if (box.sizes().minCoeff() < kMinLength)
      throw InputError(parameters_.pointer("scale"),
                       fmt::format("{} scaled by {:g} spans only {} m; each extent must be at least {:g} m: check "
                                   "scale (metres per STL unit: 0.001 for a file in millimetres)",
                                   surface.file.string(), scale_, format_vector(box.sizes()), kMinLength));
  }

  std::filesystem::path resolve(const std::filesystem::path& scene_directory) const {
    std::filesystem::path file(path_);
    if (file.is_relative() && !scene_directory.empty()) file = scene_directory / file;
    file = file.lexically_normal();  // messages name the file as a user would
    std::error_code error;
    if (!std::filesystem::exists(file, error))
      throw InputError(
          parameters_.pointer("path"),
          fmt::format("STL file {} not found{}; give a path to an existing file (relative paths start "
                      "at the scene's folder)",
                      file.string(),
                      scene_directory.empty() ? "" : fmt::format(" (scene folder {})", scene_directory.string())));
    if (std::filesystem::is_directory(file, error))
      throw InputError(parameters_.pointer("path"),
                       fmt::format("{} is a folder; give the path of the STL file itself", file.string()));
    return file;
  }

  Parameters parameters_;
  std::string path_;
  double scale_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshStlSurface)
