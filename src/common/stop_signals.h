// SIGINT, SIGTERM and SIGHUP blocked while a command works (its worker threads and children inherit
// the mask) and read between its steps, so it stops at a step's end and answers for the signal
// (exit 128 + the signal) instead of dying with half its work lost. The caller's mask is restored
// on exit, and a signal still pending is taken so it does not kill the process afterwards. Used by
// `tailsim merge` (sharding.cc) and the design commands (src/app/modules/optimize.cc).
#pragma once

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <time.h>

namespace tailsim {

class StopSignals {
 public:
  StopSignals() {
    sigemptyset(&set_);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set_, sig);
    pthread_sigmask(SIG_BLOCK, &set_, &old_);
  }
  ~StopSignals() {
    pending();
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  // The first stop signal received so far (0: none).
  int pending() {
    const timespec zero{0, 0};
    for (;;) {
      const int sig = ::sigtimedwait(&set_, nullptr, &zero);
      if (sig > 0) {
        if (first_ == 0) first_ = sig;
        continue;
      }
      if (errno != EINTR) return first_;
    }
  }
  // "Ctrl-C", "SIGTERM" or "SIGHUP".
  static const char* name(int sig) { return sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "Ctrl-C"; }

 private:
  sigset_t set_{}, old_{};
  int first_ = 0;
};

}  // namespace tailsim
