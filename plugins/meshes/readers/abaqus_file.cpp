// Abaqus input (.inp) reader for meshes of 4-node tets (C3D4): *NODE, *ELEMENT, *NSET, *ELSET (with
// GENERATE and set names in data lines), *SOLID SECTION (which element sets carry material), *INCLUDE and
// the flat single-part *PART / *ASSEMBLY / *INSTANCE layout that Abaqus/CAE writes. Keywords, options and
// set names are case-insensitive, as in Abaqus; everything else (materials, steps, ...) is skipped.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/io/mesh_file.hpp"
#include "mtled/io/text_cursor.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {

using mesh_readers::quote_token;
using mesh_readers::TextCursor;
using mesh_readers::uppercase;

constexpr int kMaxIncludeDepth = 16;
constexpr long long kMaxGenerated = 20'000'000;  // a GENERATE range that large is a typo, not a mesh

// Element types by name (Abaqus Elements Guide). 4-node tets in any variant (hybrid, coupled temperature)
// share the geometry mtled uses.
enum class ElementKind { tet, quadratic_tet, other_volume, not_volume, unknown };

bool starts_with_any(std::string_view type, std::initializer_list<std::string_view> prefixes) {
  for (std::string_view prefix : prefixes)
    if (type.substr(0, prefix.size()) == prefix) return true;
  return false;
}

ElementKind element_kind(std::string_view type) {
  if (type.substr(0, 4) == "C3D4" && type.find_first_not_of("HTEP", 4) == std::string_view::npos)
    return ElementKind::tet;
  if (type.substr(0, 5) == "C3D10") return ElementKind::quadratic_tet;
  if (starts_with_any(type, {"C3D", "DC3D", "AC3D", "SC6", "SC8", "COH3D", "GK3D", "EC3D", "Q3D", "CCL"}))
    return ElementKind::other_volume;
  if (starts_with_any(
          type, {"CPS",    "CPE",     "CAX",  "CGAX",  "M3D",   "SFM3D",  "SFMAX",  "SFMGAX",   "R3D",   "R2D",
                 "RAX",    "T2D",     "T3D",  "B2",    "B3",    "PIPE",   "S3",     "S4",       "S8",    "S9",
                 "STRI",   "SAX",     "DS",   "DC1D",  "DC2D",  "DCAX",   "F2D",    "F3D",      "MASS",  "ROTARYI",
                 "SPRING", "DASHPOT", "CONN", "ELBOW", "FRAME", "GAPUNI", "GAPCYL", "GAPSPHER", "JOINT", "ITS",
                 "DRAG",   "ACIN",    "ASI",  "WARP",  "MAX",   "MGAX"}))
    return ElementKind::not_volume;
  return ElementKind::unknown;
}

// A place in one of the files read (the main file or an *INCLUDE).
struct Place {
  int file = 0;
  long line = 0;
};

struct Keyword {
  std::string name;                                          // upper case, blanks removed: "SOLIDSECTION"
  std::vector<std::pair<std::string, std::string>> options;  // (upper-case key, value as written)
  Place place;

  std::optional<std::string> option(std::string_view key) const {
    for (const auto& [k, v] : options)
      if (k == key) return v;
    return std::nullopt;
  }
  bool flag(std::string_view key) const { return option(key).has_value(); }
};

struct Member {
  long long id;
  Place place;
};

struct NamedSet {
  std::string name;  // as first written
  std::vector<Member> members;
  Place place;  // first definition
};

struct Element {
  long long id;
  std::size_t first_node;  // into element_nodes_
  int node_count;
  bool tet;
  Place place;
};

class InpParser {
 public:
  InpParser(const mesh_readers::MeshFileText& file) { open(file); }

  TetMesh parse(const std::vector<std::string>& region_sets, const std::string& region_pointer) {
    while (const auto keyword = next_keyword()) handle(*keyword);
    return build(region_sets, region_pointer);
  }

 private:
  // --- lines ---

