#include "mtled/io/mesh_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <sstream>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled::mesh_readers {

void declare_file_parameters(ComponentDeclaration& declaration, std::string_view format) {
  declaration.string("path")
      .doc(fmt::format("The mesh file ({}). A relative path is taken from the folder of the scene file.", format))
      .to<&FileSettings::path>();
  declaration.number("scale")
      .unit("1")
      .positive()
      .defaults(1.0)
      .doc("Multiplies every coordinate: mtled works in metres, so use 0.001 for a mesh drawn in millimetres.")
      .to<&FileSettings::scale>();
}

namespace {

std::string folder_suggestion(const fs::path& file) {
  std::error_code ec;
  const fs::path folder = file.parent_path().empty() ? fs::path(".") : file.parent_path();
  if (!fs::is_directory(folder, ec)) return fmt::format("the folder {} does not exist either", folder.string());
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.is_regular_file(ec)) names.push_back(entry.path().filename().string());
    if (names.size() > 10000) break;
  }
  const std::string hint = did_you_mean(file.filename().string(), names);
  return hint.empty() ? "check the name and the folder" : hint;
}

}  // namespace

MeshFileText read_text_file(const fs::path& file, const std::string& where) {
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw InputError(where, fmt::format("the mesh file {} does not exist: {}", file.string(), folder_suggestion(file)));
  if (fs::is_directory(file, ec))
    throw InputError(where, fmt::format("{} is a folder, not a mesh file: name the file in it", file.string()));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(where, fmt::format("cannot open the mesh file {}: check its permissions", file.string()));
  MeshFileText result;
  result.path = file;
  result.label = file.string();
  // In one read of the file's size (a run's result.vtu is tens of megabytes; character by character took a second).
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size > 0) {
    result.text.resize(static_cast<std::size_t>(size));
    in.read(result.text.data(), size);
  }
  if (in.bad() || (size > 0 && in.gcount() != size))
    throw InputError(where, fmt::format("reading the mesh file {} failed", file.string()));
  if (result.text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(result.label, "the mesh file is empty: was it saved completely? Export the mesh again");
  return result;
}

MeshFileText read_mesh_file(const Parameters& parameters, const MeshContext& context) {
  const fs::path given = parameters.read<FileSettings>().path;
  // Normalised (no "scenes/../meshes"), so that messages name the file as a user would.
  const fs::path file =
      (given.is_absolute() || context.scene_directory.empty() ? given : context.scene_directory / given).lexically_normal();
  return read_text_file(file, parameters.pointer("path"));
}

void NodeIds::reserve(std::size_t count) {
  index_.reserve(count);
  line_.reserve(count);
}

Index NodeIds::add(long long id, const TextCursor& at) {
  const auto index = static_cast<Index>(line_.size());
  const auto [it, added] = index_.emplace(id, index);
  if (!added)
    at.fail(fmt::format("node {} is defined twice (first on line {}): node ids must be unique; remove or renumber one",
                        id, line_[static_cast<std::size_t>(it->second)]));
  line_.push_back(at.line());
  return index;
}

std::optional<Index> NodeIds::find(long long id) const {
  const auto it = index_.find(id);
  if (it == index_.end()) return std::nullopt;
  return it->second;
}

void finish_mesh(TetMesh& mesh, double scale, const std::string& source) {
  if (scale != 1.0)
    for (auto& p : mesh.points) p *= scale;
  if (mesh.region_names.empty()) {
    mesh.region_names = {"all"};
    mesh.tet_region.assign(mesh.tets.size(), 0);
  }
  for (auto& [name, nodes] : mesh.node_sets) {
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }
  mesh.source = source;
}

std::string list_names(const std::vector<std::string>& names, std::size_t count) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < count; ++i) text += (i == 0 ? "" : ", ") + names[i];
  if (names.size() > count) text += ", ...";
  return text.empty() ? "(none)" : text;
}

}  // namespace mtled::mesh_readers
