// Gmsh .msh reader: ASCII MSH 2.2 and 4.1 as described in the Gmsh reference manual ("MSH file format").
// Physical volume groups become regions; the nodes of the elements of physical surface, curve and point
// groups become node sets (the triangles, lines and points Gmsh writes beside the tets are used for that
// and otherwise ignored).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <unordered_map>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/io/mesh_file.hpp"
#include "mtled/io/text_cursor.hpp"
#include "gmsh_msh.hpp"

namespace mtled {

namespace {

using msh::kTetType;
using msh::volume_element_advice;
using mesh_readers::MeshFileText;
using mesh_readers::TextCursor;

// Element types of the MSH format (Gmsh manual, "MSH file format": elm-type) with their node counts and
// dimensions. Types not listed here are refused.
struct GmshElementType {
  int nodes;
  int dimension;
  const char* name;
};

std::optional<GmshElementType> gmsh_element_type(long long type) {
  switch (type) {
    case 1:
      return GmshElementType{2, 1, "2-node line"};
    case 2:
      return GmshElementType{3, 2, "3-node triangle"};
    case 3:
      return GmshElementType{4, 2, "4-node quadrangle"};
    case 4:
      return GmshElementType{4, 3, "4-node tetrahedron"};
    case 5:
      return GmshElementType{8, 3, "8-node hexahedron"};
    case 6:
      return GmshElementType{6, 3, "6-node prism"};
    case 7:
      return GmshElementType{5, 3, "5-node pyramid"};
    case 8:
      return GmshElementType{3, 1, "3-node line"};
    case 9:
      return GmshElementType{6, 2, "6-node triangle"};
    case 10:
      return GmshElementType{9, 2, "9-node quadrangle"};
    case 11:
      return GmshElementType{10, 3, "10-node second-order tetrahedron"};
    case 12:
      return GmshElementType{27, 3, "27-node hexahedron"};
    case 13:
      return GmshElementType{18, 3, "18-node prism"};
    case 14:
      return GmshElementType{14, 3, "14-node pyramid"};
    case 15:
      return GmshElementType{1, 0, "point"};
    case 16:
      return GmshElementType{8, 2, "8-node quadrangle"};
    case 17:
      return GmshElementType{20, 3, "20-node hexahedron"};
    case 18:
      return GmshElementType{15, 3, "15-node prism"};
    case 19:
      return GmshElementType{13, 3, "13-node pyramid"};
    case 20:
      return GmshElementType{9, 2, "9-node triangle"};
    case 21:
      return GmshElementType{10, 2, "10-node triangle"};
    case 22:
      return GmshElementType{12, 2, "12-node triangle"};
    case 23:
      return GmshElementType{15, 2, "15-node triangle"};
    case 24:
      return GmshElementType{15, 2, "15-node triangle"};
    case 25:
      return GmshElementType{21, 2, "21-node triangle"};
    case 26:
      return GmshElementType{4, 1, "4-node line"};
    case 27:
      return GmshElementType{5, 1, "5-node line"};
    case 28:
      return GmshElementType{6, 1, "6-node line"};
    case 29:
      return GmshElementType{20, 3, "20-node tetrahedron"};
    case 30:
      return GmshElementType{35, 3, "35-node tetrahedron"};
    case 31:
      return GmshElementType{56, 3, "56-node tetrahedron"};
    case 92:
      return GmshElementType{64, 3, "64-node hexahedron"};
    case 93:
      return GmshElementType{125, 3, "125-node hexahedron"};
    default:
      return std::nullopt;
  }
}

// Where a section's data lines are read from, for messages about a section that ends too soon.
struct SectionProgress {
  std::string_view section;  // "Nodes"
  long start_line = 0;
  std::string_view items;  // "nodes"
  long long done = 0;
  long long total = 0;
};

class MshParser {
 public:
  explicit MshParser(const MeshFileText& file) : cursor_(file.text, file.label) {}

