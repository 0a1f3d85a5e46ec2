// .msh files through Gmsh's own reader (libgmsh's C++ API): binary MSH 2.2 / 4.1 (Gmsh's `-bin`), and every
// other version Gmsh reads. The same regions and node sets as mtled's ASCII parser: physical volumes become
// regions, physical points, curves and surfaces node sets of the nodes of their elements.
#include <fmt/format.h>
#include <gmsh.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <unordered_map>

#include "gmsh_msh.hpp"
#include "mtled/errors.hpp"
#include "support/gmsh_session.hpp"

namespace mtled::msh {

namespace {

std::string physical_name(int dimension, int tag) {
  std::string name;
  gmsh::model::getPhysicalName(dimension, tag, name);
  return name.empty() ? std::to_string(tag) : name;
}

class GmshModelReader {
 public:
  explicit GmshModelReader(const std::string& label) : label_(label) {}

  TetMesh read() {
    read_nodes();
    gmsh::vectorpair volumes;
    gmsh::model::getEntities(volumes, 3);
    for (const auto& [dim, volume] : volumes) read_volume(volume);
    if (mesh_.tets.empty())
      throw InputError(label_, "Gmsh finds no 4-node tetrahedra in the file: mtled needs a volume mesh; mesh the "
                               "volumes with `gmsh -3` and save again");
    assign_physical_regions(mesh_, tet_physical_, [](long long tag) { return physical_name(3, static_cast<int>(tag)); },
                            label_);
    for (int dimension = 0; dimension < 3; ++dimension) read_node_sets(dimension);
    return std::move(mesh_);
  }

 private:
  void read_nodes() {
    std::vector<std::size_t> tags;
    std::vector<double> coordinates, parametric;
    gmsh::model::mesh::getNodes(tags, coordinates, parametric, -1, -1, false, false);
    mesh_.points.reserve(tags.size());
    for (std::size_t i = 0; i < tags.size(); ++i) {
      index_.emplace(tags[i], static_cast<Index>(i));
      mesh_.points.push_back({coordinates[3 * i], coordinates[3 * i + 1], coordinates[3 * i + 2]});
    }
  }

  Index index(std::size_t tag) const {
    const auto it = index_.find(tag);
    if (it == index_.end())
      throw InputError(label_, fmt::format("an element names node {}, which the file does not define: the file is "
                                           "damaged; export it again",
                                           tag));
    return it->second;
  }

  void read_volume(int volume) {
    std::vector<int> types;
    gmsh::model::mesh::getElementTypes(types, 3, volume);
    for (int type : types)
      if (type != kTetType) throw InputError(label_, volume_element_advice(type));
    std::vector<int> physicals;
    gmsh::model::getPhysicalGroupsForEntity(3, volume, physicals);
    if (physicals.size() > 1)
      throw InputError(label_, fmt::format("volume {} belongs to {} physical groups: a tet belongs to one region; keep "
                                           "the volume in one Physical Volume",
                                           volume, physicals.size()));
    std::vector<std::size_t> elements, nodes;
    gmsh::model::mesh::getElementsByType(kTetType, elements, nodes, volume);
    for (std::size_t e = 0; e < elements.size(); ++e) {
      mesh_.tets.push_back({index(nodes[4 * e]), index(nodes[4 * e + 1]), index(nodes[4 * e + 2]), index(nodes[4 * e + 3])});
      tet_physical_.push_back(physicals.empty() ? 0 : physicals.front());
    }
  }

  void read_node_sets(int dimension) {
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, dimension);
    for (const auto& [dim, group] : groups) {
      std::vector<std::size_t> tags;
      std::vector<double> coordinates;
      gmsh::model::mesh::getNodesForPhysicalGroup(dim, group, tags, coordinates);
      auto& set = mesh_.node_sets[physical_name(dim, group)];
      for (std::size_t tag : tags) set.push_back(index(tag));
    }
  }

  std::string label_;
  TetMesh mesh_;
  std::unordered_map<std::size_t, Index> index_;
  std::vector<long long> tet_physical_;
};

// In the process itself (used by the child below).
TetMesh read_in_this_process(const mesh_readers::MeshFileText& file) {
  GmshSession session;
  try {
    gmsh_checked([&] { gmsh::open(file.path.string()); });
    return gmsh_checked([&] { return GmshModelReader(file.label).read(); });
  } catch (const GmshError& error) {
    throw InputError(file.label, fmt::format("Gmsh could not read the file: {}; is it a complete .msh file? Export "
                                             "the mesh again",
                                             error.what()));
  } catch (const std::bad_alloc&) {
    throw InputError(file.label, "Gmsh ran out of memory reading the file: a count in it is damaged; export the mesh "
                                 "again");
  }
}

// The mesh (or the error) passed from the child to the parent: counts and raw arrays.
class Pipe {
 public:
  void put(const void* data, std::size_t bytes) {
    const auto* begin = static_cast<const char*>(data);
    buffer_.insert(buffer_.end(), begin, begin + bytes);
  }
  template <class T>
  void put(const T& value) { put(&value, sizeof(T)); }
  void put_string(const std::string& text) {
    put(text.size());
    put(text.data(), text.size());
  }
  template <class T>
  void put_vector(const std::vector<T>& values) {
    put(values.size());
    put(values.data(), values.size() * sizeof(T));
  }

