#pragma once
// The component registry: declarations and factories, looked up by category and name. A plugin's
// registration function adds its component here (see plugin.hpp); the kernel never casts between
// categories: each category has its own factory type.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "mtled/interfaces/backend.hpp"
#include "mtled/interfaces/driver.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/interfaces/process_group.hpp"
#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/interfaces/volumetric_treatment.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

template <class Interface>
using Factory = std::function<std::unique_ptr<Interface>(const Parameters&)>;

// Parameters the kernel adds to every component of a category (a material's "region").
std::vector<ParameterSpec> common_parameters(Category category);

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  template <class Interface>
  void add(ComponentDeclaration declaration, Factory<Interface> factory) {
    check_category(declaration, Interface::category);
    add_entry(std::move(declaration), AnyFactory(std::move(factory)));
  }

  const ComponentDeclaration* find(Category category, std::string_view name) const;
  std::vector<const ComponentDeclaration*> all() const;

  template <class Interface>
  std::unique_ptr<Interface> create(std::string_view name, const Parameters& parameters) const {
    const auto& factory = std::get<Factory<Interface>>(entry(Interface::category, name).factory);
    return factory(parameters);
  }

 private:
  using AnyFactory = std::variant<Factory<MeshSource>, Factory<ShapeFunctions>, Factory<Material>,
                                  Factory<BoundaryCondition>, Factory<NeedleModel>, Factory<TimeIntegrator>,
                                  Factory<VolumetricTreatment>, Factory<StepEngine>, Factory<ProcessGroup>>;
  struct Entry {
    ComponentDeclaration declaration;
    AnyFactory factory;
  };
  static void check_category(const ComponentDeclaration& declaration, Category expected);
  void add_entry(ComponentDeclaration declaration, AnyFactory factory);
  const Entry& entry(Category category, std::string_view name) const;
  std::map<std::pair<Category, std::string>, Entry, std::less<>> entries_;
};

}  // namespace mtled
