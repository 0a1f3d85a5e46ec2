// `mpi` process group: the processes mpirun (or another MPI launcher) started, as MPI_COMM_WORLD. Loaded by the
// command line only when the launcher's environment says it started this process; it starts MPI, and ends it after a
// run every process finished alike. Its backend, `mpi`, runs one scene across the processes.
#include "mtled/interfaces/process_group.hpp"

#include <mpi.h>

#include "mtled/plugin.hpp"

namespace mtled {

class MpiProcessGroup final : public ProcessGroup {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The processes of an MPI run (mpirun -np N mtled run SCENE, or mtled study): loaded when a launcher started "
        "mtled, never from a scene. Rank 0 writes and reports; a scene runs across the ranks on the mpi backend, a "
        "study's runs are shared between them.");
  }
  explicit MpiProcessGroup(const Parameters&) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);  // MPI is called from the main thread only
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::string backend() const override { return "mpi"; }

  void barrier() override {
    if (size_ > 1) MPI_Barrier(MPI_COMM_WORLD);
  }

  void sum_on_first(std::vector<double>& values) override {
    if (size_ == 1) return;
    const auto count = static_cast<int>(values.size());
    if (rank_ == 0)
      MPI_Reduce(MPI_IN_PLACE, values.data(), count, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    else
      MPI_Reduce(values.data(), nullptr, count, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  }

  void finish() override {
    int stopped = 0;
    MPI_Finalized(&stopped);
    if (!stopped) MPI_Finalize();
  }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::ProcessGroup, mtled::MpiProcessGroup)
