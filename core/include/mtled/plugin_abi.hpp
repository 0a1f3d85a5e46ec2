#pragma once
// The C-linkage handshake between the kernel and a plugin (see plugin.hpp for the plugin side and
// plugin_catalog.cpp for the kernel side).
#include <cstddef>
#include <cstdint>

namespace mtled {
class Registry;
}

extern "C" {
// Layout is frozen: abi_version comes first so that any future layout can still be refused safely.
struct mtled_plugin_handshake {
  std::uint32_t abi_version;
  std::uint32_t struct_size;
  const char* category;
  const char* component;
  const char* fingerprint;
  const char* mtled_version;
};
}
using mtled_handshake_function = const mtled_plugin_handshake*();
using mtled_register_function = int(mtled::Registry*, char* error, std::size_t error_size);

