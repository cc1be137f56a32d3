#include "gnuplot_runner.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

namespace dpc {
namespace {

// Sets an environment variable for the lifetime of the object, then restores it.
class ScopedEnvironmentVariable {
 public:
  ScopedEnvironmentVariable(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value, 1);
  }
  ~ScopedEnvironmentVariable() {
    if (old_) {
      ::setenv(name_.c_str(), old_->c_str(), 1);
    } else {
      ::unsetenv(name_.c_str());
    }
  }

 private:
  std::string name_;
  std::optional<std::string> old_;
};

std::string ExceptionMessage(const std::string& script) {
  try {
    RunGnuplot(script);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(GnuplotQuoteTest, DoublesSingleQuotesAndFlattensLineBreaks) {
  EXPECT_EQ(GnuplotQuote("plain"), "'plain'");
  EXPECT_EQ(GnuplotQuote("it's"), "'it''s'");
  EXPECT_EQ(GnuplotQuote("a\nb\r"), "'a b '");
  EXPECT_EQ(GnuplotQuote("\"x\" $y `z`"), "'\"x\" $y `z`'");  // no other escapes in '…'
}

TEST(RunGnuplotTest, RunsAScriptAndRemovesItsTemporaryFile) {
  const std::filesystem::path png = std::filesystem::temp_directory_path() /
                                    ("dpc_gnuplot_runner_test_" + std::to_string(::getpid()) +
                                     " it's.png");  // a space and a quote in the path
  const std::string output =
      RunGnuplot("set terminal pngcairo size 200,100\nset output " + GnuplotQuote(png.string()) +
                 "\nplot sin(x) notitle\nprint 'done'\n");
  EXPECT_NE(output.find("done"), std::string::npos) << output;
  EXPECT_GT(std::filesystem::file_size(png), 0u);
  std::filesystem::remove(png);
}

TEST(RunGnuplotTest, ScriptErrorThrowsWithGnuplotsMessage) {
  const std::string message = ExceptionMessage("print 1\nplot no_such_function_42(x)\n");
  EXPECT_NE(message.find("gnuplot failed"), std::string::npos) << message;
  EXPECT_NE(message.find("no_such_function_42"), std::string::npos) << message;
  // The script is kept for the user to read gnuplot's line numbers against.
  const std::string kept_at = "script kept at ";
  const size_t begin = message.find(kept_at);
  ASSERT_NE(begin, std::string::npos) << message;
  const size_t path_begin = begin + kept_at.size();
  const std::string script_path = message.substr(path_begin, message.find(':', path_begin) - path_begin);
  EXPECT_TRUE(std::filesystem::exists(script_path)) << script_path;
  std::filesystem::remove(script_path);
}

TEST(RunGnuplotTest, MissingGnuplotSaysWhatToInstall) {
  const ScopedEnvironmentVariable path("PATH", "/nonexistent-dpc-test-directory");
  const std::string message = ExceptionMessage("print 1\n");
  EXPECT_NE(message.find("install gnuplot-nox"), std::string::npos) << message;
}

}  // namespace
}  // namespace dpc
