#pragma once
// One lock per process for a library that keeps a single global state (Gmsh: its options, models and meshes), so that
// scenes set up at once in one process (the Python module's run_many) take turns with it. Each plugin module holds
// its own copy of the static data it links, so the lock lives in the kernel's library, the one copy they all share.
#include <mutex>
#include <string_view>

namespace mtled {

// The lock for `library` ("gmsh"), the same object on every call with that name.
std::mutex& process_lock(std::string_view library);

}  // namespace mtled
