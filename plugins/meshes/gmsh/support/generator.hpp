#pragma once
// What every Gmsh generator shares: the size parameters (target_nodes, mesh_size) and the generation loop
// that calibrates the mesh size until the node count lands within +-3% of the target.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "mtled/mesh.hpp"
#include "mtled/parameters.hpp"
#include "path_refinement.hpp"
#include "support/gmsh_model.hpp"

namespace mtled {

// Declares "target_nodes" (default `default_target_nodes`), "mesh_size", "jitter" and the refinement along a
// segment (path_refinement.hpp) on a generator.
void declare_mesh_size(ComponentDeclaration& declaration, long default_target_nodes);

// Declares "refine_rims" on a generator that sets GeneratorRequest::rim_curves.
void declare_rim_refinement(ComponentDeclaration& declaration);

// What the two declare their parameters into (generate_tet_mesh reads them).
struct MeshSizeSettings {
  long target_nodes = 0;
  std::optional<double> mesh_size;
  double jitter = 0.0;
  std::optional<Vec3> refine_from, refine_to;
  std::optional<double> refine_ratio, refine_size;
  double refine_distance = 0.0;
  std::optional<double> refine_transition;
  bool refine_rims = false;  // false where the generator does not declare it
  bool refine_along_needle = false;
};

struct GeneratorRequest {
  MeshContext context;      // the scene's: its needle's planned path, for refine_along_needle
  std::string component;    // the generator's name, for log lines and messages
  std::string description;  // what is generated, with its dimensions: becomes TetMesh::source
  // Builds the geometry and its physical groups into the current, empty Gmsh model and measures it.
  std::function<GeometryMeasure()> build_geometry;
  // CAD geometry (OpenCASCADE) is built once and only its mesh cleared between generations. Geometry made
  // from a mesh (an STL's discrete surfaces) is rebuilt for each generation: clearing the mesh takes the
  // triangles it is parametrised on, and Gmsh 4.8 then aborts the process while meshing.
  bool rebuild_each_generation = false;
  // The coarsest mesh size that still follows the shape (a cylinder's radius: at least 6 segments around
  // it; coarser, Gmsh spends minutes on the degenerate faces): coarser requests are refused.
  struct SizeLimit {
    double size;       // m
    std::string what;  // "the radius"
  };
  std::optional<SizeLimit> max_mesh_size;
  // Generators whose shape has rims (a cylinder's circular edges) name the curves "refine_rims" refines along;
  // called after build_geometry. Empty: the generator declares no refine_rims.
  std::function<std::vector<int>()> rim_curves;
  // Where a failure is reported (InputError's `where`): the block's pointer unless a file is to blame.
  std::optional<std::string> failure_where;
  std::string failure_advice = "check the dimensions, or try another target_nodes or mesh_size";
  // The node-count model's factor k for this shape, measured once on a pilot of its default cloud: given, the
  // calibration starts from it instead of generating a pilot (one generation for the default target_nodes).
  std::optional<double> node_factor;
};

// Generates the mesh under a GmshSession. With "mesh_size" given, one generation at that size; otherwise
// the size is calibrated with the node-count model N(h) = k (c_v V / h^3 + c_s A / h^2): the first size
// solves the model with k = 1, each further generation corrects k by the node count measured, so that one
// to three generations land within +-3% of target_nodes (targets from 20,000 nodes first calibrate k on a
// pilot mesh with 1/4 of the nodes, which costs about 1/4 of a generation, unless the generator states its
// shape's k: GeneratorRequest::node_factor). Sizes already tried bracket
// the next guess, since on coarse meshes the count jumps in steps (whole segments per edge); after 5
// generations, or once the bracket is 0.5% wide, the closest mesh is kept with a warning. Every step is
// deterministic. Logs the node count, tet count, mesh size and time; throws InputError when Gmsh fails.
TetMesh generate_tet_mesh(const Parameters& parameters, const GeneratorRequest& request);

// Lengths below this are refused: OpenCASCADE's modelling tolerance is 1e-7 m.
inline constexpr double kMinLength = 1e-5;

// An extent (the vector3 parameter `name` of `parameters`, its value `extent`) whose components must each be
// >= kMinLength: the kernel's range check on vectors only covers |v| > 0, so each component is checked here. Throws
// InputError at its pointer.
Vec3 positive_extent(const Vec3& extent, const Parameters& parameters, std::string_view name);

// "[0.03, 0.02, 0.01]" for descriptions and messages.
std::string format_vector(const Vec3& v);

// Relative tolerance on the node count that the calibration aims for.
inline constexpr double kNodeCountTolerance = 0.03;

}  // namespace mtled
