// libFuzzer target: the gmsh_file reader (ASCII MSH 2.2 and 4.1) on arbitrary bytes. See fuzz_mesh_reader.hpp.
#include "fuzz_mesh_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static mtled::fuzz::ReaderHarness harness("gmsh_file");
  harness.run(data, size, "fuzz.msh", mtled::json::object());
  return 0;
}