  struct Source {
    std::unique_ptr<mesh_readers::MeshFileText> file;
    std::unique_ptr<TextCursor> cursor;
  };

  void open(const mesh_readers::MeshFileText& file) {
    auto text = std::make_unique<mesh_readers::MeshFileText>(file);
    auto cursor = std::make_unique<TextCursor>(text->text, text->label);
    sources_.push_back({std::move(text), std::move(cursor)});
    open_.push_back(static_cast<int>(sources_.size()) - 1);
  }

  // The file of the last line read, and that line.
  TextCursor& cursor() { return *sources_[static_cast<std::size_t>(current_)].cursor; }
  Place here() { return {current_, cursor().line()}; }
  std::string where(const Place& place) const {
    return sources_[static_cast<std::size_t>(place.file)].cursor->where(place.line);
  }
  [[noreturn]] void fail(const Place& place, const std::string& message) const {
    throw InputError(where(place), message);
  }
  [[noreturn]] void fail_here(const std::string& message) { fail(here(), message); }

  // The next line that is not blank and not a "**" comment, from the innermost open file. With `same_file`,
  // nothing at the end of that file rather than the next line of the file that included it.
  std::optional<std::string_view> next_raw_line(bool same_file = false) {
    while (!open_.empty()) {
      TextCursor& innermost = *sources_[static_cast<std::size_t>(open_.back())].cursor;
      while (const auto line = innermost.next_line()) {
        const auto text = mesh_readers::trim(*line);
        if (text.empty() || text.substr(0, 2) == "**") continue;
        current_ = open_.back();
        return text;
      }
      if (same_file) return std::nullopt;
      open_.pop_back();
    }
    return std::nullopt;
  }

  std::optional<std::string_view> peek_data_line() {
    if (!pending_) pending_ = next_raw_line();
    if (pending_ && !pending_->empty() && pending_->front() == '*') return std::nullopt;
    return pending_;
  }

  // The next data line of the current keyword, or nothing at the next keyword or the end.
  std::optional<std::string_view> next_data_line() {
    const auto line = peek_data_line();
    if (line) pending_.reset();
    return line;
  }

  std::optional<Keyword> next_keyword() {
    while (true) {
      if (!pending_) pending_ = next_raw_line();
      if (!pending_) return std::nullopt;
      const std::string_view line = *pending_;
      pending_.reset();
      if (line.front() == '*') return parse_keyword(line);
      // Data lines of a skipped keyword.
    }
  }

  Keyword parse_keyword(std::string_view first) {
    Keyword keyword;
    keyword.place = here();
    std::string text(first.substr(1));
    // A keyword line ending with a comma continues on the next line of its file. (Going on in the including
    // file closed this one, so "*INCLUDE, INPUT=self.inp," at its end included itself forever: found by
    // tests/fuzz.)
    while (!mesh_readers::trim(text).empty() && mesh_readers::trim(text).back() == ',') {
      const auto more = next_raw_line(true);
      if (!more) break;
      text += *more;
    }
    std::vector<std::string_view> fields;
    mesh_readers::split_commas(text, fields);
    if (fields.empty() || fields.front().empty()) fail(keyword.place, "a \"*\" line without a keyword");
    for (char c : fields.front())
      if (c != ' ' && c != '\t') keyword.name += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    for (std::size_t i = 1; i < fields.size(); ++i) {
      if (fields[i].empty()) continue;
      const auto equals = fields[i].find('=');
      std::string key = uppercase(mesh_readers::trim(fields[i].substr(0, equals)));
      std::erase(key, ' ');
      std::string value;
      if (equals != std::string_view::npos) {
        std::string_view v = mesh_readers::trim(fields[i].substr(equals + 1));
        if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
        value = std::string(v);
      }
      keyword.options.emplace_back(std::move(key), std::move(value));
    }
    return keyword;
  }

