#include "mtled/io/mesh_writer.hpp"

#include <fmt/format.h>

#include <fstream>

#include "mtled/errors.hpp"
#include "mtled/io/output.hpp"

namespace mtled {

namespace {

std::string set_name(const std::string& name, const std::filesystem::path& file) {
  if (name.empty() || name.find_first_of(",\n\r\"") != std::string::npos)
    throw InputError(file.string(), fmt::format("the set name \"{}\" cannot be written to an Abaqus file (no commas, "
                                                "quotes or line breaks)", name));
  return name;
}

// Ids (1-based) 16 to a line.
void write_ids(std::string& out, const std::vector<Index>& ids) {
  for (std::size_t k = 0; k < ids.size(); ++k)
    out += fmt::format("{}{}", ids[k] + 1, (k + 1) % 16 == 0 || k + 1 == ids.size() ? "\n" : ", ");
}

}  // namespace

void write_abaqus_mesh(const TetMesh& mesh, const std::filesystem::path& file) {
  std::string out = fmt::format("*HEADING\nmtled mesh: {} ({} nodes, {} tets)\n*NODE\n", mesh.source, mesh.node_count(),
                                mesh.tet_count());
  out.reserve(static_cast<std::size_t>(mesh.node_count()) * 64 + static_cast<std::size_t>(mesh.tet_count()) * 40);
  for (Index i = 0; i < mesh.node_count(); ++i) {
    const Vec3& x = mesh.points[static_cast<std::size_t>(i)];
    out += fmt::format("{}, {:.17g}, {:.17g}, {:.17g}\n", i + 1, x[0], x[1], x[2]);
  }
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const Index region = mesh.tet_region[static_cast<std::size_t>(t)];
    if (t == 0 || region != mesh.tet_region[static_cast<std::size_t>(t) - 1])
      out += fmt::format("*ELEMENT, TYPE=C3D4, ELSET={}\n",
                         set_name(mesh.region_names[static_cast<std::size_t>(region)], file));
    const auto& v = mesh.tets[static_cast<std::size_t>(t)];
    out += fmt::format("{}, {}, {}, {}, {}\n", t + 1, v[0] + 1, v[1] + 1, v[2] + 1, v[3] + 1);
  }
  for (const auto& [name, nodes] : mesh.node_sets) {
    if (nodes.empty()) continue;
    out += fmt::format("*NSET, NSET={}\n", set_name(name, file));
    write_ids(out, nodes);
  }
  // Through a temporary name, renamed when complete: never a half-written mesh.
  const auto folder = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  OutputFolder(folder).write_file(file.filename().string(), [&](std::ostream& stream) { stream << out; });
}

}  // namespace mtled
