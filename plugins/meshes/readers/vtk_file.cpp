// VTK mesh reader: legacy .vtk (ASCII, binary) and XML .vtu (plain, zlib) unstructured grids, chosen by the file extension.
// 4-node tetrahedra (VTK type 10) become the mesh; an integer cell array names the region of each tet; point
// arrays named in "node_set_arrays" become node sets.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/io/mesh_file.hpp"
#include "mtled/io/vtk_grid.hpp"

namespace mtled {

namespace {

// Cell arrays that carry a region number in files written by mtled ("region"), meshio ("gmsh:physical",
// "medit:ref"), Gmsh's VTK export ("CellEntityIds") and deal.II / FEniCS ("MaterialIds"), in this order.
const std::vector<std::string> kRegionArrays = {"region", "gmsh:physical", "CellEntityIds", "MaterialIds", "medit:ref"};

std::vector<std::string> array_names(const std::vector<vtk::DataArray>& arrays) {
  std::vector<std::string> names;
  for (const auto& a : arrays) names.push_back(a.name);
  return names;
}

const vtk::DataArray* find_array(const std::vector<vtk::DataArray>& arrays, const std::string& name) {
  for (const auto& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

}  // namespace

class VtkFileReader final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Reads a VTK unstructured grid of 4-node tets: legacy .vtk (ASCII or binary, versions 2 to 5.1) or XML "
        ".vtu (ascii, inline base64, or appended base64 or raw data, uncompressed or zlib-compressed: what VTK, "
        "ParaView, meshio and 3D Slicer save), chosen by the file extension. 3D Slicer's \"SPACE\" tag (LPS or "
        "RAS) is kept with the mesh and carried into results. Other cells (vertices, lines, triangles) "
        "are skipped; other volume cells are refused. Regions come from an integer cell array; node sets from "
        "the point arrays named in \"node_set_arrays\". Reads mtled's own result.vtu (one written in millimetres, "
        "tagged LENGTH_UNIT, is read back in metres). The example reads the "
        "fixture tests/data/meshes/cube.vtu (a path from the source tree's root).");
    mesh_readers::declare_file_parameters(d, "VTK: legacy .vtk (ASCII or binary), or XML .vtu");
    d.string("region_array")
        .defaults("auto")
        .doc(
            "The integer cell array that gives each tet its region; regions are named by its values (\"1\", "
            "\"2\", ...). \"auto\": the first of \"region\", \"gmsh:physical\", \"CellEntityIds\", \"MaterialIds\" and "
            "\"medit:ref\" the file has, else one region \"all\"; \"none\": one region \"all\" whatever the file has.")
        .to<&Settings::region_array>();
    d.string_list("node_set_arrays")
        .defaults(json::array())
        .doc(
            "Point arrays that mark node sets: each becomes a node set of the same name holding the points where "
            "the array is not 0 (so one point can be in several sets). Empty: no node sets.")
        .to<&Settings::node_set_arrays>();
    d.example({{"path", "tests/data/meshes/cube.vtu"}, {"node_set_arrays", {"bottom", "top"}}});
  }

  explicit VtkFileReader(const Parameters& parameters) : parameters_(parameters) {}

  TetMesh load(const MeshContext& context) override {
    const auto file = mesh_readers::read_mesh_file(parameters_, context);
    const std::string extension = mesh_readers::lowercase(file.path.extension().string());
    const Settings settings = parameters_.read<Settings>();
    const std::string& region_array = settings.region_array;
    const std::vector<std::string>& node_set_arrays = settings.node_set_arrays;

    vtk::ArrayRequest request;
    if (region_array == "auto")
      request.cell_arrays = kRegionArrays;
    else if (region_array != "none")
      request.cell_arrays = {region_array};
    request.point_arrays = node_set_arrays;

    vtk::UnstructuredGrid grid;
    if (extension == ".vtk") {
      grid = vtk::read_legacy_vtk(file, request);
    } else if (extension == ".vtu") {
      grid = vtk::read_vtu(file, request);
    } else {
      throw InputError(
          parameters_.pointer("path"),
          fmt::format("{}: the extension {} is not a VTK unstructured grid: vtk_file reads legacy .vtk and "
                      "XML .vtu files (rename the file if its extension is wrong; use gmsh_file for .msh, "
                      "abaqus_file for .inp)",
                      file.label, mesh_readers::quote_token(extension)));
    }
    if (grid.tets.empty())
      throw InputError(file.label, fmt::format("the grid has {} cells but no tetrahedra (VTK cell type 10): mtled "
                                               "needs a volume mesh of 4-node tets",
                                               grid.cell_count));

    TetMesh mesh;
    mesh.points = std::move(grid.points);
    mesh.tets = std::move(grid.tets);
    mesh.coordinate_system = grid.coordinate_system;
    assign_regions(mesh, grid, region_array, file.label);
    for (const auto& name : node_set_arrays) add_node_set(mesh, grid, name);
    // An mtled result written in millimetres says so (LENGTH_UNIT): back to metres before `scale`.
    const double file_unit = vtk::metres_per_length_unit(grid, file.label);
    mesh_readers::finish_mesh(mesh, file_unit * parameters_.read<mesh_readers::FileSettings>().scale, file.label);
    return mesh;
  }