  std::string required_option(const Keyword& keyword, std::string_view key, std::string_view example) {
    const auto value = keyword.option(key);
    if (!value || value->empty())
      fail(keyword.place, fmt::format("*{} needs {}= (for example \"{}\")", keyword.name, key, example));
    return *value;
  }

  // --- keywords ---

  void handle(const Keyword& keyword) {
    const std::string& k = keyword.name;
    last_keyword_ = {"*" + k, keyword.place};
    if (k == "NODE")
      read_nodes(keyword);
    else if (k == "ELEMENT")
      read_elements(keyword);
    else if (k == "NSET")
      read_set(keyword, node_sets_, true);
    else if (k == "ELSET")
      read_set(keyword, element_sets_, false);
    else if (k == "SOLIDSECTION")
      add_section(keyword);
    else if (k == "PART")
      start_part(keyword);
    else if (k == "ASSEMBLY")
      in_assembly_ = true;
    else if (k == "ENDASSEMBLY")
      in_assembly_ = false;
    else if (k == "INSTANCE")
      start_instance(keyword);
    else if (k == "ENDINSTANCE")
      in_instance_ = false;
    else if (k == "INCLUDE")
      include(keyword);
    else if (k == "SYSTEM")
      fail(keyword.place,
           "*SYSTEM (a local coordinate system for the nodes that follow) is not supported: write the "
           "nodes in global coordinates");
    // Everything else (*HEADING, *MATERIAL, *STEP, *BOUNDARY, ...) does not describe the mesh.
  }

  void add_section(const Keyword& keyword) {
    section_sets_.emplace_back(required_option(keyword, "ELSET", "*SOLID SECTION, ELSET=tissue, MATERIAL=tissue"),
                               keyword.place);
  }

  // Nodes and sets of the assembly outside an instance are reference points and their sets: not mesh.
  bool at_assembly_level() const { return in_assembly_ && !in_instance_; }

  void read_nodes(const Keyword& keyword) {
    if (keyword.option("INPUT"))
      fail(keyword.place, "*NODE, INPUT= is not supported: put the nodes in the file, or use *INCLUDE, INPUT=");
    if (const auto system = keyword.option("SYSTEM"); system && uppercase(*system) != "R")
      fail(keyword.place, fmt::format("*NODE, SYSTEM={} is not supported: write the nodes in rectangular (R) "
                                      "coordinates",
                                      *system));
    const bool skip = at_assembly_level();
    if (skip)
      log().warn("{}: *NODE in the assembly, outside any instance (reference points): ignored", where(keyword.place));
    NamedSet* set = nullptr;
    if (const auto name = keyword.option("NSET"); name && !skip) set = &named_set(node_sets_, *name, keyword.place);
    while (const auto line = next_data_line()) {
      if (skip) continue;
      mesh_readers::split_commas(*line, fields_);
      if (fields_.size() < 4)
        fail_here(fmt::format("a *NODE line needs \"id, x, y, z\", found {}", quote_token(*line)));
      const auto id = mesh_readers::to_integer(fields_[0], cursor(), "a node id");
      node_ids_.add(id, cursor());
      points_.emplace_back(mesh_readers::to_real(fields_[1], cursor(), "the x coordinate"),
                           mesh_readers::to_real(fields_[2], cursor(), "the y coordinate"),
                           mesh_readers::to_real(fields_[3], cursor(), "the z coordinate"));
      if (set != nullptr) set->members.push_back({id, here()});
    }
  }

