// libFuzzer target: the label-map readers (io/src/nrrd.cpp, nifti.cpp, the gunzip they share) on arbitrary bytes,
// each input read as a NRRD file, a NIfTI file and a gzipped NIfTI file. An InputError is the expected answer to a
// bad file; anything else escaping, a sanitizer report or a hang is a finding.
#include <cstdint>
#include <string>

#include "mtled/errors.hpp"
#include "mtled/io/label_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    (void)mtled::parse_nrrd(bytes, "fuzz.nrrd");
  } catch (const mtled::InputError&) {
  }
  try {
    (void)mtled::parse_nifti(bytes, "fuzz.nii");
  } catch (const mtled::InputError&) {
  }
  try {
    (void)mtled::parse_nifti(mtled::gunzip(bytes, "fuzz.nii.gz"), "fuzz.nii.gz");
  } catch (const mtled::InputError&) {
  }
  return 0;
}
