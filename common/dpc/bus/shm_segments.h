#pragma once
// Fast DDS's shared-memory transport leaves its files in /dev/shm when a process dies without
// closing them (kill -9, a crash): a port (fastrtps_port<N>, its lock fastrtps_port<N>_el and its
// mutex sem.fastrtps_port<N>_mutex) and the process's segments (fastrtps_<16 hex>, lock
// fastrtps_<16 hex>_el). A live owner holds an exclusive flock on each "_el" file; a file nobody
// holds belongs to a dead process. Stale ports delay the discovery of a restarted participant
// (up to ~1 s, and >20 s was seen on 2.9). This is what `fastdds shm clean` does
// (/usr/share/fastdds/shm/clean.py), run by the services before they create their participant
// when their profile uses shared memory, without a Python interpreter.
//
// A lock file younger than `min_age_s` is left alone: between creating it and locking it a
// starting participant holds no lock yet.

#include <string>
#include <vector>

namespace dpc::bus {

struct StaleShmCleanup {
  int ports_removed = 0;
  int segments_removed = 0;
  int in_use = 0;                   ///< lock files held by a live process
  std::vector<std::string> errors;  ///< files that could not be removed, and why
};

/// Removes the stale Fast DDS shared-memory ports and segments in `directory`.
StaleShmCleanup RemoveStaleShmFiles(const std::string& directory = "/dev/shm", double min_age_s = 2.0);

/// What a service logs of it: a line when something was removed, one per file that could not be
/// (empty when there was nothing to do).
std::vector<std::string> DescribeShmCleanup(const StaleShmCleanup& cleanup);

/// Whether the Fast DDS profiles file uses the shared-memory transport (a transport descriptor of
/// type SHM); false if it cannot be read.
bool ProfilesUseSharedMemory(const std::string& profiles_file);

}  // namespace dpc::bus
