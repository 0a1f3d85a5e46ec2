// libFuzzer target: the abaqus_file reader (.inp) on arbitrary bytes. See fuzz_mesh_reader.hpp.
#include <algorithm>

#include "fuzz_mesh_reader.hpp"

namespace {

// A file an input may *INCLUDE (the seed corpus has one that does): the nodes of a unit tet.
constexpr const char* kPart = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static mtled::fuzz::ReaderHarness harness("abaqus_file");
  static const bool part_written = (harness.write_file("part.inp", kPart), true);
  (void)part_written;
  // *INCLUDE, INPUT= opens the file it names. Without a '/' the name can only be a file of the harness's
  // private folder (the input itself, or part.inp), never a device such as /dev/zero that would be read
  // forever: inputs with a '/' are skipped.
  if (std::find(data, data + size, '/') != data + size) return 0;
  harness.run(data, size, "fuzz.inp", mtled::json::object());
  return 0;
}
