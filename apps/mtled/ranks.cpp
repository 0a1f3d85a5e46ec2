#include "ranks.hpp"

#include <cstdlib>
#include <stdexcept>

#include "mtled/errors.hpp"

#ifdef MTLED_WITH_MPI
#include <mpi.h>
#endif

namespace mtled::app {

namespace {

Ranks current;

// The process count the launcher announced: Open MPI, then PMIx and PMI (MPICH, Slurm's srun); 0 when none did.
int launched_processes() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"})
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return std::getenv("PMIX_RANK") ? 1 : 0;
}

}  // namespace

Ranks start_ranks([[maybe_unused]] int& argc, [[maybe_unused]] char**& argv) {
  const int launched = launched_processes();
  if (launched == 0) return current;
#ifdef MTLED_WITH_MPI
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);  // MPI is called from the main thread only
  MPI_Comm_rank(MPI_COMM_WORLD, &current.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &current.count);
#else
  if (launched > 1)
    throw InputError("mpirun", "this mtled was built without MPI, so its " + std::to_string(launched) +
                                   " processes would each run the whole scene into the same folder: install "
                                   "libopenmpi-dev and libmetis-dev and rebuild (CMake finds them), or run without mpirun");
#endif
  return current;
}

const Ranks& ranks() { return current; }

void stop_ranks() {
#ifdef MTLED_WITH_MPI
  int started = 0, stopped = 0;
  MPI_Initialized(&started);
  MPI_Finalized(&stopped);
  if (started && !stopped) MPI_Finalize();
#endif
}

void wait_for_all_ranks() {
#ifdef MTLED_WITH_MPI
  if (current.count > 1) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

void sum_on_first_rank([[maybe_unused]] std::vector<double>& values) {
#ifdef MTLED_WITH_MPI
  if (current.count == 1) return;
  if (current.rank == 0)
    MPI_Reduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  else
    MPI_Reduce(values.data(), nullptr, static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
#endif
}

namespace {

class InjectedFailure final : public StepMonitor {
 public:
  explicit InjectedFailure(long step) : step_(step) {}
  std::string name() const override { return "injected_failure"; }
  void after_step(const StepRecord& step) override {
    if (step.load.step >= step_)
      throw std::runtime_error("failure injected at step " + std::to_string(step.load.step) +
                               " (MTLED_TEST_FAIL_RANK)");
  }
  bool reads_displacement(long) const override { return false; }

 private:
  long step_;
};

}  // namespace

std::shared_ptr<StepMonitor> injected_failure() {
  const char* value = std::getenv("MTLED_TEST_FAIL_RANK");
  if (value == nullptr) return nullptr;
  const std::string text = value;
  const auto colon = text.find(':');
  if (colon == std::string::npos || std::stoi(text.substr(0, colon)) != current.rank) return nullptr;
  return std::make_shared<InjectedFailure>(std::stol(text.substr(colon + 1)));
}

}  // namespace mtled::app
