// The only file that touches Boost.DLL (Debian's Boost 1.74: header-only with std::filesystem).
#define BOOST_DLL_USE_STD_FS
#include "mtled/plugin_catalog.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include "mtled/abi.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin_abi.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {
constexpr std::string_view kPrefix = "mtled-";
constexpr std::string_view kSuffix = ".so";

// "mtled-material-ogden.so" -> (material, "ogden")
std::optional<std::pair<Category, std::string>> parse_file_name(const std::string& file) {
  if (file.size() <= kPrefix.size() + kSuffix.size() || file.rfind(kPrefix, 0) != 0 ||
      file.compare(file.size() - kSuffix.size(), kSuffix.size(), kSuffix) != 0)
    return std::nullopt;
  const std::string stem = file.substr(kPrefix.size(), file.size() - kPrefix.size() - kSuffix.size());
  const auto dash = stem.find('-');
  if (dash == std::string::npos) return std::nullopt;
  const auto category = category_from_string(stem.substr(0, dash));
  if (!category || *category == Category::scene) return std::nullopt;
  return std::make_pair(*category, stem.substr(dash + 1));
}

std::vector<fs::path> split_path_list(const std::string& text) {
  std::vector<fs::path> paths;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ':'))
    if (!item.empty()) paths.emplace_back(item);
  return paths;
}

bool same_contents(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::equivalent(a, b, ec)) return true;
  if (fs::file_size(a, ec) != fs::file_size(b, ec) || ec) return false;
  std::ifstream in_a(a, std::ios::binary), in_b(b, std::ios::binary);
  return std::equal(std::istreambuf_iterator<char>(in_a), std::istreambuf_iterator<char>(),
                    std::istreambuf_iterator<char>(in_b), std::istreambuf_iterator<char>());
}
}  // namespace

fs::path kernel_library_directory() { return fs::path(boost::dll::this_line_location()).parent_path(); }

fs::path mtled_program(const std::string& name) {
  return (kernel_library_directory() / MTLED_BINDIR_FROM_LIBDIR / name).lexically_normal();
}

std::vector<fs::path> plugin_search_path(const std::vector<fs::path>& command_line, const std::vector<fs::path>& scene) {
  std::vector<fs::path> path = command_line;
  path.insert(path.end(), scene.begin(), scene.end());
  if (const char* env = std::getenv("MTLED_PLUGIN_PATH"); env != nullptr) {
    const auto listed = split_path_list(env);
    path.insert(path.end(), listed.begin(), listed.end());
  } else {
    path.push_back(kernel_library_directory() / "mtled" / "plugins");
  }
  return path;
}

struct PluginCatalog::Library {
  boost::dll::shared_library library;
  fs::path file;
};

PluginCatalog::PluginCatalog(std::vector<fs::path> search_path) : search_path_(std::move(search_path)) {
  std::set<fs::path> seen_folders;
  for (const auto& folder : search_path_) {
    std::error_code ec;
    const fs::path canonical_folder = fs::weakly_canonical(folder, ec);
    if (ec || !fs::is_directory(canonical_folder, ec)) {
      log().debug("plugin folder {} does not exist; skipped", folder.string());
      continue;
    }
    if (!seen_folders.insert(canonical_folder).second) continue;
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(canonical_folder, ec)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
      const auto parsed = parse_file_name(file.filename().string());
      if (!parsed) continue;
      const Available* earlier = find(parsed->first, parsed->second);
      if (earlier != nullptr && same_contents(earlier->file, file)) {
        // The same library reached twice (the build folder on the command line and a copy beside the
        // scene): not ambiguous, the first in search order is used.
        log().debug("{} is a copy of {}; the first is used", file.string(), earlier->file.string());
        continue;
      }
      if (earlier != nullptr) {
        duplicates_.push_back(
            {std::string(to_string(parsed->first)) + " " + parsed->second,
             fmt::format("found twice: {} and {}; remove one, or point MTLED_PLUGIN_PATH / --plugin-path at only "
                         "one of the folders",
                         earlier->file.string(), file.string())});
        continue;
      }
      available_.push_back({parsed->first, parsed->second, file});
    }
  }
}

PluginCatalog::~PluginCatalog() = default;

std::vector<std::string> PluginCatalog::names(Category category) const {
  std::vector<std::string> list;
  for (const auto& a : available_)
    if (a.category == category) list.push_back(a.name);
  return list;
}

std::optional<std::string> PluginCatalog::left_out_reason(Category category, std::string_view name) const {
  const std::string key = fmt::format("{} {}: ", to_string(category), name);
  for (const auto& folder : search_path_) {
    std::ifstream file(folder / "left-out.txt");
    for (std::string line; std::getline(file, line);)
      if (line.rfind(key, 0) == 0) return line.substr(key.size());
  }
  return std::nullopt;
}

