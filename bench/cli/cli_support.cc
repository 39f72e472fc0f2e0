#include "quasiroll/bench/cli/cli_support.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace quasiroll::cli {

namespace fs = std::filesystem;

namespace {

// Parses the whole of `text` as a finite decimal number.
std::optional<double> ParseFinite(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v))
    return std::nullopt;
  return v;
}

std::string Got(const std::string& text) { return ", got '" + text + "'"; }

}  // namespace

CLI::Validator PositiveNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> v = ParseFinite(text);
        if (!v || !(*v > 0)) return "must be a finite number > 0" + Got(text);
        return "";
      },
      "NUMBER > 0");
}

CLI::Validator NonNegativeNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> v = ParseFinite(text);
        if (!v || !(*v >= 0)) return "must be a finite number >= 0" + Got(text);
        return "";
      },
      "NUMBER >= 0");
}

CLI::Validator IntegerIn(long long lo, long long hi) {
  const std::string range =
      "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        // Digits only (optional sign), then a range check on at most 19
        // digits: no overflow, no "1e3", no "2.5".
        const size_t digits = text.size() - (!text.empty() && text[0] == '-');
        const bool well_formed =
            !text.empty() && digits > 0 && digits <= 18 &&
            std::all_of(text.begin() + (text[0] == '-'), text.end(),
                        [](char c) { return c >= '0' && c <= '9'; });
        if (!well_formed) return "must be " + range + Got(text);
        const long long v = std::stoll(text);
        if (v < lo || v > hi) return "must be " + range + Got(text);
        return "";
      },
      "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

CLI::Validator OneOf(std::vector<std::string> values) {
  std::string list;
  for (const std::string& v : values) list += (list.empty() ? "" : ", ") + v;
  return CLI::Validator(
      [values, list](std::string& text) -> std::string {
        if (std::find(values.begin(), values.end(), text) != values.end())
          return "";
        return "must be one of " + list + Got(text);
      },
      "{" + list + "}");
}

void WarnDeprecatedSpellings(const std::vector<DeprecatedSpelling>& spellings) {
  for (const DeprecatedSpelling& s : spellings)
    if (s.option->count() > 0)
      std::fprintf(stderr, "note: %s is deprecated, use %s\n",
                   s.old_name.c_str(), s.new_name.c_str());
}

void CheckOutputDirectory(const std::string& flag, const std::string& path) {
  if (path.empty())
    throw UsageError(flag, "must name a directory, got an empty string");
  std::error_code ec;
  const fs::path p(path);
  const fs::file_status st = fs::status(p, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      throw UsageError(flag,
                       "exists and is not a directory, got '" + path + "'");
    if (::access(path.c_str(), W_OK | X_OK) != 0)
      throw UsageError(flag, "directory is not writable (" +
                                 std::string(std::strerror(errno)) +
                                 "), got '" + path + "'");
    return;
  }
  // The nearest existing ancestor must be a writable directory.
  fs::path ancestor = fs::absolute(p, ec).parent_path();
  while (!ancestor.empty() && !fs::exists(ancestor, ec) &&
         ancestor != ancestor.root_path())
    ancestor = ancestor.parent_path();
  if (!fs::is_directory(ancestor, ec))
    throw UsageError(flag, "cannot be created: '" + ancestor.string() +
                               "' is not a directory, got '" + path + "'");
  if (::access(ancestor.c_str(), W_OK | X_OK) != 0)
    throw UsageError(flag, "cannot be created in '" + ancestor.string() +
                               "' (" + std::strerror(errno) + "), got '" +
                               path + "'");
}

namespace {

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1,
                         diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string ClosestName(const std::string& name,
                        const std::vector<std::string>& candidates) {
  // Distances on the names without leading dashes; at most a third of the
  // typed name's letters may differ ("--rk-metod" -> "--rk-method", not
  // "--foo" -> "--tol").
  auto bare = [](const std::string& s) {
    return s.substr(std::min(s.find_first_not_of('-'), s.size()));
  };
  const std::string typed = bare(name);
  std::string best;
  size_t best_distance = std::max<size_t>(1, typed.size() / 3) + 1;
  for (const std::string& c : candidates) {
    const std::string candidate = bare(c);
    // A typed prefix of a longer name ("--nlp-t" for "--nlp-tol") counts 1.
    const size_t score = candidate.size() > typed.size() && typed.size() >= 3 &&
                                 candidate.compare(0, typed.size(), typed) == 0
                             ? 1
                             : EditDistance(typed, candidate);
    if (score < best_distance) {
      best_distance = score;
      best = c;
    }
  }
  return best;
}

void RejectUnknownArguments(const CLI::App& command,
                            const std::string& command_path) {
  const std::vector<std::string> extras = command.remaining();
  if (extras.empty()) return;
  const std::string& first = extras.front();
  const std::string help = "; see '" + command_path + " --help'";
  if (first.size() > 1 && first[0] == '-') {
    const std::string typed = first.substr(0, first.find('='));
    std::vector<std::string> names;
    for (const CLI::Option* opt : command.get_options()) {
      for (const std::string& l : opt->get_lnames()) names.push_back("--" + l);
      for (const std::string& s : opt->get_snames()) names.push_back("-" + s);
    }
    const std::string hint = ClosestName(typed, names);
    throw UsageError(typed,
                     "unknown option of '" + command_path + "'" +
                         (hint.empty() ? "" : " (did you mean " + hint + "?)") +
                         help);
  }
  throw UsageError(command_path, "unexpected argument '" + first + "'" + help);
}

namespace {

std::atomic<bool> g_interrupted{false};
// Written once before the handler is installed; read in the handler.
std::string* g_interrupt_message = nullptr;

extern "C" void SetInterruptFlag(int) {
  g_interrupted.store(true);
  // A second Ctrl-C terminates the process the usual way.
  std::signal(SIGINT, SIG_DFL);
}

extern "C" void PrintAndExit(int) {
  if (g_interrupt_message != nullptr) {
    const std::string& m = *g_interrupt_message;
    ssize_t ignored = ::write(STDERR_FILENO, m.data(), m.size());
    (void)ignored;
  }
  ::_exit(kExitInterrupted);
}

}  // namespace

void InstallInterruptFlag() {
  g_interrupted.store(false);
  struct sigaction action {};
  action.sa_handler = SetInterruptFlag;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
}

bool Interrupted() { return g_interrupted.load(); }

void InstallInterruptMessage(const std::string& message) {
  static std::string stored;
  stored = message;
  g_interrupt_message = &stored;
  struct sigaction action {};
  action.sa_handler = PrintAndExit;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
}

std::string ShellQuote(const std::string& text) {
  const bool plain =
      !text.empty() &&
      std::all_of(text.begin(), text.end(), [](unsigned char c) {
        return std::isalnum(c) || std::strchr("-_./=:,+@%", c) != nullptr;
      });
  if (plain) return text;
  std::string out = "'";
  for (char c : text)
    out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace quasiroll::cli
