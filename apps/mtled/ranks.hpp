#pragma once
// The processes of an MPI run (mpirun -np N mtled ...). MPI starts only when a launcher started this process (its
// environment says so), so a plain `mtled run` never touches MPI. Rank 0 writes and reports; the others compute.
#include <memory>
#include <string>
#include <vector>

#include "mtled/monitor.hpp"

namespace mtled::app {

struct Ranks {
  int rank = 0;
  int count = 1;
  bool writes() const { return rank == 0; }
};

// Starts MPI when launched by mpirun (or another launcher); {0, 1} otherwise. Throws InputError when the launcher
// started several processes and this mtled was built without MPI (each would run the whole scene into one folder).
Ranks start_ranks(int& argc, char**& argv);
const Ranks& ranks();
// Ends MPI after a run every rank finished alike (exit 0, or 3 for an unstable run every rank found). After any other
// failure a rank leaves without it: the launcher then ends every rank, where a rank waiting in MPI_Finalize for one
// that waits in an exchange would hang.
void stop_ranks();

// Every rank waits here for the others.
void wait_for_all_ranks();
// values summed over the ranks, on rank 0 (the others' are left as they were).
void sum_on_first_rank(std::vector<double>& values);

// MTLED_TEST_FAIL_RANK=R:S: rank R throws at step S (null when unset or another rank). The tests' way to check that
// one failing rank ends every rank with an error, never a hang.
std::shared_ptr<StepMonitor> injected_failure();

}  // namespace mtled::app
