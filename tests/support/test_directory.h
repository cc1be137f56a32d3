#pragma once
// A directory of its own for the running test.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace dpc::testing {

/// A new, empty directory in the temporary directory for the running test:
/// "<prefix>_<suite>.<test>_<pid>" ('/' of a parameterized test's name made '_'). Never one an
/// earlier test left: a long suite reuses process ids, and gtest runs a binary's tests in one
/// process, so a directory named by either alone would carry files from test to test.
inline std::filesystem::path FreshTestDirectory(const std::string& prefix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info != nullptr ? std::string(info->test_suite_name()) + "." + info->name() : "test";
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / (prefix + "_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace dpc::testing
