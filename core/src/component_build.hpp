#pragma once
// Building a scene's components from the plugin catalog, with a plugin's failure reported at the scene's JSON path.
#include <fmt/format.h>

#include <exception>
#include <memory>
#include <string>

#include "mtled/errors.hpp"
#include "mtled/plugin_catalog.hpp"
#include "mtled/scene.hpp"

namespace mtled {

template <class Interface>
std::shared_ptr<Interface> build_component(PluginCatalog& catalog, const ComponentBlock& block) {
  try {
    return catalog.create<Interface>(block.type, block.parameters);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(block.parameters.pointer(), fmt::format("{} \"{}\" failed while being built: {}",
                                                             to_string(Interface::category), block.type, e.what()));
  }
}

// Runs call(), reporting a failure other than an InputError as "<what> failed" at the block's JSON path.
template <class Call>
void guarded(const Parameters& parameters, const std::string& what, Call call) {
  try {
    call();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(parameters.pointer(), fmt::format("{} failed: {}", what, e.what()));
  }
}

}  // namespace mtled
