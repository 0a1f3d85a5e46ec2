// libFuzzer target: the needle's 3D Slicer markups reader (plugins/contact/needle_geometry.cpp) on arbitrary bytes.
// An InputError is the expected answer to a bad file; anything else escaping, a sanitizer report or a hang is a
// finding.
#include <cstdint>
#include <string>

#include "mtled/errors.hpp"
#include "mtled/needle/needle_geometry.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)mtled::parse_markups_trajectory(std::string(reinterpret_cast<const char*>(data), size), "fuzz.mrk.json");
  } catch (const mtled::InputError&) {
  }
  return 0;
}
