// Limits and access (#22) of the `faultline` commands that open sockets, in process through
// cli::dispatch: the AccessConfig options (--curve-secret-key-file, ... from its visit()), a topic
// tool that passes every message with the right key and gets nothing with a wrong one (refused and
// counted by the publisher), and `bag play` refusing a bind beyond loopback without --allow-remote.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/command.hpp"
#include "common/clock.hpp"
#include "curve_keys.hpp"  // tests/
#include "detection.pb.h"
#include "faultline_tool.hpp"  // tests/
#include "transport/publisher.hpp"

namespace faultline::cli {
namespace {

using ::testing::internal::CaptureStdout;
using ::testing::internal::GetCapturedStdout;

int Faultline(std::vector<std::string> args) {
  args.insert(args.begin(), "faultline");
  std::vector<char*> argv;
  for (auto& s : args) argv.push_back(s.data());
  return dispatch(static_cast<int>(argv.size()), argv.data());
}

bool Eventually(const std::function<bool()>& done) {
  const StampNs deadline = monotonic_now_ns() + 30 * kNsPerSec;
  while (!done()) {
    if (monotonic_now_ns() > deadline) return false;
    std::this_thread::yield();
  }
  return true;
}

class CliAccessTest : public ::testing::Test {
 protected:
  std::vector<std::string> Keys(const std::string& name) const {
    return {"--curve-secret-key-file", keys_.dir() + "/" + name + ".secret",
            "--curve-server-public-key-file", keys_.dir() + "/server.public"};
  }
  transport::Publisher CurvePublisher() const {
    transport::PublisherConfig pc;
    pc.endpoint = "tcp://127.0.0.1:*";
    pc.snd_hwm = 1000;
    pc.access = keys_.server();
    return transport::Publisher(pc);
  }
  static void Send(transport::Publisher& pub, int count) {
    for (int seq = 1; seq <= count; ++seq) {
      msgs::SampleAck ack;
      ack.mutable_header()->set_seq(static_cast<std::uint64_t>(seq));
      ack.set_sample_token("s" + std::to_string(seq));
      ASSERT_TRUE(pub.send("/t", ack.SerializeAsString()).is_ok());
    }
  }
  test::CurveKeys keys_;
};

TEST_F(CliAccessTest, OptionsComeFromAccessConfigWithItsHelpText) {
  CaptureStdout();
  EXPECT_EQ(Faultline({"topic", "echo", "--help"}), 0);
  const std::string echo = GetCapturedStdout();
  EXPECT_NE(echo.find("--curve-secret-key-file"), std::string::npos) << echo;
  EXPECT_NE(echo.find("this node's CURVE secret key file"), std::string::npos) << echo;
  EXPECT_NE(echo.find("--curve-server-public-key-file"), std::string::npos) << echo;
  EXPECT_EQ(echo.find("--allow-remote"), std::string::npos) << "topic echo binds nothing";
  CaptureStdout();
  EXPECT_EQ(Faultline({"bag", "play", "--help"}), 0);
  const std::string play = GetCapturedStdout();
  EXPECT_NE(play.find("--allow-remote"), std::string::npos) << play;
  EXPECT_NE(play.find("--curve-allowed-clients-file"), std::string::npos) << play;
  for (const char* command : {"topic hz", "topic bw", "topic delay", "topic info", "topic list",
                              "bag record", "bag control"}) {
    std::vector<std::string> args;
    std::istringstream words(command);
    for (std::string w; words >> w;) args.push_back(w);
    args.push_back("--help");
    CaptureStdout();
    EXPECT_EQ(Faultline(args), 0) << command;
    EXPECT_NE(GetCapturedStdout().find("--curve-secret-key-file"), std::string::npos) << command;
  }
}

TEST_F(CliAccessTest, TopicEchoWithTheRightKeyPrintsEveryMessage) {
  transport::Publisher pub = CurvePublisher();
  std::vector<std::string> args{"topic",
                                "echo",
                                "/t",
                                "--endpoint",
                                pub.endpoint(),
                                "--type",
                                "faultline.msgs.SampleAck",
                                "-n",
                                "5",
                                "--duration",
                                "120"};
  for (auto& k : Keys("good")) args.push_back(k);
  CaptureStdout();
  int rc = -1;
  std::thread echo([&] { rc = Faultline(args); });
  ASSERT_TRUE(pub.wait_for_subscribers("/t", 1, 30 * kNsPerSec).is_ok());
  Send(pub, 5);
  echo.join();
  const std::string out = GetCapturedStdout();
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("summary topic=/t count=5 malformed=0"), std::string::npos) << out;
  for (int seq = 1; seq <= 5; ++seq) {
    EXPECT_NE(out.find("seq: " + std::to_string(seq) + "\n"), std::string::npos) << out;
  }
  EXPECT_EQ(pub.auth_refused(), 0u);
}

TEST_F(CliAccessTest, TopicHzWithAWrongKeyIsRefusedAndGetsNothing) {
  transport::Publisher pub = CurvePublisher();
  std::vector<std::string> args{"topic",      "hz", "/t",      "--endpoint", pub.endpoint(),
                                "--duration", "10", "--every", "0"};
  for (auto& k : Keys("bad")) args.push_back(k);
  CaptureStdout();
  int rc = -1;
  std::thread hz([&] { rc = Faultline(args); });
  EXPECT_TRUE(
      Eventually([&] { return pub.auth_refused() >= 1; }));  // counted and logged by the publisher
  Send(pub, 5);
  hz.join();
  const std::string out = GetCapturedStdout();
  EXPECT_EQ(rc, 1) << out;  // nothing heard
  EXPECT_NE(out.find("count=0"), std::string::npos) << out;
  EXPECT_EQ(pub.subscriber_count("/t"), 0);
  EXPECT_EQ(pub.auth_refused(), 1u);
  // The tool's log says once why it heard nothing (the default logger writes to stdout), and does
  // not call the refusal a closed connection.
  const std::string refused = "refused by the publisher at " + pub.endpoint() + ": its ZAP handler";
  const auto first = out.find(refused);
  EXPECT_NE(first, std::string::npos) << out;
  EXPECT_EQ(out.find(refused, first + 1), std::string::npos) << out;
  EXPECT_EQ(out.find("connection " + pub.endpoint() + " closed"), std::string::npos) << out;
}

// As a process: `bag play` terminates the process's ZeroMQ context when it ends.
TEST_F(CliAccessTest, BagPlayBindsBeyondLoopbackOnlyWithAllowRemote) {
  const std::string bag = keys_.dir() + "/empty.mcap";
  std::ofstream(bag) << "";
  const std::string out = keys_.dir() + "/out.txt";
  const std::string common =
      "bag play " + bag + " --endpoint 'tcp://0.0.0.0:*' --no-keys --no-progress";
  EXPECT_EQ(test_tool::run_faultline(common, out), 2);
  const std::string refused = test_tool::read_text(out);
  EXPECT_NE(refused.find("endpoint = tcp://0.0.0.0:*"), std::string::npos) << refused;
  EXPECT_NE(refused.find("allow_remote"), std::string::npos) << refused;
  // Allowed, it binds and then fails on the empty bag (1), not on the endpoint (2).
  EXPECT_EQ(test_tool::run_faultline(common + " --allow-remote", out), 1);
  const std::string allowed = test_tool::read_text(out);
  EXPECT_EQ(allowed.find("allow_remote"), std::string::npos) << allowed;
}

}  // namespace
}  // namespace faultline::cli
