#pragma once
// This mtled's process group (mtled/interfaces/process_group.hpp): joined once by main, read by the commands that
// share their work between the processes (run, study). Process 0 writes and reports; the others compute.
#include <filesystem>
#include <memory>
#include <vector>

#include "mtled/interfaces/process_group.hpp"
#include "mtled/monitor.hpp"

namespace mtled::app {

// Joins the group a launcher started this process in (itself alone without one). Throws InputError as
// join_process_group does.
void join_processes(const std::vector<std::filesystem::path>& plugin_paths);
// The group joined.
ProcessGroup& processes();

// MTLED_TEST_FAIL_RANK=R:S: process R throws at step S (null when unset or another process). The tests' way to check
// that one failing process ends every process with an error, never a hang.
std::shared_ptr<StepMonitor> injected_failure();

}  // namespace mtled::app
