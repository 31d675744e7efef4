// `faultline bag control ENDPOINT pause|resume|toggle|step [N]`: drives a `bag play --control
// ENDPOINT`.
#include <CLI/CLI.hpp>

#include "cli/access_options.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "transport/context.hpp"
#include "transport/publisher.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
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
  Status sent;
  {
    transport::PublisherConfig pc;
    pc.endpoint = endpoint;
    pc.pattern = transport::Pattern::PushPull;
    pc.bind = false;
    pc.linger_ms = 2000;                 // deliver the command before exiting
    pc.send_timeout_ns = 5 * kNsPerSec;  // no player listening: fail instead of blocking
    pc.access = access;
    transport::Publisher push(pc);
    sent = push.send("/bag_play/control", command);
  }
  transport::terminate_context();
  if (!sent.is_ok()) return failure(sent.to_string());
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(bag_control, "bag control", "pause/resume/step a running bag play", &run);
}  // namespace faultline::cli