  TetMesh parse() {
    read_format();
    while (const auto line = cursor_.next_line()) {
      const auto text = mesh_readers::trim(*line);
      if (text.empty()) continue;
      if (text.front() != '$')
        cursor_.fail(fmt::format("expected a section such as $Nodes, found {}: is this a Gmsh .msh file?",
                                 mesh_readers::quote_token(text)));
      const std::string_view name = text.substr(1);
      const long start = cursor_.line();
      if (name == "PhysicalNames") {
        read_physical_names(start);
      } else if (name == "Entities") {
        if (version_ == 4)
          read_entities(start);
        else
          skip_section(name, start);
      } else if (name == "PartitionedEntities") {
        cursor_.fail(
            "the mesh is partitioned ($PartitionedEntities): mtled reads whole meshes; mesh it again "
            "without partitioning (no `-part` option)");
      } else if (name == "Nodes") {
        if (have_nodes_) cursor_.fail("a second $Nodes section: mtled reads files with one $Nodes section");
        if (version_ == 4)
          read_nodes_v4(start);
        else
          read_nodes_v2(start);
        have_nodes_ = true;
      } else if (name == "Elements") {
        if (!have_nodes_) cursor_.fail("$Elements comes before $Nodes: the file is damaged; export it again");
        if (have_elements_) cursor_.fail("a second $Elements section: mtled reads files with one $Elements section");
        if (version_ == 4)
          read_elements_v4(start);
        else
          read_elements_v2(start);
        have_elements_ = true;
      } else if (name.rfind("End", 0) == 0) {
        cursor_.fail(fmt::format("{} without its opening section: the file is damaged; export it again",
                                 mesh_readers::quote_token(text)));
      } else {
        skip_section(name, start);  // $NodeData, $Periodic, $Comments, ... do not concern the mesh
      }
    }
    return finish();
  }

 private:
  void read_format() {
    std::optional<std::string_view> first;
    while ((first = cursor_.next_line()) && mesh_readers::trim(*first).empty()) {
    }
    if (!first || mesh_readers::trim(*first) != "$MeshFormat") {
      const std::string found = first ? mesh_readers::quote_token(mesh_readers::trim(*first)) : std::string("nothing");
      if (first && (mesh_readers::trim(*first) == "$NOD" || mesh_readers::trim(*first) == "$NOE"))
        cursor_.fail(
            "this is an MSH 1 file, which mtled's parser does not read: set \"reader\": \"gmsh\" to read it with "
            "Gmsh's, or save it as MSH 4.1 (`gmsh mesh.msh -save -format msh41 -o mesh41.msh`)");
      cursor_.fail(fmt::format("expected $MeshFormat on the first line of a Gmsh .msh file, found {}", found));
    }
    const auto line = cursor_.next_line();
    if (!line) cursor_.fail("the file ends after $MeshFormat: it is truncated; export it again");
    split(*line);
    if (fields_.size() < 3)
      cursor_.fail(fmt::format("expected \"version file-type data-size\" (such as \"4.1 0 8\"), found {}",
                               mesh_readers::quote_token(*line)));
    const std::string_view version = fields_[0];
    const auto file_type = mesh_readers::to_integer(fields_[1], cursor_, "the file type (0 for ASCII)");
    constexpr const char* kConvert = "`gmsh mesh.msh -save -format msh41 -o mesh41.msh`";
    if (version == "4.1") {
      version_ = 4;
    } else if (version.size() >= 2 && version.substr(0, 2) == "2.") {
      version_ = 2;
    } else if (version == "4" || version == "4.0") {
      cursor_.fail(
          fmt::format("MSH version 4.0 is not read by mtled's parser (its layout differs from 4.1): set \"reader\": "
                      "\"gmsh\" to read it with Gmsh's, or convert the file with {}",
                      kConvert));
    } else {
      cursor_.fail(
          fmt::format("MSH version {} is not read: mtled reads ASCII MSH 2.2 and 4.1; convert the file with {}",
                      mesh_readers::quote_token(version), kConvert));
    }
    if (file_type != 0)
      cursor_.fail(
          fmt::format("this is a binary .msh file, which only Gmsh's reader reads and this mtled was built without "
                      "Gmsh; convert it with {} (ASCII is the default; or mesh with Mesh.Binary = 0)",
                      kConvert));
    expect_end("MeshFormat", cursor_.line() - 1);
  }

