#pragma once
// A child `mtled run` (or any program) as its own process, its output in a log file: what studies and fits run, so
// that a run that fails (exit 3, a crash, a timeout) is recorded and the caller goes on.
#include <filesystem>
#include <string>
#include <vector>

namespace mtled {

// How a run ended, as a child process or in the calling process (what its folder alone cannot tell: a signal, the
// caller's timeout, its memory).
struct RunOutcome {
  bool reused = false;  // an earlier successful run kept (--reuse); nothing ran
  int exit_code = -1;
  int signal = 0;
  bool timed_out = false;
  double elapsed_s = 0.0;
  double max_rss_mb = 0.0;
};

// Runs `executable arguments...` with stdout and stderr into `log_file` and no standard input; an MPI launcher's
// variables are left out of its environment (a run is its own job). After `timeout_s` (0: none) it is sent SIGTERM
// (mtled run then writes summary.json with status "interrupted"), and SIGKILL 30 s later. Thread-safe.
RunOutcome run_child(const std::filesystem::path& executable, const std::vector<std::string>& arguments,
                     const std::filesystem::path& log_file, double timeout_s);

// A program as a shell finds it: a name with a slash is a path, any other is looked up in PATH's directories.
// Empty when no executable file is found.
std::filesystem::path find_program(const std::string& name);

}  // namespace mtled
