#include "dpc/cli/command_line.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "dpc/version.h"

namespace dpc::cli {
namespace {

/// The full command path of `app` ("dpc topic echo").
std::string PathOf(const CLI::App* app) {
  std::string path;
  for (const CLI::App* a = app; a != nullptr; a = a->get_parent()) {
    path = path.empty() ? a->get_name() : a->get_name() + " " + path;
  }
  return path;
}

/// The known name nearest `name` among `known` if at most 2 edits (and fewer than half of it)
/// away; else "".
std::string Nearest(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const auto& k : known) {
    const size_t d = EditDistance(name, k);
    if (d < best_distance) {
      best_distance = d;
      best = k;
    }
  }
  return best_distance <= 2 && best_distance * 2 < name.size() ? best : std::string();
}

std::string DidYouMean(const std::string& nearest) {
  return nearest.empty() ? std::string() : fmt::format(" (did you mean {}?)", nearest);
}

bool KnowsOption(const CLI::App* app, const std::string& name) {
  for (const CLI::App* a = app; a != nullptr; a = a->get_parent()) {
    if (a->get_option_no_throw(name) != nullptr) return true;
  }
  return false;
}

std::vector<std::string> LongOptionsOf(const CLI::App* app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app->get_options()) {
    for (const auto& n : option->get_lnames()) names.push_back("--" + n);
  }
  return names;
}

}  // namespace

std::string VersionText(const std::string& program) {
  return fmt::format("{} {} (jacobian_dpc, Fast DDS {})", program, kProjectVersion, kFastDdsVersion);
}

void AddVersionFlag(CLI::App& app, const std::string& program) {
  app.set_version_flag("--version", VersionText(program), "Print the version (the project's and Fast DDS's) and exit");
}

std::vector<std::string> Arguments(int argc, char** argv) {
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  return args;
}

std::string UnknownNameProblem(const CLI::App& app, const std::vector<std::string>& args) {
  const CLI::App* current = &app;
  for (const std::string& arg : args) {
    if (arg == "--") break;  // everything after is positional
    if (arg.rfind("--", 0) == 0) {
      const std::string name = arg.substr(0, arg.find('='));
      if (!KnowsOption(current, name)) {
        return fmt::format("{}: unknown option {}{}", PathOf(current), name,
                           DidYouMean(Nearest(name, LongOptionsOf(current))));
      }
      continue;
    }
    if (arg.rfind('-', 0) == 0) continue;  // a short flag or a negative number: CLI11 judges
    auto subcommands = current->get_subcommands([](const CLI::App*) { return true; });
    if (subcommands.empty()) continue;  // a positional or an option's value
    const CLI::App* named = nullptr;
    for (const CLI::App* sub : subcommands) {
      if (sub->check_name(arg)) named = sub;
    }
    if (named != nullptr) {
      current = named;
      continue;
    }
    // Not a subcommand: fine if this command takes positionals (or it is an option's value).
    const bool takes_positionals = !current->get_options([](const CLI::Option* o) { return o->get_positional(); }).empty();
    if (takes_positionals) continue;
    std::vector<std::string> names;
    for (const CLI::App* sub : subcommands) names.push_back(sub->get_name());
    return fmt::format("{}: unknown command '{}'{}; the commands are {}", PathOf(current), arg,
                       DidYouMean(Nearest(arg, names)), fmt::join(names, ", "));
  }
  return {};
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), size_t{0});
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::vector<uint64_t> ParseSeedList(const std::string& text, size_t max_count) {
  const auto number = [&](const std::string& item) {
    std::string copy = item;
    if (std::string problem = UnsignedInteger().operator()(copy); !problem.empty()) {
      throw std::invalid_argument(problem);
    }
    return static_cast<uint64_t>(std::stoull(item));
  };
  std::vector<uint64_t> seeds;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    const size_t dash = item.find('-', 1);
    if (item.empty()) throw std::invalid_argument("an empty item in '" + text + "'");
    if (dash == std::string::npos) {
      seeds.push_back(number(item));
    } else {
      const uint64_t first = number(item.substr(0, dash));
      const uint64_t last = number(item.substr(dash + 1));
      if (last < first) throw std::invalid_argument("the range '" + item + "' ends before it starts");
      if (last - first >= max_count) {
        throw std::invalid_argument(fmt::format("'{}' holds more than {} seeds", item, max_count));
      }
      for (uint64_t seed = first;; ++seed) {
        seeds.push_back(seed);
        if (seed == last) break;
      }
    }
    if (seeds.size() > max_count) throw std::invalid_argument(fmt::format("more than {} seeds", max_count));
    start = comma + 1;
  }
  return seeds;
}

namespace {

/// A validator of finite numbers: `bound_problem` says what is wrong with a finite value ("" if
/// nothing), given the text as typed.
CLI::Validator FiniteNumber(std::function<std::string(const std::string&, double)> bound_problem,
                            const std::string& description, const std::string& name) {
  return CLI::Validator(
      [bound_problem = std::move(bound_problem)](std::string& text) -> std::string {
        // strtod, not stod: a value beyond double's range is ±inf (said so below), a tiny one
        // its subnormal or 0, where stod would throw for both.
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size()) return "'" + text + "' is not a number";
        if (!std::isfinite(value)) return "'" + text + "' is not a finite number";
        return bound_problem(text, value);
      },
      description, name);
}

}  // namespace

const CLI::Validator& NonNegativeNumber() {
  static const CLI::Validator validator = FiniteNumber(
      [](const std::string& text, double value) { return value < 0.0 ? "'" + text + "' is below 0" : ""; },
      "NONNEGATIVE", "NonNegativeNumber");
  return validator;
}

const CLI::Validator& PositiveNumber() {
  static const CLI::Validator validator = FiniteNumber(
      [](const std::string& text, double value) { return value <= 0.0 ? "'" + text + "' is not above 0" : ""; },
      "POSITIVE", "PositiveNumber");
  return validator;
}

CLI::Validator NumberIn(double lowest, double highest) {
  return FiniteNumber(
      [lowest, highest](const std::string& text, double value) {
        return value < lowest || value > highest ? fmt::format("'{}' is not in [{}, {}]", text, lowest, highest)
                                                 : std::string();
      },
      fmt::format("FLOAT in [{} - {}]", lowest, highest), "NumberIn");
}

const CLI::Validator& UnsignedInteger() {
  static const CLI::Validator validator(
      [](std::string& text) -> std::string {
        if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
          return "'" + text + "' is not a non-negative integer";
        }
        if (text.size() > 20 || (text.size() == 20 && text > "18446744073709551615")) {
          return "'" + text + "' is larger than 18446744073709551615";
        }
        return {};
      },
      "UINT", "UnsignedInteger");
  return validator;
}

}  // namespace dpc::cli
