// CURVE key files for access tests (#22): a temporary directory with the key pairs "server", "good"
// and "bad" (transport::write_curve_key_files) and an allowed-clients file listing only "good".
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "transport/access.hpp"

namespace faultline::test {

class CurveKeys {
 public:
  CurveKeys() {
    char tmpl[] = "/tmp/faultline-curve-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    for (const char* name : {"server", "good", "bad"}) {
      auto pair = transport::generate_curve_keypair();
      EXPECT_TRUE(pair.is_ok()) << pair.status().to_string();
      if (pair) {
        EXPECT_TRUE(transport::write_curve_key_files(*pair, dir_ + "/" + name, false).is_ok());
      }
    }
    std::ofstream(dir_ + "/allowed") << "# the only client allowed\n"
                                     << transport::read_curve_key(dir_ + "/good.public") << "\n";
  }
  ~CurveKeys() { std::filesystem::remove_all(dir_); }
  CurveKeys(const CurveKeys&) = delete;
  CurveKeys& operator=(const CurveKeys&) = delete;

  // A binding node: the server key pair, admitting only "good".
  transport::AccessConfig server() const {
    transport::AccessConfig a;
    a.curve_secret_key_file = dir_ + "/server.secret";
    a.curve_allowed_clients_file = dir_ + "/allowed";
    return a;
  }
  // A connecting node with key pair `name`, trusting `server_key`'s public key.
  transport::AccessConfig client(const std::string& name,
                                 const std::string& server_key = "server") const {
    transport::AccessConfig a;
    a.curve_secret_key_file = dir_ + "/" + name + ".secret";
    a.curve_server_public_key_file = dir_ + "/" + server_key + ".public";
    return a;
  }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

}  // namespace faultline::test
