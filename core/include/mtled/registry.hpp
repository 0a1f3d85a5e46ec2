#pragma once
// The component registry: declarations and factories, looked up by category and name. A plugin's
// registration function adds its component here (see plugin.hpp). Each category has its own factory type,
// Factory<Interface>, held type-erased and read back only as the factory it was added as (std::any_cast checks the
// type), so the registry lists no category and never casts between them.
#include <any>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mtled/parameters.hpp"

namespace mtled {

template <class Interface>
using Factory = std::function<std::unique_ptr<Interface>(const Parameters&)>;

// Parameters the kernel adds to every component of a category (a material's "region", read into MaterialRegion).
std::vector<ParameterSpec> common_parameters(Category category);
struct MaterialRegion {
  std::optional<std::string> region;
};

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  template <class Interface>
  void add(ComponentDeclaration declaration, Factory<Interface> factory) {
    check_category(declaration, Interface::category);
    add_entry(std::move(declaration), std::any(std::move(factory)));
  }

  const ComponentDeclaration* find(Category category, std::string_view name) const;
  std::vector<const ComponentDeclaration*> all() const;

  template <class Interface>
  std::unique_ptr<Interface> create(std::string_view name, const Parameters& parameters) const {
    const auto& factory = std::any_cast<const Factory<Interface>&>(entry(Interface::category, name).factory);
    return factory(parameters);
  }

 private:
  struct Entry {
    ComponentDeclaration declaration;
    std::any factory;  // the Factory<Interface> of the declaration's category
  };
  static void check_category(const ComponentDeclaration& declaration, Category expected);
  void add_entry(ComponentDeclaration declaration, std::any factory);
  const Entry& entry(Category category, std::string_view name) const;
  std::map<std::pair<Category, std::string>, Entry, std::less<>> entries_;
};

}  // namespace mtled