  void read_elements(const Keyword& keyword) {
    if (keyword.option("INPUT"))
      fail(keyword.place, "*ELEMENT, INPUT= is not supported: put the elements in the file, or use *INCLUDE, INPUT=");
    const std::string type = uppercase(required_option(keyword, "TYPE", "*ELEMENT, TYPE=C3D4, ELSET=tissue"));
    const ElementKind kind = element_kind(type);
    switch (kind) {
      case ElementKind::tet:
      case ElementKind::not_volume:
        break;
      case ElementKind::quadratic_tet:
        fail(keyword.place, fmt::format("element type {} (10-node tet): mtled needs linear 4-node tets (C3D4); mesh "
                                        "with linear tets (Abaqus/CAE: Mesh > Element Type, Geometric Order Linear; "
                                        "Gmsh: -order 1)",
                                        type));
      case ElementKind::other_volume:
        fail(keyword.place, fmt::format("element type {}: mtled needs a mesh of 4-node tets (C3D4); mesh the part "
                                        "with tets only (Abaqus/CAE: Mesh Controls, Element Shape Tet)",
                                        type));
      case ElementKind::unknown:
        fail(keyword.place, fmt::format("element type {} is not supported: mtled reads 4-node tets (C3D4) and skips "
                                        "surface and line elements (such as S3, CPS3, T3D2)",
                                        type));
    }
    const bool tet = kind == ElementKind::tet;
    if (!tet) log().debug("{}: elements of type {} are not solids: ignored", where(keyword.place), type);
    NamedSet* set = nullptr;
    if (const auto name = keyword.option("ELSET")) {
      set = &named_set(element_sets_, *name, keyword.place);
      if (tet) element_region_sets_.emplace(uppercase(*name), keyword.place);
    }
    while (const auto line = next_data_line()) {
      // An element's nodes may go on over lines that end with a comma.
      mesh_readers::split_commas(*line, fields_);
      record_.assign(fields_.begin(), fields_.end());
      const Place place = here();
      std::string_view last = *line;
      while (last.back() == ',' && (!tet || record_.size() < 5)) {
        const auto more = next_data_line();
        if (!more) break;
        mesh_readers::split_commas(*more, fields_);
        record_.insert(record_.end(), fields_.begin(), fields_.end());
        last = *more;
      }
      if (tet && record_.size() != 5)
        fail(place, fmt::format("a {} element needs \"id, n1, n2, n3, n4\", found {} fields", type, record_.size()));
      if (record_.size() < 2) fail(place, "an element needs an id and its nodes");
      Element element{mesh_readers::to_integer(record_[0], cursor(), "an element id"), element_nodes_.size(),
                      static_cast<int>(record_.size() - 1), tet, place};
      for (std::size_t k = 1; k < record_.size(); ++k)
        element_nodes_.push_back(mesh_readers::to_integer(record_[k], cursor(), "a node id"));
      const auto [it, added] = element_index_.emplace(element.id, elements_.size());
      if (!added)
        fail(place, fmt::format("element {} is defined twice (first at {}): element ids must be unique; remove or "
                                "renumber one",
                                element.id, where(elements_[it->second].place)));
      elements_.push_back(element);
      if (set != nullptr) set->members.push_back({element.id, place});
    }
  }

