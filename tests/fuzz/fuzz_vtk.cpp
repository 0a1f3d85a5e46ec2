// libFuzzer target: the vtk_file reader, legacy .vtk and XML .vtu, on arbitrary bytes. See fuzz_mesh_reader.hpp.
#include "fuzz_mesh_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static mtled::fuzz::ReaderHarness harness("vtk_file");
  // The reader picks the parser by the extension: XML for text that starts with '<' (as every .vtu does),
  // legacy otherwise.
  std::size_t first = 0;
  while (first < size && (data[first] == ' ' || data[first] == '\t' || data[first] == '\r' || data[first] == '\n'))
    ++first;
  const bool xml = first < size && data[first] == '<';
  const std::string file = xml ? "fuzz.vtu" : "fuzz.vtk";
  // Regions from the first known region array; when that reads, again with the node-set arrays of the seed
  // files (point arrays "bottom" and "top"), which also checks their lengths and components.
  if (harness.run(data, size, file, mtled::json::object()))
    harness.run(data, size, file, {{"region_array", "region"}, {"node_set_arrays", {"bottom", "top"}}});
  return 0;
}