const PluginCatalog::Available* PluginCatalog::find(Category category, std::string_view name) const {
  for (const auto& a : available_)
    if (a.category == category && a.name == name) return &a;
  return nullptr;
}

const ComponentDeclaration& PluginCatalog::load(Category category, std::string_view name, const std::string& where) {
  const std::string label = fmt::format("{} \"{}\"", to_string(category), name);
  if (const auto* declaration = registry_.find(category, name)) return *declaration;

  for (const auto& d : duplicates_)
    if (d.where == std::string(to_string(category)) + " " + std::string(name))
      throw InputError(where, fmt::format("{} {}", label, d.message));

  const Available* available = find(category, name);
  if (available == nullptr) {
    std::string message = fmt::format("unknown {}", label);
    const auto known = names(category);
    const auto hint = did_you_mean(std::string(name), known);
    if (!hint.empty()) message += "; " + hint;
    message += known.empty() ? fmt::format(" (no {} plugins found)", to_string(category))
                             : fmt::format(" (available: {})", fmt::join(known, ", "));
    if (const auto reason = left_out_reason(category, name)) message += "; " + *reason;
    std::vector<std::string> folders;
    for (const auto& f : search_path_) folders.push_back(f.string());
    message += fmt::format("; plugin folders searched: {}", folders.empty() ? "none" : fmt::format("{}", fmt::join(folders, ":")));
    throw InputError(where, message);
  }

  const std::string file = available->file.string();
  auto library = std::make_shared<Library>();
  library->file = available->file;
  try {
    library->library.load(available->file, boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw InputError(where, fmt::format("cannot load {} from {}: {}", label, file, e.what()));
  }
  if (!library->library.has("mtled_plugin_handshake") || !library->library.has("mtled_plugin_register"))
    throw InputError(where, fmt::format("{} is not an mtled plugin (no handshake); rebuild it with "
                                        "mtled_add_plugin() and MTLED_PLUGIN()",
                                        file));

  const auto& handshake_function = library->library.get_alias<mtled_handshake_function>("mtled_plugin_handshake");
  const mtled_plugin_handshake* handshake = handshake_function();
  if (handshake == nullptr) throw InputError(where, fmt::format("{}: the plugin's handshake returned nothing", file));
  if (handshake->abi_version != MTLED_ABI_VERSION)
    throw InputError(where, fmt::format("{} was built for mtled ABI version {}, this mtled has ABI version {}; "
                                        "rebuild the plugin against this mtled",
                                        file, handshake->abi_version, MTLED_ABI_VERSION));
  if (handshake->struct_size != sizeof(mtled_plugin_handshake))
    throw InputError(where, fmt::format("{}: handshake size {} differs from {}; rebuild the plugin", file,
                                        handshake->struct_size, sizeof(mtled_plugin_handshake)));
  const auto differences = fingerprint_differences(handshake->fingerprint, kernel_build_fingerprint());
  if (!differences.empty())
    throw InputError(where, fmt::format("{} was built differently from this mtled and cannot be loaded safely "
                                        "({}); rebuild it with the same compiler, flags and libraries",
                                        file, fmt::join(differences, "; ")));
  if (std::string_view(handshake->category) != to_string(category) || std::string_view(handshake->component) != name)
    throw InputError(where, fmt::format("{} declares {} \"{}\" but its file name says {}; rename the file or "
                                        "rebuild it",
                                        file, handshake->category, handshake->component, label));

  const auto& register_function = library->library.get_alias<mtled_register_function>("mtled_plugin_register");
  char error[1024] = {0};
  if (register_function(&registry_, error, sizeof(error)) != 0)
    throw InputError(where, fmt::format("{}: registration of {} failed: {}", file, label, error));
  const ComponentDeclaration* declaration = registry_.find(category, name);
  if (declaration == nullptr)
    throw InputError(where, fmt::format("{} registered nothing under the name {}", file, label));

  loaded_.emplace(std::make_pair(category, std::string(name)), library);
  load_order_.push_back(available->file.filename().string());
  log().debug("loaded {} from {}", label, file);
  return *declaration;
}

std::shared_ptr<void> PluginCatalog::library_for(Category category, std::string_view name) const {
  const auto it = loaded_.find(std::make_pair(category, std::string(name)));
  if (it == loaded_.end())
    throw std::logic_error(fmt::format("{} \"{}\" used before it was loaded", to_string(category), name));
  return it->second;
}

std::vector<std::string> PluginCatalog::loaded_files() const { return load_order_; }

}  // namespace mtled