  // *NSET / *ELSET: ids, names of sets defined before, or GENERATE ranges "first, last[, step]".
  void read_set(const Keyword& keyword, std::map<std::string, NamedSet>& sets, bool nodes) {
    const std::string key = nodes ? "NSET" : "ELSET";
    const std::string name = required_option(keyword, key, nodes ? "*NSET, NSET=fixed" : "*ELSET, ELSET=tissue");
    if (const auto instance = keyword.option("INSTANCE"); instance && !same_name(*instance, instance_name_))
      fail(keyword.place, fmt::format("*{} refers to instance \"{}\", but the instance is \"{}\"", keyword.name,
                                      *instance, instance_name_));
    if (at_assembly_level() && !keyword.option("INSTANCE")) {
      log().debug("{}: *{} in the assembly without INSTANCE= refers to assembly nodes: ignored", where(keyword.place),
                  keyword.name);
      while (next_data_line()) {
      }
      return;
    }
    NamedSet& set = named_set(sets, name, keyword.place);
    const bool generate = keyword.flag("GENERATE");
    // *NSET, NSET=a, ELSET=b: the nodes of the elements of set b.
    if (nodes) {
      if (const auto from = keyword.option("ELSET")) {
        append_element_set_nodes(set, *from, keyword.place);
        return;
      }
    }
    while (const auto line = next_data_line()) {
      mesh_readers::split_commas(*line, fields_);
      const Place place = here();
      if (generate) {
        if (fields_.size() < 2 || fields_.size() > 3)
          fail(place, fmt::format("a GENERATE line needs \"first, last[, increment]\", found {}", quote_token(*line)));
        const auto first = mesh_readers::to_integer(fields_[0], cursor(), "the first id");
        const auto last = mesh_readers::to_integer(fields_[1], cursor(), "the last id");
        const auto step = fields_.size() == 3 ? mesh_readers::to_integer(fields_[2], cursor(), "the increment") : 1;
        // In unsigned arithmetic (which wraps, where signed overflow is undefined): ids near the ends of the
        // integer range overflowed `last - first` and `id += step` (a range from the least to the largest
        // integer passed the size check and allocated until std::bad_alloc). Every id is within [first, last].
        const auto start = static_cast<unsigned long long>(first), increment = static_cast<unsigned long long>(step);
        const unsigned long long steps =
            step <= 0 || last < first ? 0 : (static_cast<unsigned long long>(last) - start) / increment;
        if (step <= 0 || last < first || steps >= static_cast<unsigned long long>(kMaxGenerated))
          fail(place, fmt::format("GENERATE {}, {}, {} is not a range (first <= last, increment > 0, fewer than {} "
                                  "ids)",
                                  first, last, step, kMaxGenerated));
        for (unsigned long long i = 0; i <= steps; ++i)
          set.members.push_back({static_cast<long long>(start + i * increment), place});
        continue;
      }
      for (const auto field : fields_) {
        if (field.empty()) fail(place, "an empty entry between two commas");
        if (const auto id = mesh_readers::parse_integer(field)) {
          set.members.push_back({*id, place});
          continue;
        }
        // A set name: its members join this set.
        const std::string other = strip_instance(field);
        const auto it = sets.find(uppercase(other));
        if (it == sets.end())
          fail(place, fmt::format("{} is neither an id nor a {} set defined above", quote_token(field),
                                  nodes ? "node" : "element"));
        // A set named in itself adds nothing, but copying it doubled the set with each mention: "a, a, a, ..."
        // exhausted the memory. Sets that name each other can still grow so: they are stopped at a size no
        // mesh needs.
        if (&it->second == &set) continue;
        if (set.members.size() + it->second.members.size() > static_cast<std::size_t>(kMaxGenerated))
          fail(place, fmt::format("set \"{}\" grows past {} members: do sets name each other again and again?", name,
                                  kMaxGenerated));
        set.members.insert(set.members.end(), it->second.members.begin(), it->second.members.end());
      }
    }
  }

  void append_element_set_nodes(NamedSet& set, const std::string& element_set, const Place& place) {
    const auto it = element_sets_.find(uppercase(strip_instance(element_set)));
    if (it == element_sets_.end())
      fail(place, fmt::format("element set \"{}\" is not defined above this line", element_set));
    for (const auto& member : it->second.members) {
      const auto e = element_index_.find(member.id);
      if (e == element_index_.end())
        fail(member.place,
             fmt::format("element set \"{}\" lists element {}, which no *ELEMENT defines", it->second.name, member.id));
      const Element& element = elements_[e->second];
      for (int k = 0; k < element.node_count; ++k)
        set.members.push_back({element_nodes_[element.first_node + static_cast<std::size_t>(k)], place});
    }
  }

  NamedSet& named_set(std::map<std::string, NamedSet>& sets, const std::string& name, const Place& place) {
    const std::string key = uppercase(strip_instance(name));
    auto it = sets.find(key);
    if (it == sets.end()) it = sets.emplace(key, NamedSet{strip_instance(name), {}, place}).first;
    return it->second;
  }

