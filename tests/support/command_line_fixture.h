#pragma once
// The shared fixture of the tests that run the dpc command as a user would: a fresh directory
// per test (removed after it), the built binary run to completion with its output captured, and
// files and shipped scenarios to give it.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/process.h"
#include "support/test_directory.h"

namespace dpc::testing {

class CommandLineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = FreshTestDirectory("dpc");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// Runs `dpc <args>` to completion (at most `timeout`).
  Result Dpc(std::vector<std::string> args, std::chrono::milliseconds timeout = std::chrono::seconds(120)) {
    args.insert(args.begin(), DPC_BINARY);
    return dpc::testing::Run(std::move(args), dir_, "dpc" + std::to_string(++runs_), timeout);
  }
  /// The same with the arguments in one string, split at spaces (no quoting).
  Result Dpc(const std::string& command_line, std::chrono::milliseconds timeout = std::chrono::seconds(120)) {
    std::vector<std::string> args;
    std::istringstream words(command_line);
    for (std::string word; words >> word;) args.push_back(word);
    return Dpc(std::move(args), timeout);
  }
  /// Writes `text` to <dir>/<name>; the path.
  std::string Write(const std::string& name, const std::string& text) const {
    const std::filesystem::path path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }
  /// The shipped scenario deploy/scenarios/<name>.pbtxt.
  static std::string Scenario(const std::string& name) {
    return std::string(DPC_SOURCE_DIR) + "/deploy/scenarios/" + name + ".pbtxt";
  }

  std::filesystem::path dir_;
  int runs_ = 0;
};

}  // namespace dpc::testing
