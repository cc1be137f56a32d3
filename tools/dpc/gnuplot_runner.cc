#include "gnuplot_runner.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace dpc {
namespace {

// The exit status of `sh -c` when the command is not found.
constexpr int kShellCommandNotFound = 127;

// `text` as a POSIX shell single-quoted word.
std::string ShellQuote(std::string_view text) {
  std::string quoted = "'";
  for (const char c : text) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  quoted += '\'';
  return quoted;
}

// A script file that exists for the lifetime of the object.
class TemporaryScript {
 public:
  explicit TemporaryScript(const std::string& script) {
    std::string pattern = (std::filesystem::temp_directory_path() / "dpc_gnuplot_XXXXXX").string();
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = ::mkstemp(name.data());
    if (fd < 0) {
      const int error = errno;
      throw std::runtime_error(fmt::format("cannot create a temporary gnuplot script '{}': {}",
                                           pattern, std::strerror(error)));
    }
    path_ = name.data();
    size_t done = 0;
    while (done < script.size()) {
      const ssize_t written = ::write(fd, script.data() + done, script.size() - done);
      if (written < 0 && errno == EINTR) continue;
      if (written <= 0) {
        const int error = errno;
        ::close(fd);
        std::remove(path_.c_str());
        throw std::runtime_error(fmt::format("cannot write the temporary gnuplot script '{}': {}",
                                             path_, std::strerror(error)));
      }
      done += static_cast<size_t>(written);
    }
    ::close(fd);
  }
  ~TemporaryScript() {
    if (!keep_) std::remove(path_.c_str());
  }
  TemporaryScript(const TemporaryScript&) = delete;
  TemporaryScript& operator=(const TemporaryScript&) = delete;

  const std::string& path() const { return path_; }
  // Leaves the file in place (for the user to read after a failure).
  void Keep() { keep_ = true; }

 private:
  std::string path_;
  bool keep_ = false;
};

}  // namespace

std::string GnuplotQuote(std::string_view text) {
  std::string quoted = "'";
  for (const char c : text) {
    if (c == '\'') {
      quoted += "''";
    } else if (c == '\n' || c == '\r') {
      quoted += ' ';
    } else {
      quoted += c;
    }
  }
  quoted += '\'';
  return quoted;
}

std::string RunGnuplot(const std::string& script) {
  TemporaryScript file(script);
  const std::string command = fmt::format("gnuplot {} 2>&1", ShellQuote(file.path()));
  std::FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    const int error = errno;
    throw std::runtime_error(
        fmt::format("cannot start gnuplot ({}): {}", command, std::strerror(error)));
  }
  std::string output;
  std::array<char, 4096> chunk;
  size_t got = 0;
  while ((got = std::fread(chunk.data(), 1, chunk.size(), pipe)) > 0) output.append(chunk.data(), got);
  const int status = ::pclose(pipe);
  if (status == -1) {
    const int error = errno;
    throw std::runtime_error(fmt::format("waiting for gnuplot failed: {}", std::strerror(error)));
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return output;
  if (WIFEXITED(status) && WEXITSTATUS(status) == kShellCommandNotFound) {
    throw std::runtime_error(fmt::format(
        "gnuplot was not found on the PATH: install gnuplot-nox (apt-get install gnuplot-nox)\n{}",
        output));
  }
  const std::string how = WIFEXITED(status)
                              ? fmt::format("exit status {}", WEXITSTATUS(status))
                              : fmt::format("signal {}", WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  file.Keep();
  throw std::runtime_error(
      fmt::format("gnuplot failed ({}); script kept at {}:\n{}", how, file.path(), output));
}

}  // namespace dpc