  // "Part-1-1.Set-1" at assembly level names the set of the (single) instance.
  std::string strip_instance(std::string_view name) const {
    const auto dot = name.find('.');
    if (dot != std::string_view::npos && !instance_name_.empty() && same_name(name.substr(0, dot), instance_name_))
      return std::string(name.substr(dot + 1));
    return std::string(name);
  }

  static bool same_name(std::string_view a, std::string_view b) { return uppercase(a) == uppercase(b); }

  void start_part(const Keyword& keyword) {
    const std::string name = required_option(keyword, "NAME", "*PART, NAME=tissue");
    if (!part_name_.empty())
      fail(keyword.place, fmt::format("a second part (\"{}\" after \"{}\"): mtled reads one part; merge the parts "
                                      "(Abaqus/CAE: Merge/Cut Instances) or write a flat input file without *PART",
                                      name, part_name_));
    part_name_ = name;
  }

  void start_instance(const Keyword& keyword) {
    const std::string name = required_option(keyword, "NAME", "*INSTANCE, NAME=tissue-1, PART=tissue");
    if (!instance_name_.empty())
      fail(keyword.place, fmt::format("a second *INSTANCE (\"{}\" after \"{}\"): mtled reads a single part instance; "
                                      "merge the instances into one part (Abaqus/CAE: Merge/Cut Instances) or write a "
                                      "flat input file without *PART and *INSTANCE",
                                      name, instance_name_));
    if (const auto part = keyword.option("PART"); part && !part_name_.empty() && !same_name(*part, part_name_))
      fail(keyword.place,
           fmt::format("instance \"{}\" is of part \"{}\", but the file defines part \"{}\"", name, *part, part_name_));
    instance_name_ = name;
    in_instance_ = true;
    // Optional data lines: a translation "dx, dy, dz", then a rotation "a, b, angle".
    if (const auto line = next_data_line()) {
      mesh_readers::split_commas(*line, fields_);
      if (fields_.size() != 3)
        fail_here(fmt::format("an *INSTANCE translation needs \"dx, dy, dz\", found {}", quote_token(*line)));
      for (int d = 0; d < 3; ++d)
        translation_[d] = mesh_readers::to_real(fields_[static_cast<std::size_t>(d)], cursor(), "a translation");
    }
    if (next_data_line())
      fail_here(
          "*INSTANCE with a rotation is not supported: position the part in its own coordinates, or write the "
          "instance without rotation");
  }

  void include(const Keyword& keyword) {
    const std::string input = required_option(keyword, "INPUT", "*INCLUDE, INPUT=mesh.inp");
    if (static_cast<int>(open_.size()) >= kMaxIncludeDepth)
      fail(keyword.place,
           fmt::format("*INCLUDE nested more than {} deep: does a file include itself?", kMaxIncludeDepth));
    const fs::path including = sources_[static_cast<std::size_t>(keyword.place.file)].file->path;
    fs::path target(input);
    if (target.is_relative()) target = including.parent_path() / target;
    pending_.reset();
    open(mesh_readers::read_text_file(target, where(keyword.place)));
  }

  // --- the mesh ---

