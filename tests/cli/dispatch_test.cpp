// Exit codes of the `faultline` tool, for every registered command: 2 for any usage error (CLI11's
// own codes, 104-109, used to leak out), 0 for --help. In process, through cli::dispatch.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "transport/access.hpp"

namespace faultline::cli {
namespace {

int run(const std::vector<std::string>& words) {
  std::vector<std::string> storage{"faultline"};
  for (const auto& w : words) {
    std::istringstream split(w);  // a two-word command name becomes two arguments
    for (std::string part; split >> part;) storage.push_back(part);
  }
  std::vector<char*> argv;
  for (auto& s : storage) argv.push_back(s.data());
  return dispatch(static_cast<int>(argv.size()), argv.data());
}

TEST(DispatchTest, EveryCommandExitsTwoOnAnUnknownOption) {
  ASSERT_GT(all_commands().size(), 30u);
  for (const Command* c : all_commands()) {
    EXPECT_EQ(run({c->name, "--no-such-option-anywhere"}), 2) << c->name;
  }
}

TEST(DispatchTest, EveryCommandExitsZeroOnHelp) {
  for (const Command* c : all_commands()) EXPECT_EQ(run({c->name, "--help"}), 0) << c->name;
}

TEST(DispatchTest, ValueThatDoesNotConvertExitsTwo) {
  EXPECT_EQ(run({"corrupt", "--angle", "abc", "in.jpg", "out.png"}), 2);  // was 104
  EXPECT_EQ(run({"bench transport", "--seconds", "many"}), 2);
}

TEST(DispatchTest, MissingRequiredOptionExitsTwo) {
  EXPECT_EQ(run({"score"}), 2);  // --results is required (was 106)
  EXPECT_EQ(run({"detect"}), 2);
}

TEST(DispatchTest, UnknownCommandAndBareGroupExitTwo) {
  EXPECT_EQ(run({"no-such-command"}), 2);
  EXPECT_EQ(run({"bag"}), 2);
  EXPECT_EQ(run({"bag", "no-such-subcommand"}), 2);
}

// A command returns its failure and dispatch prints it once, prefixed with the command's name.
TEST(DispatchTest, PrintsAReturnedFailureOnceWithTheCommandName) {
  const std::string missing = ::testing::TempDir() + "/faultline_no_such_robustness.json";
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run({"report", "--robustness", missing}), 1);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            "faultline report: " + missing + ": not found\n");
}

TEST(DispatchTest, PrintsAReturnedUsageErrorAndExitsTwo) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run({"bag record", "-o", "unused.mcap", "--all", "--meta", "no-equals-sign"}), 2);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            "faultline bag record: --meta no-equals-sign: expected KEY=VALUE\n");
}

// `keys generate` writes a pair the transport reads back, and refuses to replace it without
// --force.
TEST(DispatchTest, KeysGenerateWritesAPairAndKeepsAnExistingOne) {
  const std::string prefix = ::testing::TempDir() + "/faultline_keys_" + std::to_string(::getpid());
  EXPECT_EQ(run({"keys generate", prefix}), 0);
  const std::string secret = transport::read_curve_key(prefix + ".secret");
  EXPECT_EQ(transport::read_curve_key(prefix + ".public").size(), 40u);
  EXPECT_EQ(run({"keys generate", prefix}), 1);
  EXPECT_EQ(transport::read_curve_key(prefix + ".secret"), secret);
  EXPECT_EQ(run({"keys generate", "--force", prefix}), 0);
  EXPECT_NE(transport::read_curve_key(prefix + ".secret"), secret);
  std::remove((prefix + ".secret").c_str());
  std::remove((prefix + ".public").c_str());
}

}  // namespace
}  // namespace faultline::cli
