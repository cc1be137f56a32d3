#pragma once
// What every entry point (dpc and the services) says about itself and about a command line it
// cannot take: the version (the project's and the Fast DDS it was built against), and an
// unknown subcommand or option named, with the nearest known name, before CLI11 would blame
// something else ("dpc simm": "A subcommand is required"; "dpc sim --metod gp": "File does not
// exist: gp", the flag's value taken for the scenario).

#include <cstdint>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace dpc::cli {

/// "dpc 0.1.0 (jacobian_dpc, Fast DDS 2.9.1)".
std::string VersionText(const std::string& program);

/// Adds --version (prints VersionText(program), exits 0).
void AddVersionFlag(CLI::App& app, const std::string& program);

/// The words of argv after the program name.
std::vector<std::string> Arguments(int argc, char** argv);

/// "" if every subcommand and every long option in `args` is known to `app` (walking into the
/// subcommands as they are named); else what is unknown and where, with the nearest known
/// name if one is close ("dpc sim: unknown option --metod (did you mean --method?)").
std::string UnknownNameProblem(const CLI::App& app, const std::vector<std::string>& args);

/// The number of single-character edits between `a` and `b` (Levenshtein distance).
size_t EditDistance(const std::string& a, const std::string& b);

/// A validator for unsigned integer options (seeds): digits only, so that "-1" is refused
/// instead of wrapping to 2^64 − 1 (CLI11 converts it).
const CLI::Validator& UnsignedInteger();

/// Validators for floating-point options: a finite number ≥ 0 (NonNegativeNumber) or > 0
/// (PositiveNumber). CLI11's own accept "nan" (every comparison with it is false) and name
/// their range as "0.000000 to 1797693…" (DBL_MAX written out); these say "'nan' is not a
/// finite number" or "'-1' is below 0". The help shows NONNEGATIVE / POSITIVE, as CLI11's do.
const CLI::Validator& NonNegativeNumber();
const CLI::Validator& PositiveNumber();
/// A finite number in [lowest, highest] (CLI::Range takes "nan": "'nan' is not a finite number",
/// "'7' is not in [0.1, 5]"). The help shows "FLOAT in [lowest - highest]", as CLI11's does.
CLI::Validator NumberIn(double lowest, double highest);

/// Seeds from a list of values and ranges: "3", "1,2,7", "1-10", "1-3,8". Throws
/// std::invalid_argument naming the bad item (not a non-negative integer, a range whose end is
/// before its start) or when the list holds more than `max_count` seeds.
std::vector<uint64_t> ParseSeedList(const std::string& text, size_t max_count = 10000);

}  // namespace dpc::cli
