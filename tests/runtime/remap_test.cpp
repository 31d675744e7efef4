#include "runtime/remap.hpp"

#include <gtest/gtest.h>

#include "runtime/injector_loop.hpp"
#include "runtime/player_loop.hpp"

namespace faultline::runtime {
namespace {

TEST(RemapTest, ExactMatchWins) {
  const RemapTable t{{"/a/b", "/x"}, {"/a/", "/ns/"}};
  EXPECT_EQ(remap_topic(t, "/a/b"), "/x");
  EXPECT_EQ(remap_topic(t, "/a/c"), "/ns/c");
  EXPECT_EQ(remap_topic(t, "/other"), "/other");
}

TEST(RemapTest, LongestNamespaceWins) {
  const RemapTable t{{"/faulty/", "/f1/"}, {"/faulty/cam_front/", "/front/"}};
  EXPECT_EQ(remap_topic(t, "/faulty/cam_front/image_raw"), "/front/image_raw");
  EXPECT_EQ(remap_topic(t, "/faulty/cam_back/image_raw"), "/f1/cam_back/image_raw");
}

TEST(RemapTest, CameraTopicIsLowerCased) {
  EXPECT_EQ(camera_topic("CAM_FRONT_LEFT"), "/cam_front_left/image_rect_compressed");
}

TEST(RemapTest, FaultedTopicNames) {
  InjectorConfig c;
  EXPECT_EQ(faulted_topic(c, "/cam_front/image_rect_compressed"),
            "/faulty/cam_front/image_rect_compressed");
  c.decode = true;
  EXPECT_EQ(faulted_topic(c, "/cam_front/image_rect_compressed"), "/faulty/cam_front/image_raw");
  c.remap = {{"/faulty/", "/fog/"}};
  EXPECT_EQ(faulted_topic(c, "/cam_back/image_rect_compressed"), "/fog/cam_back/image_raw");
}

}  // namespace
}  // namespace faultline::runtime
