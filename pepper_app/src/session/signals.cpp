#include "session/signals.hpp"

#include <atomic>
#include <csignal>

namespace pepper::app {
namespace {

std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "flag must be usable from a signal handler");

extern "C" void on_interrupt_signal(int /*signum*/) { g_interrupted.store(true); }

}  // namespace

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = on_interrupt_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: blocking waits return early with EINTR
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupted() { return g_interrupted.load(); }
void request_interrupt() { g_interrupted.store(true); }
void reset_interrupt() { g_interrupted.store(false); }

}  // namespace pepper::app
