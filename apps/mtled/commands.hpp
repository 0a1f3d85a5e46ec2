#pragma once
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace mtled::app {

// Options every command that reads a scene shares.
struct SceneOptions {
  std::filesystem::path scene;
  std::vector<std::string> overrides;  // --set /pointer=value
  std::vector<std::filesystem::path> plugin_paths;
};

struct RunOptions {
  SceneOptions scene;
  std::filesystem::path output;
  int threads = 0;  // 0: all hardware threads
  bool progress = true;
};

struct MeshOptions {
  SceneOptions scene;
  std::filesystem::path output;  // FILE.inp
};

struct FieldOptions {
  std::filesystem::path run;     // run folder or result .vtu
  std::filesystem::path like;    // an image whose grid the field is sampled on (NRRD, NIfTI)
  // Or the grid itself: the first voxel's centre (mm), the spacing (mm), the voxels per axis and the frame.
  std::vector<double> origin_mm, spacing_mm;
  std::vector<std::int64_t> size;
  std::string space;
  std::filesystem::path output;  // .nrrd, .nii or .nii.gz
  std::string direction = "resampling";  // or "forward"
  std::string frame;             // "LPS" or "RAS": the result's frame when its mesh recorded none
  double decay_mm = 10.0;        // outside the body the field fades to zero over this distance; 0: zero outside
};

struct WarpOptions {
  std::filesystem::path image;   // the reference image (NRRD, NIfTI), scalar
  std::filesystem::path run;     // run folder or result .vtu
  std::filesystem::path output;  // .nrrd, .nii or .nii.gz
  std::string interpolation;     // "linear" or "nearest"; empty: nearest for whole-number types, else linear
  std::string frame;             // as FieldOptions
  double decay_mm = 10.0;        // as FieldOptions
};

struct CompareOptions {
  std::filesystem::path a, b;       // run folders or result .vtu files
  bool json = false;                // machine-readable output
  std::filesystem::path histogram;  // SVG of the node-by-node differences, when set
  int bins = 41;
};

struct StudyOptions {
  std::filesystem::path study;   // STUDY.json
  std::filesystem::path output;  // the study's folder
  int threads = 0;               // passed to every run; 0: the study file's "threads", else the run's default
  bool reuse = false;            // keep runs whose folder already holds an "ok" result of the same settings
  std::vector<std::filesystem::path> plugin_paths;
  std::string log_level = "info";  // passed to every run
  std::filesystem::path job_list;  // write every run's command line here instead of running (a batch scheduler's jobs)
  bool gather = false;             // run nothing: measure and report the runs the job list made
};

struct FitOptions {
  std::filesystem::path fit;     // FIT.json
  std::filesystem::path output;  // the fit's folder
  std::vector<std::string> overrides;  // --set on the fit file
  int threads = 0;               // in all, split between the runs that go at once (0: the fit file's, else all)
  bool reuse_mesh = true;        // each experiment's mesh written once, its meshless basis built once
  bool check = false;            // read and check everything, run nothing
  std::optional<unsigned long long> synthesize;  // write data from the model at the start values, with this seed
  std::vector<std::filesystem::path> plugin_paths;
  std::string log_level = "warn";  // passed to every forward run
};

struct ConformanceOptions {
  std::filesystem::path library;              // a plugin library (mtled-CATEGORY-NAME.so) or a folder of them
  std::vector<std::string> gtest_arguments;   // passed on to the runner (--gtest_brief=1, ...)
};

// Each returns the process exit code (0 ok, 2 invalid input, 3 instability, 1 anything else); InputError
// and other exceptions propagate to main, which prints them and picks the code.
int run_scene(const RunOptions& options);
// A run's threads: `requested` when positive, else OMP_NUM_THREADS when set (the OpenMP convention), else every core.
int run_thread_count(int requested);
int validate_scene_command(const SceneOptions& options);
int mesh_command(const MeshOptions& options);
int list_plugins(const std::vector<std::filesystem::path>& plugin_paths, bool as_json, bool as_markdown,
                 const std::string& describe);
int print_schema(const std::vector<std::filesystem::path>& plugin_paths);
int compare_command(const CompareOptions& options, const std::vector<std::filesystem::path>& plugin_paths);
int field_command(const FieldOptions& options, const std::vector<std::filesystem::path>& plugin_paths);
int warp_command(const WarpOptions& options, const std::vector<std::filesystem::path>& plugin_paths);
int study_command(const StudyOptions& options);
int fit_command(const FitOptions& options);
// Replaces the process by the conformance runner (its exit code: 0 when every suite passed).
int conformance_command(const ConformanceOptions& options, const std::vector<std::filesystem::path>& plugin_paths);

}  // namespace mtled::app