  TetMesh build(const std::vector<std::string>& region_sets, const std::string& region_pointer) {
    TetMesh mesh;
    mesh.points = std::move(points_);
    std::vector<std::size_t> tet_elements;
    for (std::size_t e = 0; e < elements_.size(); ++e)
      if (elements_[e].tet) tet_elements.push_back(e);
    if (tet_elements.empty()) {
      const Place end{0, sources_.front().cursor->line()};
      std::string hint;
      if (last_keyword_.keyword == "*NODE" || last_keyword_.keyword == "*ELEMENT")
        hint = fmt::format("; the file ends in the {} block that starts on line {}: is it truncated?",
                           last_keyword_.keyword, last_keyword_.place.line);
      fail(end,
           fmt::format("the file has no C3D4 elements (4-node tets){}: mtled needs a tet mesh; export it again", hint));
    }
    for (const auto& element : elements_) {
      std::array<Index, 4> tet{};
      for (int k = 0; k < element.node_count; ++k) {
        const long long id = element_nodes_[element.first_node + static_cast<std::size_t>(k)];
        const auto index = node_ids_.find(id);
        if (!index)
          fail(element.place, fmt::format("element {} refers to node {}, which no *NODE defines: the file is damaged "
                                          "or incomplete; export it again",
                                          element.id, id));
        if (element.tet) tet[static_cast<std::size_t>(k)] = *index;
      }
      if (element.tet) mesh.tets.push_back(tet);
    }
    if (translation_ != Vec3::Zero())
      for (auto& p : mesh.points) p += translation_;
    assign_regions(mesh, tet_elements, region_sets, region_pointer);
    for (const auto& [key, set] : node_sets_) {
      auto& nodes = mesh.node_sets[set.name];
      for (const auto& member : set.members) {
        const auto index = node_ids_.find(member.id);
        if (!index)
          fail(member.place, fmt::format("node set \"{}\" lists node {}, which no *NODE defines", set.name, member.id));
        nodes.push_back(*index);
      }
    }
    return mesh;
  }

  // Regions: the element sets named in "regions"; else those of *SOLID SECTION; else those named on *ELEMENT
  // lines of tets. A tet in none of them is in "unassigned".
  void assign_regions(TetMesh& mesh, const std::vector<std::size_t>& tet_elements,
                      const std::vector<std::string>& region_sets, const std::string& region_pointer) {
    std::vector<std::pair<std::string, std::optional<Place>>> chosen;  // (upper-case key, where it was named)
    if (!region_sets.empty()) {
      for (const auto& name : region_sets) {
        const std::string key = uppercase(name);
        if (element_sets_.find(key) == element_sets_.end()) {
          std::vector<std::string> names;
          for (const auto& [k, set] : element_sets_) names.push_back(set.name);
          const auto hint = did_you_mean(name, names);
          throw InputError(
              region_pointer,
              fmt::format("{} has no element set \"{}\"; its element sets: {}{}{}", sources_.front().file->label, name,
                          mesh_readers::list_names(names), hint.empty() ? "" : "; ", hint));
        }
        chosen.emplace_back(key, std::nullopt);
      }
    } else if (!section_sets_.empty()) {
      for (const auto& [name, place] : section_sets_) {
        const std::string key = uppercase(strip_instance(name));
        if (element_sets_.find(key) == element_sets_.end())
          fail(place, fmt::format("*SOLID SECTION names element set \"{}\", which the file does not define", name));
        chosen.emplace_back(key, place);
      }
    } else {
      for (const auto& [key, place] : element_region_sets_) chosen.emplace_back(key, place);
      std::sort(chosen.begin(), chosen.end(), [](const auto& a, const auto& b) {
        return std::make_pair(a.second->file, a.second->line) < std::make_pair(b.second->file, b.second->line);
      });
    }
    if (chosen.empty()) return;  // finish_mesh: one region "all"

    std::unordered_map<long long, std::size_t> tet_of_element;
    for (std::size_t t = 0; t < tet_elements.size(); ++t) tet_of_element.emplace(elements_[tet_elements[t]].id, t);
    constexpr Index kNone = -1;
    mesh.tet_region.assign(mesh.tets.size(), kNone);
    for (const auto& [key, place] : chosen) {
      const NamedSet& set = element_sets_.at(key);
      if (std::find(mesh.region_names.begin(), mesh.region_names.end(), set.name) != mesh.region_names.end()) continue;
      const auto region = static_cast<Index>(mesh.region_names.size());
      mesh.region_names.push_back(set.name);
      for (const auto& member : set.members) {
        const auto it = tet_of_element.find(member.id);
        if (it == tet_of_element.end()) {
          if (element_index_.find(member.id) == element_index_.end())
            fail(member.place,
                 fmt::format("element set \"{}\" lists element {}, which no *ELEMENT defines", set.name, member.id));
          continue;  // a surface element in a region set: not a tet
        }
        Index& current = mesh.tet_region[it->second];
        if (current != kNone && current != region)
          fail(member.place, fmt::format("element {} is in element sets \"{}\" and \"{}\", which are both regions: a "
                                         "tet belongs to one region; {}",
                                         member.id, mesh.region_names[static_cast<std::size_t>(current)], set.name,
                                         region_sets.empty() ? "name the region sets with \"regions\""
                                                             : "list sets that do not overlap in \"regions\""));
        current = region;
      }
    }
    const auto count = static_cast<std::size_t>(std::count(mesh.tet_region.begin(), mesh.tet_region.end(), kNone));
    if (count > 0) {
      const auto unassigned = static_cast<Index>(mesh.region_names.size());
      mesh.region_names.push_back("unassigned");
      for (auto& r : mesh.tet_region)
        if (r == kNone) r = unassigned;
      log().warn("{}: {} of {} tets are in no region set; they form the region \"unassigned\"",
                 sources_.front().file->label, count, mesh.tets.size());
    }
  }

