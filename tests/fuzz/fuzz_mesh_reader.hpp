#pragma once
// What the mesh-reader fuzz targets share. Each target compiles one reader plugin's sources into itself and
// registers it through the plugin's own exported registration function (the one the kernel's loader calls
// after dlopen), so the harness runs exactly the component a scene would: parameters validated against its
// declaration, the input written to a file and loaded through MeshSource::load, then remove_unused_nodes
// and check_mesh as a run does. An InputError is the expected answer to bad input; anything else escaping,
// a sanitizer report, a hang or a mesh whose indices are out of range is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/log.hpp"
#include "mtled/mesh.hpp"
#include "mtled/plugin_abi.hpp"
#include "mtled/registry.hpp"

// Defined by MTLED_PLUGIN (through BOOST_DLL_ALIAS) in the reader's sources compiled into the target.
extern "C" const void* mtled_plugin_register;

namespace mtled::fuzz {

// Stops the process with a message: libFuzzer saves the input as a crash.
[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
  std::abort();
}

class ReaderHarness {
 public:
  explicit ReaderHarness(std::string name) : name_(std::move(name)) {
    set_log_level("off");  // warnings about damaged files are expected, and slow the fuzzer down
    char error[512] = "";
    auto* reg = reinterpret_cast<mtled_register_function*>(const_cast<void*>(mtled_plugin_register));
    if (reg(&registry_, error, sizeof(error)) != 0) finding(std::string("registration failed: ") + error);
    // A private folder on tmpfs when there is one: one file write per input is then cheap. Only the
    // input's own file lives there, so Abaqus *INCLUDE (resolved against it) stays inside.
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    directory_ = base / ("mtled-fuzz-" + name_ + "-" + std::to_string(::getpid()));
    std::filesystem::create_directories(directory_);
  }
  ~ReaderHarness() {
    std::error_code ec;
    std::filesystem::remove_all(directory_, ec);
  }

  // Writes a file into the private folder (for Abaqus *INCLUDE targets).
  void write_file(const std::string& file_name, std::string_view text) const {
    std::ofstream(directory_ / file_name, std::ios::binary | std::ios::trunc) << text;
  }

  // Writes `data` to `file_name` in the private folder and reads it with the parameter block `block` (no
  // "path": it is added). Returns whether the mesh was read and passed check_mesh.
  bool run(const std::uint8_t* data, std::size_t size, const std::string& file_name, json block) {
    write_file(file_name, std::string_view(reinterpret_cast<const char*>(data), size));
    block["path"] = file_name;
    std::vector<Problem> problems;
    const Parameters parameters =
        validate_parameters(*registry_.find(Category::mesh, name_), block, "/mesh", problems);
    if (!problems.empty()) finding("the harness's parameter block is invalid: " + problems.front().format());
    try {
      const auto source = registry_.create<MeshSource>(name_, parameters);
      TetMesh mesh = source->load(MeshContext{directory_, 1, {}});
      check_indices(mesh);
      remove_unused_nodes(mesh);
      check_indices(mesh);
      check_mesh(mesh);
      return true;
    } catch (const InputError& e) {
      for (const auto& problem : e.problems()) (void)problem.format();  // as the command line prints them
      return false;
    }
  }

 private:
  // What a reader hands over must index its own points and regions (check_mesh would refuse bad indices
  // with an InputError, which would hide the reader's bug).
  static void check_indices(const TetMesh& mesh) {
    for (const auto& tet : mesh.tets)
      for (Index v : tet)
        if (v < 0 || v >= mesh.node_count()) finding("a tet index out of range");
    if (mesh.tet_region.size() != mesh.tets.size()) finding("tet_region does not match the tets");
    for (Index r : mesh.tet_region)
      if (r < 0 || static_cast<std::size_t>(r) >= mesh.region_names.size()) finding("a region index out of range");
    for (const auto& [name, nodes] : mesh.node_sets)
      for (Index n : nodes)
        if (n < 0 || n >= mesh.node_count()) finding("node set " + name + " has an index out of range");
  }

  std::string name_;
  Registry registry_;
  std::filesystem::path directory_;
};

}  // namespace mtled::fuzz
