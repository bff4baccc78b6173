#pragma once
// Operator interrupts (Ctrl-C, SIGTERM) for the session loops.
//
// The handler only sets an atomic flag (the one async-signal-safe thing to do). Every session
// loop polls interrupted() at least once per frame wait (<= 100 ms) and, when set, stops the
// robot first, then saves what can be saved. A second Ctrl-C while shutting down is ignored by
// the flag but the bridge watchdog still stops the base if the loop hangs.

namespace pepper::app {

/// Installs SIGINT and SIGTERM handlers (idempotent).
void install_interrupt_handlers();

/// True once SIGINT/SIGTERM has been received (or request_interrupt() was called).
bool interrupted();

/// Sets the flag as a signal would (UI STOP-and-quit, tests).
void request_interrupt();

/// Clears the flag (tests only).
void reset_interrupt();

}  // namespace pepper::app
