#pragma once
// What a plugin author includes, beside the interface the component implements. One component per shared library:
//
//   #include "mtled/interfaces/material.hpp"
//   #include "mtled/plugin.hpp"
//
//   class OgdenMaterial final : public mtled::Material {
//    public:
//     static void declare(mtled::ComponentDeclaration& d);      // summary and parameters
//     explicit OgdenMaterial(const mtled::Parameters& p);
//     ...
//   };
//   MTLED_PLUGIN(mtled::Material, OgdenMaterial)
//
// and builds it with mtled_add_plugin(CATEGORY material NAME ogden SOURCES ogden.cpp) from CMake, which
// names the file mtled-material-ogden.so and defines MTLED_PLUGIN_NAME.
//
// The macro exports two C-linkage, exception-free entry points through Boost.DLL aliases: a handshake (ABI
// version, build fingerprint, component name) that the kernel checks before anything else, and a
// registration function that adds the declaration and a factory to the kernel's registry.
#define BOOST_DLL_USE_STD_FS
#include <boost/dll/alias.hpp>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>

#include "mtled/abi.hpp"
#include "mtled/plugin_abi.hpp"
#include "mtled/registry.hpp"

namespace mtled::detail {

template <class Interface, class Component>
int register_component(Registry* registry, const char* name, char* error, std::size_t error_size) noexcept {
  try {
    ComponentDeclaration declaration(name, Interface::category);
    Component::declare(declaration);
    registry->add<Interface>(std::move(declaration), [](const Parameters& parameters) -> std::unique_ptr<Interface> {
      return std::make_unique<Component>(parameters);
    });
    return 0;
  } catch (const std::exception& e) {
    if (error_size > 0) {
      std::strncpy(error, e.what(), error_size - 1);
      error[error_size - 1] = '\0';
    }
  } catch (...) {
    if (error_size > 0) std::strncpy(error, "unknown exception", error_size - 1);
  }
  return 1;
}

}  // namespace mtled::detail

#ifndef MTLED_PLUGIN_NAME
#error "MTLED_PLUGIN_NAME is defined by mtled_add_plugin() in CMake"
#endif
#ifndef MTLED_PLUGIN_CATEGORY
#error "MTLED_PLUGIN_CATEGORY is defined by mtled_add_plugin() in CMake"
#endif

#define MTLED_PLUGIN(Interface, Component)                                                                 \
  namespace {                                                                                              \
  const ::mtled_plugin_handshake mtled_plugin_handshake_data{                                              \
      MTLED_PLUGIN_ABI_VERSION, sizeof(::mtled_plugin_handshake), MTLED_PLUGIN_CATEGORY, MTLED_PLUGIN_NAME, \
      MTLED_BUILD_FINGERPRINT, MTLED_VERSION_STRING};                                                      \
  const ::mtled_plugin_handshake* mtled_plugin_handshake_function() noexcept {                             \
    return &mtled_plugin_handshake_data;                                                                   \
  }                                                                                                        \
  int mtled_plugin_register_function(::mtled::Registry* registry, char* error, std::size_t size) noexcept { \
    static_assert(Interface::category == ::mtled::category_from_literal(MTLED_PLUGIN_CATEGORY),            \
                  "the plugin's interface does not match the CATEGORY given to mtled_add_plugin()");       \
    return ::mtled::detail::register_component<Interface, Component>(registry, MTLED_PLUGIN_NAME, error,    \
                                                                     size);                                \
  }                                                                                                        \
  }                                                                                                        \
  BOOST_DLL_ALIAS(mtled_plugin_handshake_function, mtled_plugin_handshake)                                 \
  BOOST_DLL_ALIAS(mtled_plugin_register_function, mtled_plugin_register)
