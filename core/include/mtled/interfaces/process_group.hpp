#pragma once
// The processes one run is shared between (mpirun -np N mtled run SCENE). A plain run is one process and loads nothing
// for it; a process a launcher started (its environment says so) joins the launcher's group through the
// process_group plugin (`mpi`, which starts and ends MPI). Process 0 writes and reports; the others compute the same
// run and take part in every exchange. The group names the backend a scene runs on across its processes, so the
// command line and the kernel never name a parallel library.
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mtled/parameters.hpp"

namespace mtled {

struct SceneDocument;

class ProcessGroup {
 public:
  static constexpr Category category = Category::process_group;
  virtual ~ProcessGroup();

  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool writes() const { return rank() == 0; }
  // The backend plugin that runs one scene across these processes.
  virtual std::string backend() const = 0;

  // Every process waits here for the others.
  virtual void barrier() = 0;
  // values summed over the processes, on process 0 (the others' are left as they were).
  virtual void sum_on_first(std::vector<double>& values) = 0;
  // Ends the group after a run every process finished alike (exit 0, or 3 for an unstable run every process found).
  // After any other failure a process leaves without it: the launcher then ends every process, where one waiting here
  // for a process that waits in an exchange would hang.
  virtual void finish() = 0;
};

// How many processes a launcher started this one among: Open MPI's mpirun, then PMIx and PMI (MPICH, Slurm's srun);
// 0 when none did.
int launched_processes();
// Whether an environment entry ("NAME=value") is a launcher's: a child process that inherits one would join the
// launcher's job instead of running on its own.
bool launcher_variable(std::string_view entry);

// The group this process belongs to: itself alone, unless a launcher started it; then the process_group plugin found
// on `search_path`. Throws InputError (at "mpirun") when a launcher started several processes and no such plugin was
// built: each would otherwise run the whole scene into the same folder.
std::shared_ptr<ProcessGroup> join_process_group(const std::vector<std::filesystem::path>& search_path);

// On a group of several processes a scene runs on the group's backend: /backend becomes it when the scene names none,
// and a scene that names another is refused (InputError at /backend/type).
void run_across(SceneDocument& document, const ProcessGroup& group);

}  // namespace mtled
