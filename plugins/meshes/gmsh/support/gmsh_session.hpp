#pragma once
// Gmsh keeps one global state per process (options, models, meshes). A generator owns it for the length
// of one load(): GmshSession takes the process's Gmsh lock (scenes set up at once in one process take turns),
// initialises Gmsh with fixed settings and finalises it on every exit path.
#include <mutex>
#include <stdexcept>
#include <string>

namespace mtled {

// An error that Gmsh reported. Gmsh 4.8 throws its error message as a plain std::string (General.AbortOnError
// = 2, set by gmsh::initialize); gmsh_checked() turns that into this type.
class GmshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  ~GmshError() override;
};

// Initialises Gmsh for deterministic, quiet meshing:
// - no configuration files (a user's gmshrc must not change the mesh);
// - one thread everywhere, 2D algorithm 6 (Frontal-Delaunay), 3D algorithm 1 (Delaunay), fixed random seed:
//   the same geometry and size give the same nodes and tets on every run;
// - Gmsh's terminal output only when mtled's log level is debug or finer.
class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  static void set_options();
  std::unique_lock<std::mutex> lock_;
  int host_threads_;  // OpenMP threads before Gmsh changed them, restored on finalise
};

// Gmsh's error messages as exceptions of a known type.
template <class Call>
decltype(auto) gmsh_checked(Call&& call) {
  try {
    return call();
  } catch (const std::string& message) {
    throw GmshError(message);
  } catch (const char* message) {
    throw GmshError(message);
  }
}

}  // namespace mtled
