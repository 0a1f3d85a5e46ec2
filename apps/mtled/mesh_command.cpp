// `mtled mesh SCENE -o FILE.inp`: the scene's mesh, read or generated as a run would, written as an Abaqus file
// (nodes, tets by region, node sets) that the abaqus_file reader takes back unchanged; for machines without Gmsh.
#include "commands.hpp"
#include "mtled/io/mesh_writer.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/analysis/scene_sections.hpp"
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"

namespace mtled::app {

int mesh_command(const MeshOptions& options) {
  SceneDocument document = read_scene(options.scene.scene, options.scene.overrides);
  PluginCatalog catalog(plugin_search_path(options.scene.plugin_paths, scene_plugin_paths(document)));
  const Scene scene = validate_scene(std::move(document), catalog, run_scene_sections());
  const TetMesh mesh = load_scene_mesh(scene, catalog);
  write_abaqus_mesh(mesh, options.output);
  log().info("{}: {} nodes, {} tets, {} regions, {} node sets; read it with {{\"type\": \"abaqus_file\", \"path\": \"{}\"}}",
             options.output.string(), mesh.node_count(), mesh.tet_count(), mesh.region_names.size(), mesh.node_sets.size(),
             options.output.filename().string());
  return 0;
}

}  // namespace mtled::app