  void read_physical_names(long start) {
    SectionProgress progress{"PhysicalNames", start, "physical names", 0, 0};
    progress.total = count_line(progress, "the number of physical names");
    for (; progress.done < progress.total; ++progress.done) {
      const std::string_view line = data_line(progress);
      split(line);
      if (fields_.size() < 3)
        cursor_.fail(fmt::format("expected \"dimension tag \"name\"\", found {}", mesh_readers::quote_token(line)));
      const auto dimension = mesh_readers::to_integer(fields_[0], cursor_, "the physical group's dimension");
      const auto tag = mesh_readers::to_integer(fields_[1], cursor_, "the physical group's tag");
      // The name is the rest of the line, in double quotes, and may contain spaces.
      std::string_view name =
          mesh_readers::trim(line.substr(static_cast<std::size_t>(fields_[2].data() - line.data())));
      if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
      physical_names_[{static_cast<int>(dimension), tag}] = std::string(name);
    }
    expect_end("PhysicalNames", start);
  }

  // MSH 4.1 $Entities: which physical groups each point, curve, surface and volume belongs to.
  void read_entities(long start) {
    SectionProgress progress{"Entities", start, "entities", 0, 0};
    const std::string_view header = data_line(progress);
    split(header);
    if (fields_.size() != 4)
      cursor_.fail(fmt::format("expected \"numPoints numCurves numSurfaces numVolumes\", found {}",
                               mesh_readers::quote_token(header)));
    std::array<long long, 4> counts{};
    for (int d = 0; d < 4; ++d) {
      counts[d] = mesh_readers::to_integer(fields_[d], cursor_, "an entity count");
      if (counts[d] < 0) cursor_.fail("entity counts cannot be negative");
      // Saturated: four counts near the largest integer would overflow the sum (the section then ends early).
      if (__builtin_add_overflow(progress.total, counts[d], &progress.total))
        progress.total = std::numeric_limits<long long>::max();
    }
    for (int dimension = 0; dimension < 4; ++dimension) {
      for (long long i = 0; i < counts[dimension]; ++i, ++progress.done) {
        const std::string_view line = data_line(progress);
        split(line);
        // Points: tag x y z numPhysicalTags tags...; others: tag minX minY minZ maxX maxY maxZ numPhysicalTags ...
        const std::size_t count_field = dimension == 0 ? 4 : 7;
        if (fields_.size() <= count_field)
          cursor_.fail(
              fmt::format("the entity line is too short: expected {} fields before the physical tags, "
                          "found {}",
                          count_field + 1, fields_.size()));
        const auto tag = mesh_readers::to_integer(fields_[0], cursor_, "an entity tag");
        const auto physical_count =
            mesh_readers::to_integer(fields_[count_field], cursor_, "the number of physical tags");
        if (physical_count < 0 || fields_.size() < count_field + 1 + static_cast<std::size_t>(physical_count))
          cursor_.fail(
              fmt::format("entity {} lists {} physical tags but the line has room for fewer", tag, physical_count));
        EntityGroups& groups = entity_groups_[{dimension, tag}];
        groups.line = cursor_.line();
        for (long long p = 0; p < physical_count; ++p)
          groups.physical_tags.push_back(mesh_readers::to_integer(
              fields_[count_field + 1 + static_cast<std::size_t>(p)], cursor_, "a physical tag"));
      }
    }
    expect_end("Entities", start);
  }

  void read_nodes_v2(long start) {
    SectionProgress progress{"Nodes", start, "nodes", 0, 0};
    progress.total = count_line(progress, "the number of nodes");
    reserve_nodes(progress.total);
    for (; progress.done < progress.total; ++progress.done) {
      split(data_line(progress));
      if (fields_.size() != 4)
        cursor_.fail(fmt::format("expected \"node-number x y z\", found {} fields", fields_.size()));
      add_node(fields_[0], fields_[1], fields_[2], fields_[3]);
    }
    expect_end("Nodes", start);
  }

