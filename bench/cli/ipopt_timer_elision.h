// Ipopt 3.11's task timers answered without a system call — an opt-in of the
// executables that link bench/cli/ipopt_timer_elision.cc (the quasiroll CLI
// and the micro-benchmarks), never of a library: that file defines the C
// library's getrusage, which only a program may do for itself.
//
// Ipopt 3.11 reads the process's CPU time (getrusage) around every phase of
// every iteration, for timing statistics quasiroll never uses; those system
// calls were two thirds of a warm solve (docs/performance.md). In a program
// that links this file, calls made from Ipopt's own code get zero usage
// without a system call; every other caller of getrusage is forwarded to the
// C library. Programs that do not link it (anything built on the installed
// quasiroll libraries, the Python module) get Ipopt's real timers: same
// results, slower Ipopt solves.
#pragma once

namespace quasiroll {

// Process-wide switch, initially off (= elision active) unless the
// environment variable QUASIROLL_IPOPT_TASK_TIMERS is "1" at start-up.
// Enable to get Ipopt's real timers back (for print_timing_statistics or a
// max_cpu_time limit; quasiroll sets neither).
void SetIpoptTaskTimersEnabled(bool enabled);
bool IpoptTaskTimersEnabled();
// How many of Ipopt's getrusage calls this thread has answered without a
// system call (for tests and diagnostics).
long IpoptTaskTimerCallsElidedOnThisThread();

}  // namespace quasiroll
