#include "common/shutdown.hpp"

#include <csignal>

namespace faultline {

namespace {
std::atomic<bool> g_shutdown{false};
std::atomic<int> g_signal{0};

extern "C" void on_signal(int sig) {
  g_signal.store(sig);
  g_shutdown.store(true);
}
}  // namespace

const std::atomic<bool>& shutdown_requested() {
  static const bool installed = [] {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    std::signal(SIGPIPE, SIG_IGN);
    return true;
  }();
  (void)installed;
  return g_shutdown;
}

void request_shutdown() { g_shutdown.store(true); }
int shutdown_signal() { return g_signal.load(); }

}  // namespace faultline