 private:
  struct Settings {
    std::string region_array;
    std::vector<std::string> node_set_arrays;
  };
  void assign_regions(TetMesh& mesh, const vtk::UnstructuredGrid& grid, const std::string& choice,
                      const std::string& label) const {
    const vtk::DataArray* array = nullptr;
    if (choice == "auto") {
      for (const auto& name : kRegionArrays)
        if ((array = find_array(grid.cell_arrays, name)) != nullptr) break;
    } else if (choice != "none") {
      array = find_array(grid.cell_arrays, choice);
      if (array == nullptr) {
        const auto names = array_names(grid.cell_arrays);
        const auto hint = did_you_mean(choice, names);
        throw InputError(parameters_.pointer("region_array"),
                         fmt::format("{} has no cell array \"{}\"; its cell arrays: {}{}{} (or use \"auto\" or "
                                     "\"none\")",
                                     label, choice, mesh_readers::list_names(names), hint.empty() ? "" : "; ", hint));
      }
    }
    if (array == nullptr) return;  // finish_mesh makes the one region "all"
    log().debug("{}: regions from cell array \"{}\"", label, array->name);
    if (array->components != 1)
      throw InputError(array->where, fmt::format("cell array \"{}\" has {} components: a region array has one integer "
                                                 "per cell; name another with \"region_array\"",
                                                 array->name, array->components));
    if (array->values.size() != grid.cell_count)
      throw InputError(array->where, fmt::format("cell array \"{}\" holds {} values for {} cells: it is missing from "
                                                 "some pieces, or the file is damaged",
                                                 array->name, array->values.size(), grid.cell_count));
    std::vector<long long> value(mesh.tets.size());
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      const double v = array->values[grid.tet_cell[t]];
      if (v != std::floor(v) || std::abs(v) > 9.0e15)
        throw InputError(array->where, fmt::format("cell array \"{}\" gives cell {} the value {}, not an integer: "
                                                   "regions need integer values; name another array with "
                                                   "\"region_array\" or use \"none\"",
                                                   array->name, grid.tet_cell[t], v));
      value[t] = static_cast<long long>(v);
    }
    // Regions by ascending value, named by it.
    std::map<long long, Index> region_of_value;
    for (long long v : value) region_of_value.emplace(v, 0);
    for (auto& [v, region] : region_of_value) {
      region = static_cast<Index>(mesh.region_names.size());
      mesh.region_names.push_back(std::to_string(v));
    }
    mesh.tet_region.resize(mesh.tets.size());
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) mesh.tet_region[t] = region_of_value[value[t]];
  }

  void add_node_set(TetMesh& mesh, const vtk::UnstructuredGrid& grid, const std::string& name) const {
    const vtk::DataArray* array = find_array(grid.point_arrays, name);
    if (array == nullptr) {
      const auto names = array_names(grid.point_arrays);
      const auto hint = did_you_mean(name, names);
      throw InputError(parameters_.pointer("node_set_arrays"),
                       fmt::format("the file has no point array \"{}\"; its point arrays: {}{}{}", name,
                                   mesh_readers::list_names(names), hint.empty() ? "" : "; ", hint));
    }
    if (array->components != 1)
      throw InputError(array->where, fmt::format("point array \"{}\" has {} components: a node-set array has one value "
                                                 "per point (not 0: in the set)",
                                                 name, array->components));
    if (array->values.size() != mesh.points.size())
      throw InputError(array->where, fmt::format("point array \"{}\" holds {} values for {} points: it is missing "
                                                 "from some pieces, or the file is damaged",
                                                 name, array->values.size(), mesh.points.size()));
    auto& nodes = mesh.node_sets[name];
    for (std::size_t i = 0; i < array->values.size(); ++i)
      if (array->values[i] != 0.0) nodes.push_back(static_cast<Index>(i));
  }

  Parameters parameters_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::VtkFileReader)
