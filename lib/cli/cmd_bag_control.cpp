// `faultline bag control ENDPOINT pause|resume|toggle|step [N]`: drives a `bag play --control
// ENDPOINT`.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "transport/context.hpp"
#include "transport/publisher.hpp"

namespace faultline::cli {
namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "Send a pause/resume/toggle/step command to `faultline bag play --control ENDPOINT`."};
  std::string endpoint, command;
  int count = 1;
  app.add_option("endpoint", endpoint, "the player's --control address")->required();
  app.add_option("command", command, "pause | resume | toggle | step")
      ->required()
      ->check(CLI::IsMember({"pause", "resume", "toggle", "step"}));
  app.add_option("count", count, "messages per step")->check(CLI::PositiveNumber);
  transport::AccessConfig access;
  add_access_options(app, access, SocketSides::Connect);
  FAULTLINE_PARSE(app, argc, argv);
  if (command == "step" && count > 1) command += " " + std::to_string(count);
  int rc = 0;
  {
    transport::PublisherConfig pc;
    pc.endpoint = endpoint;
    pc.pattern = transport::Pattern::PushPull;
    pc.bind = false;
    pc.linger_ms = 2000;                 // deliver the command before exiting
    pc.send_timeout_ns = 5 * kNsPerSec;  // no player listening: fail instead of blocking
    pc.access = access;
    transport::Publisher push(pc);
    const Status s = push.send("/bag_play/control", command);
    if (!s.is_ok()) {
      std::fprintf(stderr, "bag control: %s\n", s.to_string().c_str());
      rc = 1;
    }
  }
  transport::terminate_context();
  return rc;
}

}  // namespace
FAULTLINE_COMMAND(bag_control, "bag control", "pause/resume/step a running bag play", &run);
}  // namespace faultline::cli