  void read_nodes_v4(long start) {
    SectionProgress progress{"Nodes", start, "nodes", 0, 0};
    const std::string_view header = data_line(progress);
    split(header);
    if (fields_.size() != 4)
      cursor_.fail(fmt::format("expected \"numEntityBlocks numNodes minNodeTag maxNodeTag\", found {}",
                               mesh_readers::quote_token(header)));
    const auto blocks = mesh_readers::to_integer(fields_[0], cursor_, "the number of entity blocks");
    progress.total = mesh_readers::to_integer(fields_[1], cursor_, "the number of nodes");
    if (blocks < 0 || progress.total < 0) cursor_.fail("negative counts in the $Nodes header");
    reserve_nodes(progress.total);
    std::vector<std::string_view> tags;
    std::vector<std::string> tag_text;  // tags are read before their coordinates: keep them
    for (long long b = 0; b < blocks; ++b) {
      split(data_line(progress));
      if (fields_.size() != 4)
        cursor_.fail(
            fmt::format("expected a node block header \"entityDim entityTag parametric numNodesInBlock\", "
                        "found {} fields",
                        fields_.size()));
      const auto parametric = mesh_readers::to_integer(fields_[2], cursor_, "the parametric flag (0 or 1)");
      const auto in_block = mesh_readers::to_integer(fields_[3], cursor_, "the number of nodes in the block");
      // Compared with what is left, not summed: a huge block count would overflow done + in_block.
      if (in_block < 0 || in_block > progress.total - progress.done)
        cursor_.fail(
            fmt::format("the node blocks hold more nodes than the $Nodes header announces ({})", progress.total));
      const long first_tag_line = cursor_.line() + 1;
      tag_text.clear();
      for (long long i = 0; i < in_block; ++i) {
        split(data_line(progress));
        if (fields_.size() != 1) cursor_.fail(fmt::format("expected one node tag, found {} fields", fields_.size()));
        tag_text.emplace_back(fields_[0]);
      }
      for (long long i = 0; i < in_block; ++i, ++progress.done) {
        split(data_line(progress));
        const std::size_t expected = parametric != 0 ? fields_.size() : 3;
        if (fields_.size() < 3 || fields_.size() != expected || fields_.size() > 6)
          cursor_.fail(fmt::format("expected the coordinates \"x y z\" of node {}, found {} fields",
                                   tag_text[static_cast<std::size_t>(i)], fields_.size()));
        // Errors about the tag itself point at its own line.
        const auto id = mesh_readers::parse_integer(tag_text[static_cast<std::size_t>(i)]);
        if (!id)
          throw InputError(cursor_.where(first_tag_line + static_cast<long>(i)),
                           fmt::format("expected a node tag (an integer), found {}",
                                       mesh_readers::quote_token(tag_text[static_cast<std::size_t>(i)])));
        add_node(*id, fields_[0], fields_[1], fields_[2]);
      }
    }
    if (progress.done != progress.total)
      cursor_.fail(fmt::format("the node blocks hold {} nodes but the $Nodes header (line {}) announces {}",
                               progress.done, start + 1, progress.total));
    expect_end("Nodes", start);
  }

  void read_elements_v2(long start) {
    SectionProgress progress{"Elements", start, "elements", 0, 0};
    progress.total = count_line(progress, "the number of elements");
    std::array<Index, 4> tet{};
    for (; progress.done < progress.total; ++progress.done) {
      split(data_line(progress));
      // elm-number elm-type number-of-tags tags... node-number-list
      if (fields_.size() < 3)
        cursor_.fail(fmt::format("expected \"elm-number elm-type number-of-tags tags... nodes...\", found {} fields",
                                 fields_.size()));
      const auto id = mesh_readers::to_integer(fields_[0], cursor_, "an element number");
      const auto type = mesh_readers::to_integer(fields_[1], cursor_, "an element type");
      const auto tag_count = mesh_readers::to_integer(fields_[2], cursor_, "the number of tags");
      const auto info = gmsh_element_type(type);
      if (!info)
        cursor_.fail(
            fmt::format("element {} has type {}, which mtled does not know: mtled reads 4-node tets "
                        "(type 4) beside points, lines and triangles",
                        id, type));
      // The count in the message is a double: 3 + a damaged tag count near the largest integer would overflow.
      if (tag_count < 0 ||
          fields_.size() != 3 + static_cast<std::size_t>(tag_count) + static_cast<std::size_t>(info->nodes))
        cursor_.fail(fmt::format("element {} ({} with {} tags) should have {} fields, found {}", id, info->name,
                                 tag_count, 3 + static_cast<double>(tag_count) + info->nodes, fields_.size()));
      // The first tag is the physical group (0: none), the second the elementary entity.
      const long long physical = tag_count >= 1 ? mesh_readers::to_integer(fields_[3], cursor_, "a physical tag") : 0;
      const std::size_t first_node = 3 + static_cast<std::size_t>(tag_count);
      if (info->dimension == 3) {
        if (type != kTetType) cursor_.fail(volume_element_advice(type));
        for (int k = 0; k < 4; ++k)
          tet[static_cast<std::size_t>(k)] = node_index(fields_[first_node + static_cast<std::size_t>(k)], id);
        add_tet_v2(tet, physical);
      } else if (physical != 0) {
        auto& nodes = group_nodes_[{info->dimension, physical}];
        for (int k = 0; k < info->nodes; ++k)
          nodes.push_back(node_index(fields_[first_node + static_cast<std::size_t>(k)], id));
      }
    }
    expect_end("Elements", start);
  }

