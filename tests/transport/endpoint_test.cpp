#include "transport/endpoint.hpp"

#include <gtest/gtest.h>

namespace faultline::transport {
namespace {

TEST(EndpointTest, LoopbackEndpoints) {
  EXPECT_TRUE(is_loopback_endpoint("tcp://127.0.0.1:5600"));
  EXPECT_TRUE(is_loopback_endpoint("tcp://127.0.0.1:*"));
  EXPECT_TRUE(is_loopback_endpoint("tcp://localhost:5600"));
  EXPECT_TRUE(is_loopback_endpoint("tcp://[::1]:5600"));
  EXPECT_TRUE(is_loopback_endpoint("ipc:///tmp/faultline.sock"));
  EXPECT_TRUE(is_loopback_endpoint("inproc://frames"));
}

TEST(EndpointTest, NonLoopbackEndpoints) {
  EXPECT_FALSE(is_loopback_endpoint("tcp://*:5600"));
  EXPECT_FALSE(is_loopback_endpoint("tcp://0.0.0.0:5600"));
  EXPECT_FALSE(is_loopback_endpoint("tcp://192.168.1.4:5600"));
  EXPECT_FALSE(is_loopback_endpoint("tcp://eth0:5600"));
}

TEST(EndpointTest, Scheme) {
  EXPECT_EQ(endpoint_scheme("ipc:///tmp/x"), "ipc");
  EXPECT_EQ(endpoint_scheme("nonsense"), "");
}

}  // namespace
}  // namespace faultline::transport
