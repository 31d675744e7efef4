// `faultline keys generate`: a CURVE key pair for a node (transport/access.hpp), written as
// PREFIX.secret (0600) and PREFIX.public.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "transport/access.hpp"

namespace faultline::cli {
namespace {
ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Writes a new ZeroMQ CURVE key pair: PREFIX.secret (mode 0600; this node's "
      "curve_secret_key_file) "
      "and PREFIX.public (for its peers: curve_server_public_key_file, or a line of "
      "curve_allowed_clients_file).",
      argv[0]};
  std::string prefix;
  bool force = false;
  app.add_option("prefix", prefix, "path prefix of the two files, e.g. keys/injector")->required();
  app.add_flag("--force", force, "replace existing files");
  FAULTLINE_PARSE(app, argc, argv);
  auto pair = transport::generate_curve_keypair();
  if (!pair.is_ok()) return pair.status();
  const Status written = transport::write_curve_key_files(*pair, prefix, force);
  if (!written.is_ok()) return written;
  std::printf("wrote %s.secret (keep private) and %s.public: %s\n", prefix.c_str(), prefix.c_str(),
              pair->public_key.c_str());
  return 0;
}
}  // namespace
FAULTLINE_COMMAND(keys_generate, "keys generate",
                  "write a CURVE key pair for authenticated transport", &run);
}  // namespace faultline::cli
