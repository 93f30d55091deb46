#pragma once
// The exit statuses of every phri command (docs/configuration.md lists them for users).
namespace phri::cli {

inline constexpr int kOk = 0;
/// The command ran, and what it measured failed its own checks: an evaluation verdict, a run that
/// is invalid, a fuzz violation with --fail-on-violation, an F/T sensor that never answered.
inline constexpr int kChecksFailed = 1;
/// Refused input: the command line (the option parser's refusals too), a configuration, an input file.
inline constexpr int kBadInput = 2;
/// The run ended in a safe hold (the safety stop latched).
inline constexpr int kSafetyStop = 3;
/// The system refused: an output folder or file that cannot be written, a device that cannot be
/// opened, a simulated plant that faulted, an error from a library below.
inline constexpr int kSystemError = 4;
/// A signal ended the run: 128 + its number (SIGINT 130, SIGTERM 143), its files written.
inline constexpr int kSignalBase = 128;

}  // namespace phri::cli
