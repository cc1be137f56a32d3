#include "dpc/bus/shm_segments.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>

#include <fmt/format.h>

namespace dpc::bus {
namespace {

enum class Kind { kPort, kSegment };

/// Whether `lock_path` is held by a live process; nullopt when it cannot be told (gone, not
/// ours to open). On false the caller removes the files while `*held_fd` keeps it locked, so
/// that no participant takes it over meanwhile; the caller closes it.
std::optional<bool> HeldByAnother(const std::string& lock_path, int* held_fd) {
  const int fd = ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return std::nullopt;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return true;
  }
  *held_fd = fd;
  return false;
}

void Remove(const std::string& path, StaleShmCleanup* result) {
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    result->errors.push_back(fmt::format("{}: {}", path, std::strerror(errno)));
  }
}

}  // namespace

StaleShmCleanup RemoveStaleShmFiles(const std::string& directory, double min_age_s) {
  StaleShmCleanup result;
  DIR* dir = ::opendir(directory.c_str());
  if (dir == nullptr) return result;
  static const std::regex kPortLock("^fastrtps_port[0-9]{1,5}_el$");
  static const std::regex kSegmentLock("^fastrtps_[0-9a-z]{16}_el$");
  std::vector<std::pair<Kind, std::string>> locks;
  while (const dirent* entry = ::readdir(dir)) {
    const std::string name = entry->d_name;
    if (std::regex_match(name, kPortLock)) {
      locks.emplace_back(Kind::kPort, name);
    } else if (std::regex_match(name, kSegmentLock)) {
      locks.emplace_back(Kind::kSegment, name);
    }
  }
  ::closedir(dir);
  const std::time_t now = std::time(nullptr);
  for (const auto& [kind, name] : locks) {
    const std::string lock_path = directory + "/" + name;
    struct stat info {};
    if (::lstat(lock_path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) continue;
    if (static_cast<double>(now - info.st_mtime) < min_age_s) continue;  // being created
    int fd = -1;
    const std::optional<bool> held = HeldByAnother(lock_path, &fd);
    if (!held) continue;
    if (*held) {
      ++result.in_use;
      continue;
    }
    const std::string base = name.substr(0, name.size() - 3);  // without "_el"
    Remove(directory + "/" + base, &result);
    if (kind == Kind::kPort) Remove(directory + "/sem." + base + "_mutex", &result);
    Remove(lock_path, &result);
    ::close(fd);
    ++(kind == Kind::kPort ? result.ports_removed : result.segments_removed);
  }
  return result;
}

std::vector<std::string> DescribeShmCleanup(const StaleShmCleanup& cleanup) {
  std::vector<std::string> lines;
  if (cleanup.ports_removed + cleanup.segments_removed > 0) {
    lines.push_back(fmt::format("removed what dead processes left in /dev/shm: {} Fast DDS port{}, {} segment{} "
                                "({} in use)",
                                cleanup.ports_removed, cleanup.ports_removed == 1 ? "" : "s",
                                cleanup.segments_removed, cleanup.segments_removed == 1 ? "" : "s", cleanup.in_use));
  }
  for (const std::string& error : cleanup.errors) lines.push_back("could not remove a stale shared-memory file: " + error);
  return lines;
}

bool ProfilesUseSharedMemory(const std::string& profiles_file) {
  std::ifstream in(profiles_file);
  if (!in) return false;
  std::ostringstream text;
  text << in.rdbuf();
  static const std::regex kShm("<type>\\s*SHM\\s*</type>");
  return std::regex_search(text.str(), kShm);
}

}  // namespace dpc::bus
