// Shared pieces of the quasiroll CLI contract (docs/cli.md): flag
// validators whose messages name the flag as typed, output-location checks
// done before any work, unknown-argument hints, deprecated flag spellings,
// SIGINT handling and the exit codes.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace quasiroll::cli {

// Process exit codes (docs/cli.md, "Exit codes").
enum ExitCode : int {
  kExitOk = 0,
  kExitNotOk = 1,          // a solve/run ended with a non-OK status
  kExitBadInput = 2,       // bad flag, scene, suite or output location
  kExitInternal = 3,       // an unexpected error (I/O failure, bug)
  kExitMissingTool = 4,    // report: no usable Python 3 with matplotlib
  kExitInterrupted = 130,  // SIGINT (128 + 2), partial results kept
};

// A bad command-line value: exit code 2, the message starts with the flag
// as the user typed it ("--dt: must be > 0, got 0").
class UsageError : public std::invalid_argument {
 public:
  UsageError(const std::string& flag, const std::string& problem)
      : std::invalid_argument(flag + ": " + problem) {}
};

// Validators for CLI11 options. They run on the text before conversion, so
// "abc" and "0" get the same kind of message; CLI11 prefixes the option name.
CLI::Validator PositiveNumber();     // finite and > 0
CLI::Validator NonNegativeNumber();  // finite and >= 0
CLI::Validator IntegerIn(long long lo, long long hi);
CLI::Validator OneOf(std::vector<std::string> values);

// Adds `--old` as a deprecated spelling of `--new` (same variable, same
// validator). After parsing, WarnDeprecatedSpellings prints one line per
// deprecated spelling used: "note: --rk is deprecated, use --rk-method".
struct DeprecatedSpelling {
  CLI::Option* option;
  std::string old_name, new_name;
};
void WarnDeprecatedSpellings(const std::vector<DeprecatedSpelling>& spellings);

// Throws UsageError(flag, ...) unless `path` can be used as an output
// directory: non-empty, not an existing non-directory, and (for a path that
// does not exist yet) its nearest existing ancestor is a writable directory.
// Creates nothing.
void CheckOutputDirectory(const std::string& flag, const std::string& path);

// After a successful parse with extras allowed: throws UsageError for the
// first argument (in the order typed) that `command` did not recognise, with
// a "did you mean" hint among its option names. No-op if none.
void RejectUnknownArguments(const CLI::App& command,
                            const std::string& command_path);

// For `quasiroll <typo>`: the subcommand closest to `name`, or "".
std::string ClosestName(const std::string& name,
                        const std::vector<std::string>& candidates);

// SIGINT: after InstallInterruptFlag() the first Ctrl-C sets the flag
// (Interrupted() returns true) and a second one terminates the process.
void InstallInterruptFlag();
bool Interrupted();

// SIGINT: print `message` on stderr and _exit(kExitInterrupted). For
// commands whose results on disk are consistent at every instant (bench).
void InstallInterruptMessage(const std::string& message);

// The string quoted for a POSIX shell when it needs quoting.
std::string ShellQuote(const std::string& text);

}  // namespace quasiroll::cli