  struct Block {
    std::string keyword;
    Place place;
  };

  std::vector<Source> sources_;
  std::vector<int> open_;  // stack of sources being read
  int current_ = 0;        // the source of the last line read
  std::optional<std::string_view> pending_;
  std::vector<std::string_view> fields_, record_;
  Block last_keyword_;  // for "the file ends in the *NODE block ..."

  mesh_readers::NodeIds node_ids_;
  std::vector<Vec3> points_;
  std::vector<Element> elements_;
  std::vector<long long> element_nodes_;
  std::unordered_map<long long, std::size_t> element_index_;
  std::map<std::string, NamedSet> node_sets_, element_sets_;  // by upper-case name
  std::map<std::string, Place> element_region_sets_;          // ELSET= on *ELEMENT of tets, first place
  std::vector<std::pair<std::string, Place>> section_sets_;   // *SOLID SECTION, ELSET=

  std::string part_name_, instance_name_;
  bool in_assembly_ = false, in_instance_ = false;
  Vec3 translation_ = Vec3::Zero();
};

}  // namespace

class AbaqusFileReader final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Reads an Abaqus input file (.inp) of C3D4 tets: *NODE, *ELEMENT, *NSET and *ELSET (with GENERATE), "
        "*INCLUDE, and one *PART with one *INSTANCE. Element sets become regions (see \"regions\"); tets in "
        "none form \"unassigned\"; node sets (*NSET) become node sets. Surface and line elements are skipped; "
        "other solid elements are refused. The example reads the fixture tests/data/meshes/cube.inp (a path "
        "from the source tree's root).");
    mesh_readers::declare_file_parameters(d, "Abaqus .inp");
    d.string_list("regions")
        .defaults(json::array())
        .doc(
            "Element sets that become regions, in this order. Empty: the sets of the *SOLID SECTION lines, else "
            "the sets named by ELSET= on the *ELEMENT lines of the tets; no set at all gives one region \"all\". For "
            "Gmsh's .inp export, whose *ELEMENT sets are named after entities (Volume1), list the physical groups' "
            "sets here.")
        .to<&Settings::regions>();
    d.example({{"path", "tests/data/meshes/cube.inp"}, {"scale", 1.0}});
  }

  explicit AbaqusFileReader(const Parameters& parameters) : parameters_(parameters) {}

  TetMesh load(const MeshContext& context) override {
    const auto file = mesh_readers::read_mesh_file(parameters_, context);
    TetMesh mesh = InpParser(file).parse(parameters_.read<Settings>().regions, parameters_.pointer("regions"));
    mesh_readers::finish_mesh(mesh, parameters_.read<mesh_readers::FileSettings>().scale, file.label);
    return mesh;
  }

 private:
  struct Settings {
    std::vector<std::string> regions;
  };
  Parameters parameters_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::AbaqusFileReader)