  void read_elements_v4(long start) {
    SectionProgress progress{"Elements", start, "elements", 0, 0};
    const std::string_view header = data_line(progress);
    split(header);
    if (fields_.size() != 4)
      cursor_.fail(fmt::format("expected \"numEntityBlocks numElements minElementTag maxElementTag\", found {}",
                               mesh_readers::quote_token(header)));
    const auto blocks = mesh_readers::to_integer(fields_[0], cursor_, "the number of entity blocks");
    progress.total = mesh_readers::to_integer(fields_[1], cursor_, "the number of elements");
    if (blocks < 0 || progress.total < 0) cursor_.fail("negative counts in the $Elements header");
    std::array<Index, 4> tet{};
    for (long long b = 0; b < blocks; ++b) {
      split(data_line(progress));
      if (fields_.size() != 4)
        cursor_.fail(
            fmt::format("expected an element block header \"entityDim entityTag elementType "
                        "numElementsInBlock\", found {} fields",
                        fields_.size()));
      const auto dimension = mesh_readers::to_integer(fields_[0], cursor_, "the entity dimension");
      const auto entity = mesh_readers::to_integer(fields_[1], cursor_, "the entity tag");
      const auto type = mesh_readers::to_integer(fields_[2], cursor_, "the element type");
      const auto in_block = mesh_readers::to_integer(fields_[3], cursor_, "the number of elements in the block");
      if (dimension < 0 || dimension > 3)
        cursor_.fail(fmt::format("entity dimension {} is not 0, 1, 2 or 3", dimension));
      if (in_block < 0 || in_block > progress.total - progress.done)  // not summed: see read_nodes_v4
        cursor_.fail(fmt::format("the element blocks hold more elements than the $Elements header announces ({})",
                                 progress.total));
      const auto info = gmsh_element_type(type);
      if (dimension == 3 && type != kTetType) cursor_.fail(volume_element_advice(type));
      const std::vector<long long>* physicals = entity_physicals(static_cast<int>(dimension), entity);
      long long tet_physical = 0;
      if (dimension == 3 && physicals != nullptr && !physicals->empty()) {
        if (physicals->size() > 1)
          cursor_.fail(
              fmt::format("volume {} belongs to {} physical groups ({}): a tet belongs to one region; keep "
                          "the volume in one Physical Volume",
                          entity, physicals->size(), group_list(3, *physicals)));
        tet_physical = physicals->front();
      }
      for (long long i = 0; i < in_block; ++i, ++progress.done) {
        const std::string_view line = data_line(progress);
        if (dimension < 3 && (physicals == nullptr || physicals->empty())) continue;  // in no group: not needed
        split(line);
        if (fields_.empty()) cursor_.fail("expected \"elementTag nodeTags...\", found an empty line");
        const auto id = mesh_readers::to_integer(fields_[0], cursor_, "an element tag");
        if (info && fields_.size() != 1 + static_cast<std::size_t>(info->nodes))
          cursor_.fail(fmt::format("element {} ({}) should list {} nodes, found {}", id, info->name, info->nodes,
                                   fields_.size() - 1));
        if (dimension == 3) {
          for (std::size_t k = 0; k < 4; ++k) tet[k] = node_index(fields_[1 + k], id);
          mesh_.tets.push_back(tet);
          tet_physical_.push_back(tet_physical);
        } else {
          for (long long physical : *physicals) {
            auto& nodes = group_nodes_[{static_cast<int>(dimension), physical}];
            for (std::size_t k = 1; k < fields_.size(); ++k) nodes.push_back(node_index(fields_[k], id));
          }
        }
      }
    }
    if (progress.done != progress.total)
      cursor_.fail(fmt::format("the element blocks hold {} elements but the $Elements header (line {}) announces {}",
                               progress.done, start + 1, progress.total));
    expect_end("Elements", start);
  }

