// SIGINT/SIGTERM handling: the handler only sets a flag; loops poll it with a bounded timeout.
#pragma once

#include <atomic>

namespace faultline {

// Installs the handlers once (idempotent) and returns the flag that turns true on SIGINT/SIGTERM.
const std::atomic<bool>& shutdown_requested();
// For tests and for nodes that end on their own (end of dataset): sets the same flag.
void request_shutdown();
// The signal that triggered shutdown (0 if none or requested programmatically).
int shutdown_signal();

}  // namespace faultline
