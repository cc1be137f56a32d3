#pragma once
// Runs a gnuplot script and turns its failures into exceptions.
//
// The script is written to a temporary file (mkstemp in std::filesystem::temp_directory_path())
// and run as `gnuplot <file> 2>&1` through popen(); gnuplot's combined output is captured. The
// file is removed afterwards, except when gnuplot fails: then the error names it, since
// gnuplot's messages refer to its line numbers. Paths and labels inside a script should be quoted with GnuplotQuote, so
// no user text ever reaches the shell. Not for the real-time path (forks a process).

#include <string>
#include <string_view>

namespace dpc {

/// `text` as a gnuplot single-quoted string literal: '…' with every ' doubled (the only escape
/// gnuplot knows inside single quotes) and line breaks replaced by spaces.
std::string GnuplotQuote(std::string_view text);

/// Runs gnuplot on `script` and returns what it printed (warnings) on success.
/// @throws std::runtime_error quoting gnuplot's output and naming the kept script file if
///         gnuplot exits with a non-zero status; saying "install gnuplot-nox" if no gnuplot is
///         on the PATH; or if the temporary script file cannot be written.
std::string RunGnuplot(const std::string& script);

}  // namespace dpc