  TetMesh finish() {
    if (!have_nodes_ || !have_elements_)
      throw InputError(cursor_.label(), fmt::format("the file has no ${} section: it holds no mesh (only geometry?) or "
                                                    "is truncated; mesh it with `gmsh -3` and save again",
                                                    have_nodes_ ? "Elements" : "Nodes"));
    if (mesh_.tets.empty())
      throw InputError(cursor_.label(),
                       "the file has no 4-node tetrahedra (element type 4): mtled needs a volume "
                       "mesh; mesh the volumes with `gmsh -3` and save again");
    msh::assign_physical_regions(mesh_, tet_physical_, [this](long long tag) { return group_name(3, tag); },
                                 cursor_.label());
    for (auto& [key, nodes] : group_nodes_) {
      auto& set = mesh_.node_sets[group_name(key.first, key.second)];
      set.insert(set.end(), nodes.begin(), nodes.end());
    }
    return std::move(mesh_);
  }

  // --- helpers ---

  void split(std::string_view line) { mesh_readers::split_whitespace(line, fields_); }

  // The next data line of a section; the file ending, or a "$" line, before the section's items are all
  // read means a truncated file or a wrong count.
  std::string_view data_line(const SectionProgress& progress) {
    const auto line = cursor_.next_line();
    if (!line)
      cursor_.fail(
          fmt::format("the file ends inside the ${} section that starts on line {}{}: it is truncated; "
                      "export the mesh again",
                      progress.section, progress.start_line, progress_text(progress)));
    if (!line->empty() && line->front() == '$')
      cursor_.fail(
          fmt::format("the ${} section that starts on line {} ends{}: a count in it is wrong or lines are "
                      "missing; export the mesh again",
                      progress.section, progress.start_line, progress_text(progress)));
    return *line;
  }

  static std::string progress_text(const SectionProgress& progress) {
    if (progress.total <= 0) return {};
    return fmt::format(" after {} of {} {}", progress.done, progress.total, progress.items);
  }

  long long count_line(const SectionProgress& progress, std::string_view what) {
    const std::string_view line = data_line(progress);
    split(line);
    if (fields_.size() != 1) cursor_.fail(fmt::format("expected {}, found {}", what, mesh_readers::quote_token(line)));
    const auto count = mesh_readers::to_integer(fields_[0], cursor_, what);
    if (count < 0) cursor_.fail(fmt::format("{} cannot be negative", what));
    return count;
  }

  void expect_end(std::string_view section, long start) {
    const std::string end = fmt::format("$End{}", section);
    while (const auto line = cursor_.next_line()) {
      const auto text = mesh_readers::trim(*line);
      if (text.empty()) continue;
      if (text == end) return;
      cursor_.fail(
          fmt::format("expected {} (closing the section that starts on line {}), found {}: a count in the "
                      "section is wrong or the file is damaged",
                      end, start, mesh_readers::quote_token(text)));
    }
    cursor_.fail(
        fmt::format("the file ends before {} (the section starts on line {}): it is truncated; export the "
                    "mesh again",
                    end, start));
  }

  void skip_section(std::string_view name, long start) {
    const std::string end = fmt::format("$End{}", name);
    while (const auto line = cursor_.next_line())
      if (mesh_readers::trim(*line) == end) return;
    cursor_.fail(
        fmt::format("the file ends before {} (the section starts on line {}): it is truncated; export the "
                    "mesh again",
                    end, start));
  }

  void reserve_nodes(long long count) {
    const std::size_t n = cursor_.reservable(count, 8);  // "1 0 0 0\n": a node takes 8 bytes at least
    node_ids_.reserve(n);
    mesh_.points.reserve(n);
  }

  void add_node(std::string_view id_text, std::string_view x, std::string_view y, std::string_view z) {
    add_node(mesh_readers::to_integer(id_text, cursor_, "a node number"), x, y, z);
  }