  Pipe() = default;
  explicit Pipe(const std::string& received) : buffer_(received.begin(), received.end()) {}
  void get(void* data, std::size_t bytes) {
    if (buffer_.size() - at_ < bytes) throw std::runtime_error("the reading process sent a short message");
    std::copy_n(buffer_.begin() + static_cast<std::ptrdiff_t>(at_), bytes, static_cast<char*>(data));
    at_ += bytes;
  }
  template <class T>
  T get() {
    T value{};
    get(&value, sizeof(T));
    return value;
  }
  std::string get_string() {
    std::string text(get<std::size_t>(), '\0');
    get(text.data(), text.size());
    return text;
  }
  template <class T>
  std::vector<T> get_vector() {
    std::vector<T> values(get<std::size_t>());
    get(values.data(), values.size() * sizeof(T));
    return values;
  }
  std::string buffer() const { return {buffer_.begin(), buffer_.end()}; }

 private:
  std::vector<char> buffer_;
  std::size_t at_ = 0;
};

std::string serialise(const TetMesh& mesh) {
  Pipe pipe;
  pipe.put('M');
  pipe.put_vector(mesh.points);
  pipe.put_vector(mesh.tets);
  pipe.put_vector(mesh.tet_region);
  pipe.put(mesh.region_names.size());
  for (const auto& name : mesh.region_names) pipe.put_string(name);
  pipe.put(mesh.node_sets.size());
  for (const auto& [name, nodes] : mesh.node_sets) {
    pipe.put_string(name);
    pipe.put_vector(nodes);
  }
  return pipe.buffer();
}

TetMesh deserialise(Pipe& pipe) {
  TetMesh mesh;
  mesh.points = pipe.get_vector<Vec3>();
  mesh.tets = pipe.get_vector<std::array<Index, 4>>();
  mesh.tet_region = pipe.get_vector<Index>();
  mesh.region_names.resize(pipe.get<std::size_t>());
  for (auto& name : mesh.region_names) name = pipe.get_string();
  for (auto sets = pipe.get<std::size_t>(); sets > 0; --sets) {
    std::string name = pipe.get_string();
    mesh.node_sets[name] = pipe.get_vector<Index>();
  }
  return mesh;
}

// The child's whole answer: the mesh, or "E" with the error's place and message.
std::string answer_of(const mesh_readers::MeshFileText& file) {
  try {
    return serialise(read_in_this_process(file));
  } catch (const InputError& error) {
    Pipe pipe;
    pipe.put('E');
    pipe.put_string(error.problems().empty() ? file.label : error.problems().front().where);
    pipe.put_string(error.problems().empty() ? error.what() : error.problems().front().message);
    return pipe.buffer();
  } catch (const std::exception& error) {
    Pipe pipe;
    pipe.put('E');
    pipe.put_string(file.label);
    pipe.put_string(fmt::format("Gmsh could not read the file: {}", error.what()));
    return pipe.buffer();
  }
}

}  // namespace

// Gmsh's reader runs in a child process: on damaged binary files it can crash (3 of 100 randomly damaged
// copies of a small binary .msh made it fail with SIGSEGV or a double free), which must end as an input
// error, not take mtled down. The child also keeps Gmsh's global state out of the run's process.
TetMesh read_with_gmsh(const mesh_readers::MeshFileText& file) {
  int ends[2];
  if (pipe(ends) != 0) throw std::runtime_error("cannot create a pipe to read a .msh file through Gmsh");
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t child = fork();
  if (child < 0) throw std::runtime_error("cannot start a process to read a .msh file through Gmsh");
  if (child == 0) {
    close(ends[0]);
    const std::string answer = answer_of(file);
    for (std::size_t sent = 0; sent < answer.size();) {
      const ssize_t n = write(ends[1], answer.data() + sent, answer.size() - sent);
      if (n <= 0) _exit(1);
      sent += static_cast<std::size_t>(n);
    }
    _exit(0);
  }
  close(ends[1]);
  std::string answer;
  char chunk[65536];
  for (ssize_t n; (n = read(ends[0], chunk, sizeof chunk)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    answer.append(chunk, static_cast<std::size_t>(n));
  }
  close(ends[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status) || answer.empty())
    throw InputError(file.label, fmt::format("Gmsh's reader crashed on the file ({}): it is damaged; export the "
                                             "mesh again",
                                             WIFSIGNALED(status) ? strsignal(WTERMSIG(status)) : "no answer"));
  Pipe pipe(answer);
  if (pipe.get<char>() == 'E') {
    std::string where = pipe.get_string();
    throw InputError(std::move(where), pipe.get_string());
  }
  return deserialise(pipe);
}

}  // namespace mtled::msh
