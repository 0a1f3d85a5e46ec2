#pragma once
// What every mesh-file reader shares: the common parameters ("path", "scale"), finding and reading the
// file, mapping the file's node ids to indices, and the finishing touches on the TetMesh.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/mesh.hpp"
#include "mtled/parameters.hpp"
#include "mtled/io/text_cursor.hpp"

namespace mtled::mesh_readers {

// Declares "path" (required) and "scale" (default 1), bound to FileSettings. `format` names the files the reader
// takes, for the doc.
struct FileSettings {
  std::string path;
  double scale = 1.0;
};
void declare_file_parameters(ComponentDeclaration& declaration, std::string_view format);

struct MeshFileText {
  std::filesystem::path path;  // as resolved against the scene's folder
  std::string label;           // the file as named in messages ("label:line")
  std::string text;
};

// Resolves the "path" parameter against context.scene_directory and reads the file whole. A missing or
// unreadable file is an InputError at the "path" pointer (with close file names in that folder as
// suggestions); an empty file one at the file.
MeshFileText read_mesh_file(const Parameters& parameters, const MeshContext& context);

// Reads `file` whole (for files named inside other files, such as Abaqus *INCLUDE). Errors are reported at
// `where`.
MeshFileText read_text_file(const std::filesystem::path& file, const std::string& where);

// A file's node ids (any integers, in any order, with gaps) mapped to indices 0, 1, ... in file order.
class NodeIds {
 public:
  void reserve(std::size_t count);
  // Adds the node read at the cursor's current line; a repeated id fails there, naming the first line.
  Index add(long long id, const TextCursor& at);
  std::optional<Index> find(long long id) const;
  std::size_t size() const { return line_.size(); }

 private:
  std::unordered_map<long long, Index> index_;
  std::vector<long> line_;
};

// Coordinates times `scale`; region "all" (every tet) when the file named none; node sets sorted without
// repeats; `source` set for messages.
void finish_mesh(TetMesh& mesh, double scale, const std::string& source);

// Up to `count` names joined with ", " (and "..." when there are more), for messages.
std::string list_names(const std::vector<std::string>& names, std::size_t count = 12);

}  // namespace mtled::mesh_readers
