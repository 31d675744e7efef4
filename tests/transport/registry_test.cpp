#include "transport/registry.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

namespace faultline::transport {
namespace {

class RegistryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-registry-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    ::setenv("FAULTLINE_RUN_DIR", dir_.c_str(), 1);
  }
  void TearDown() override {
    ::unsetenv("FAULTLINE_RUN_DIR");
    std::system(("rm -rf " + dir_).c_str());
  }
  std::string dir_;
};

TEST_F(RegistryTest, AdvertisedTopicsAreListedAndRemovedOnExit) {
  {
    TopicRegistry reg("nusc_player");
    ASSERT_TRUE(reg.advertise("/cam_front/image_rect_compressed", "faultline.msgs.CameraFrame",
                              "tcp://127.0.0.1:5600")
                    .is_ok());
    ASSERT_TRUE(
        reg.advertise("/sync/sample", "faultline.msgs.SampleBoundary", "tcp://127.0.0.1:5600")
            .is_ok());
    const auto topics = list_topics();
    ASSERT_EQ(topics.size(), 2u);
    EXPECT_EQ(topics[0].topic, "/cam_front/image_rect_compressed");
    EXPECT_EQ(topics[0].node, "nusc_player");
    EXPECT_EQ(topics[0].pid, ::getpid());
    EXPECT_EQ(topics[1].type, "faultline.msgs.SampleBoundary");
  }
  EXPECT_TRUE(list_topics().empty());
}

TEST_F(RegistryTest, DeadPidsAndGarbageFilesAreIgnored) {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);  // now a pid that is surely not alive
  std::ofstream(dir_ + "/dead-" + std::to_string(child) + ".json")
      << R"({"node":"dead","pid":)" << child
      << R"(,"topics":[{"topic":"/x","type":"t","endpoint":"e","node":"dead","pid":1}]})";
  std::ofstream(dir_ + "/garbage-1.json") << "{not json";
  EXPECT_TRUE(list_topics().empty());
}

}  // namespace
}  // namespace faultline::transport