  void add_node(long long id, std::string_view x, std::string_view y, std::string_view z) {
    node_ids_.add(id, cursor_);
    mesh_.points.emplace_back(mesh_readers::to_real(x, cursor_, "the x coordinate"),
                              mesh_readers::to_real(y, cursor_, "the y coordinate"),
                              mesh_readers::to_real(z, cursor_, "the z coordinate"));
  }

  Index node_index(std::string_view text, long long element) {
    const auto id = mesh_readers::to_integer(text, cursor_, "a node number");
    const auto index = node_ids_.find(id);
    if (!index)
      cursor_.fail(
          fmt::format("element {} refers to node {}, which $Nodes does not define: the file is damaged; "
                      "export the mesh again",
                      element, id));
    return *index;
  }

  // MSH 2.2 writes an element once per physical group it belongs to: a tet listed twice would double its mass.
  void add_tet_v2(const std::array<Index, 4>& tet, long long physical) {
    std::array<Index, 4> key = tet;
    std::sort(key.begin(), key.end());
    const auto [it, added] = first_tet_line_.emplace(key, cursor_.line());
    if (!added)
      cursor_.fail(
          fmt::format("this tet repeats the tet of line {} (MSH 2.2 writes an element once per physical "
                      "group): a tet belongs to one region; keep each volume in one Physical Volume",
                      it->second));
    mesh_.tets.push_back(tet);
    tet_physical_.push_back(physical);
  }

  const std::vector<long long>* entity_physicals(int dimension, long long entity) const {
    const auto it = entity_groups_.find({dimension, entity});
    return it == entity_groups_.end() ? nullptr : &it->second.physical_tags;
  }

  std::string group_name(int dimension, long long tag) const {
    const auto it = physical_names_.find({dimension, tag});
    return it != physical_names_.end() ? it->second : std::to_string(tag);
  }

  std::string group_list(int dimension, const std::vector<long long>& tags) const {
    std::vector<std::string> names;
    for (long long tag : tags) names.push_back("\"" + group_name(dimension, tag) + "\"");
    return mesh_readers::list_names(names);
  }

  struct EntityGroups {
    std::vector<long long> physical_tags;
    long line = 0;
  };
  struct TetKeyHash {
    std::size_t operator()(const std::array<Index, 4>& k) const {
      std::size_t h = 0;
      for (Index v : k) h = h * 1000003u ^ static_cast<std::size_t>(v);
      return h;
    }
  };

