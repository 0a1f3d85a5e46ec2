#include "support/gmsh_session.hpp"

#include <gmsh.h>
#include <omp.h>

#include "mtled/log.hpp"
#include "mtled/process_lock.hpp"

namespace mtled {

GmshError::~GmshError() = default;

GmshSession::GmshSession() : lock_(process_lock("gmsh")), host_threads_(omp_get_max_threads()) {
  gmsh_checked([] { gmsh::initialize(0, nullptr, /*readConfigFiles=*/false); });
  try {
    set_options();
  } catch (...) {
    gmsh::finalize();  // the destructor does not run when the constructor throws
    omp_set_num_threads(host_threads_);
    throw;
  }
}

void GmshSession::set_options() {
  gmsh_checked([] {
    const bool verbose = log().should_log(spdlog::level::debug);
    gmsh::option::setNumber("General.Terminal", verbose ? 1 : 0);
    gmsh::option::setNumber("General.Verbosity", verbose ? 5 : 1);
    gmsh::option::setNumber("General.AbortOnError", 2);  // errors become exceptions, never exit()
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads1D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads2D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads3D", 1);
    gmsh::option::setNumber("Geometry.OCCParallel", 0);
    gmsh::option::setNumber("Mesh.Algorithm", 6);
    gmsh::option::setNumber("Mesh.Algorithm3D", 1);
    gmsh::option::setNumber("Mesh.RandomSeed", 1);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    gmsh::option::setNumber("Mesh.Optimize", 1);
    gmsh::option::setNumber("Mesh.OptimizeNetgen", 0);
    // Size from Mesh.MeshSizeMax alone: no refinement from curvature or from CAD points.
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 1);
    gmsh::option::setNumber("Mesh.MeshSizeMin", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFactor", 1);
  });
}

GmshSession::~GmshSession() {
  try {
    gmsh::finalize();
  } catch (...) {
    // A destructor must not throw; Gmsh's state is released by then.
  }
  omp_set_num_threads(host_threads_);  // Gmsh sets the process-wide OpenMP thread count to its own
}

}  // namespace mtled
