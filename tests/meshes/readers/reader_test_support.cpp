#include "reader_test_support.hpp"

#include <algorithm>
#include <cmath>

namespace mtled::test {

std::filesystem::path fixtures() { return source_dir() / "tests" / "data" / "meshes"; }

TetMesh read_mesh(const std::string& reader, const json& block, const std::filesystem::path& directory) {
  const auto source = make<MeshSource>(reader, block);
  return source->load(MeshContext{directory, 1, {}});
}

InputError read_error(const std::string& reader, const json& block, const std::filesystem::path& directory) {
  try {
    read_mesh(reader, block, directory);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << reader << " read " << block.dump() << " without an InputError";
  return InputError("", "");
}

std::string where_of(const InputError& error) { return error.problems().empty() ? "" : error.problems().front().where; }
std::filesystem::path folder_with_file(const std::string& folder, const std::string& name, const std::string& text) {
  const auto dir = scratch_dir(folder);
  write_text(dir / name, text);
  return dir;
}

std::string message_of(const InputError& error) {
  return error.problems().empty() ? "" : error.problems().front().message;
}

CanonicalMesh canonical(const TetMesh& mesh, const std::map<std::string, std::string>& rename, double quantum) {
  auto round = [quantum](double x) { return quantum > 0.0 ? std::round(x / quantum) * quantum : x; };
  auto point = [&](Index i) {
    return Point{round(mesh.points[i][0]), round(mesh.points[i][1]), round(mesh.points[i][2])};
  };
  // Only the nodes the tets use (the kernel drops the others).
  std::vector<char> used(mesh.points.size(), 0);
  for (const auto& tet : mesh.tets)
    for (Index v : tet) used[v] = 1;
  CanonicalMesh result;
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
    if (used[i]) result.points.push_back(point(static_cast<Index>(i)));
  std::sort(result.points.begin(), result.points.end());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    std::string name = mesh.region_names.at(static_cast<std::size_t>(mesh.tet_region.at(t)));
    if (const auto it = rename.find(name); it != rename.end()) name = it->second;
    std::set<Point> corners;
    for (Index v : mesh.tets[t]) corners.insert(point(v));
    result.regions[name].insert(corners);
  }
  for (const auto& [name, nodes] : mesh.node_sets) {
    auto& set = result.node_sets[name];
    for (Index n : nodes)
      if (used[n]) set.insert(point(n));
  }
  return result;
}

std::ostream& operator<<(std::ostream& out, const CanonicalMesh& mesh) {
  out << mesh.points.size() << " points; regions";
  for (const auto& [name, tets] : mesh.regions) out << " " << name << " (" << tets.size() << " tets)";
  out << "; node sets";
  for (const auto& [name, nodes] : mesh.node_sets) out << " " << name << " (" << nodes.size() << " nodes)";
  return out;
}

CanonicalMesh reference_cube() {
  // Points (i, j, k) -> (0.5 i, j, k); each box [i, i+1] cut into the 6 tets of the paths from its corner
  // (i, 0, 0) to (i+1, 1, 1) that step one axis at a time.
  CanonicalMesh cube;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) cube.points.push_back({0.5 * i, 1.0 * j, 1.0 * k});
  std::sort(cube.points.begin(), cube.points.end());
  const char* names[2] = {"left", "right"};
  std::array<int, 3> axes{0, 1, 2};
  for (int box = 0; box < 2; ++box) {
    do {
      std::array<int, 3> c{box, 0, 0};
      std::set<Point> corners{{0.5 * c[0], 1.0 * c[1], 1.0 * c[2]}};
      for (int axis : axes) {
        ++c[static_cast<std::size_t>(axis)];
        corners.insert({0.5 * c[0], 1.0 * c[1], 1.0 * c[2]});
      }
      cube.regions[names[box]].insert(corners);
    } while (std::next_permutation(axes.begin(), axes.end()));
  }
  for (const auto& p : cube.points) cube.node_sets[p[2] == 0.0 ? "bottom" : "top"].insert(p);
  return cube;
}

double total_volume(const TetMesh& mesh) {
  double sum = 0.0;
  for (Index t = 0; t < mesh.tet_count(); ++t) sum += std::abs(tet_volume(mesh, t));
  return sum;
}

}  // namespace mtled::test