  TextCursor cursor_;
  int version_ = 0;
  bool have_nodes_ = false;
  bool have_elements_ = false;
  std::vector<std::string_view> fields_;
  std::map<std::pair<int, long long>, std::string> physical_names_;  // (dimension, tag) -> name
  std::map<std::pair<int, long long>, EntityGroups> entity_groups_;  // (dimension, entity tag) -> groups (MSH 4.1)
  mesh_readers::NodeIds node_ids_;
  TetMesh mesh_;
  std::vector<long long> tet_physical_;                                        // per tet; 0: in no physical volume
  std::map<std::pair<int, long long>, std::vector<Index>> group_nodes_;        // (dimension < 3, physical tag) -> nodes
  std::unordered_map<std::array<Index, 4>, long, TetKeyHash> first_tet_line_;  // MSH 2.2 only
};

}  // namespace

namespace msh {

std::string volume_element_advice(long long type) {
  const auto info = gmsh_element_type(type);
  const std::string name = info ? info->name : "volume element";
  if (type == 11 || type == 29 || type == 30 || type == 31)
    return fmt::format(
        "element type {} ({}): mtled needs linear 4-node tets (type 4); mesh with `gmsh -3 -order 1` "
        "(Mesh.ElementOrder = 1) and save again",
        type, name);
  return fmt::format(
      "element type {} ({}): mtled needs a tet-only mesh (4-node tets, type 4); remove the "
      "Recombine / Transfinite settings that make hexahedra, prisms or pyramids and mesh with `gmsh -3`",
      type, name);
}

void assign_physical_regions(TetMesh& mesh, std::span<const long long> tet_physical,
                             const std::function<std::string(long long)>& name_of, const std::string& label) {
  std::set<long long> tags(tet_physical.begin(), tet_physical.end());
  const bool unassigned = tags.erase(0) > 0;
  if (tags.empty()) return;
  std::map<long long, Index> region_of_tag;
  for (long long tag : tags) {
    region_of_tag[tag] = static_cast<Index>(mesh.region_names.size());
    mesh.region_names.push_back(name_of(tag));
  }
  const auto unassigned_region = static_cast<Index>(mesh.region_names.size());
  std::size_t unassigned_count = 0;
  mesh.tet_region.resize(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (tet_physical[t] == 0) {
      mesh.tet_region[t] = unassigned_region;
      ++unassigned_count;
    } else {
      mesh.tet_region[t] = region_of_tag[tet_physical[t]];
    }
  }
  if (unassigned) {
    mesh.region_names.push_back("unassigned");
    log().warn(
        "{}: {} of {} tets belong to no physical volume; they form the region \"unassigned\" (add their "
        "volumes to a Physical Volume to name it)",
        label, unassigned_count, mesh.tets.size());
  }
}

bool is_binary(std::string_view text) {
  const auto at = text.find("$MeshFormat");
  if (at == std::string_view::npos) return false;
  const auto line_start = text.find('\n', at);
  if (line_start == std::string_view::npos) return false;
  std::vector<std::string_view> fields;
  mesh_readers::split_whitespace(text.substr(line_start + 1, text.find('\n', line_start + 1) - line_start - 1), fields);
  return fields.size() >= 2 && fields[1] == "1";
}

}  // namespace msh

class GmshFileReader final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Reads a Gmsh .msh file of 4-node tets: ASCII MSH 2.2 and 4.1 with mtled's own parser (every complaint "
        "names the file and line), binary ones (Gmsh's -bin) and other versions through Gmsh's own reader. "
        "Physical volumes become regions (named "
        "by $PhysicalNames, else by their number; \"all\" when there are none; tets in no physical volume form "
        "\"unassigned\"); physical surfaces, curves and points become node sets holding the nodes of their "
        "elements. The example reads the fixture tests/data/meshes/cube_gmsh41.msh (a path from the source "
        "tree's root).");
    mesh_readers::declare_file_parameters(d, "Gmsh .msh, ASCII or binary");
    d.string("reader")
        .defaults("auto")
        .choices({"auto", "gmsh"})
        .doc(
            "\"auto\": ASCII MSH 2.2 and 4.1 through mtled's parser, binary files through Gmsh's reader (libgmsh); "
            "\"gmsh\": every file through Gmsh's reader (MSH 1, 2.x, 4.0, 4.1), whose messages name no line")
        .to<&Settings::reader>();
    d.example({{"path", "tests/data/meshes/cube_gmsh41.msh"}, {"scale", 1.0}});
  }

  explicit GmshFileReader(const Parameters& parameters) : parameters_(parameters) {}

  TetMesh load(const MeshContext& context) override {
    const auto file = mesh_readers::read_mesh_file(parameters_, context);
    TetMesh mesh = through_gmsh(file) ? read_with_gmsh(file) : MshParser(file).parse();
    mesh_readers::finish_mesh(mesh, parameters_.read<mesh_readers::FileSettings>().scale, file.label);
    return mesh;
  }

 private:
  struct Settings {
    std::string reader;
  };
  bool through_gmsh(const MeshFileText& file) const {
    return parameters_.read<Settings>().reader == "gmsh" || (kWithGmsh && msh::is_binary(file.text));
  }

  TetMesh read_with_gmsh(const MeshFileText& file) const {
#ifdef MTLED_WITH_GMSH
    return msh::read_with_gmsh(file);
#else
    throw InputError(parameters_.pointer("reader"),
                     fmt::format("{}: this mtled was built without Gmsh (MTLED_WITH_GMSH=OFF), so only ASCII MSH 2.2 "
                                 "and 4.1 files are read; convert the file with `gmsh mesh.msh -save -format msh41 -o "
                                 "mesh41.msh`",
                                 file.label));
#endif
  }

#ifdef MTLED_WITH_GMSH
  static constexpr bool kWithGmsh = true;
#else
  static constexpr bool kWithGmsh = false;
#endif
  Parameters parameters_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::GmshFileReader)
