// A one-node Slurm cluster on localhost for a test: munged, slurmctld and slurmd started as root
// without systemd, every file (config, key, sockets, state, logs) under one temporary folder and
// the daemons on free ports of their own. The destructor stops them, whatever happened in the test.
#pragma once

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "faultline_tool.hpp"  // read_text

namespace faultline::test_slurm {
namespace fs = std::filesystem;

// Runs `cmd` through /bin/sh; stdout (and stderr) as text, the exit code in *rc.
inline std::string run(const std::string& cmd, int* rc = nullptr) {
  std::string out;
  if (FILE* p = ::popen((cmd + " 2>&1").c_str(), "r")) {
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    const int status = ::pclose(p);
    if (rc) *rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  } else if (rc) {
    *rc = -1;
  }
  return out;
}

// The programs the cluster needs that are not on PATH (or in /usr/sbin), space-separated.
inline std::string missing_programs() {
  std::string missing;
  for (const char* p :
       {"munged", "mungekey", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "sinfo"}) {
    int rc = 0;
    run(std::string("PATH=$PATH:/usr/sbin:/sbin command -v ") + p, &rc);
    if (rc != 0) missing += std::string(missing.empty() ? "" : " ") + p;
  }
  return missing;
}

// A TCP port nobody listens on right now (bound to port 0 and released).
inline int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = -1;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) {
    port = ntohs(a.sin_port);
  }
  ::close(fd);
  return port;
}

class Cluster {
 public:
  explicit Cluster(fs::path dir) : dir_(std::move(dir)) {}
  Cluster(const Cluster&) = delete;
  Cluster& operator=(const Cluster&) = delete;
  ~Cluster() { stop(); }

  // Starts the three daemons and waits (bounded) for the node to be idle. "" or what went wrong,
  // with the daemons' logs.
  std::string start(int cpus) {
    fs::create_directories(dir_ / "munge");
    fs::create_directories(dir_ / "state");
    fs::create_directories(dir_ / "spool");
    fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                              fs::perms::others_read | fs::perms::others_exec);
    fs::permissions(dir_ / "munge", fs::perms::owner_all);
    const std::string m = (dir_ / "munge").string();
    int rc = 0;
    std::string out = run("PATH=$PATH:/usr/sbin mungekey -c -k " + m + "/munge.key", &rc);
    if (rc != 0) return "mungekey: " + out;
    out = run("PATH=$PATH:/usr/sbin munged -f --key-file=" + m + "/munge.key --socket=" + m +
                  "/munge.sock --pid-file=" + m + "/munged.pid --log-file=" + m +
                  "/munged.log --seed-file=" + m + "/munged.seed",
              &rc);
    munge_started_ = rc == 0;
    if (rc != 0) return "munged: " + out + test_tool::read_text(dir_ / "munge" / "munged.log");
    write_config(cpus);
    out = run(env() + "PATH=$PATH:/usr/sbin slurmctld -i -f " + conf(), &rc);
    if (rc != 0) return "slurmctld: " + out + logs();
    out = run(env() + "PATH=$PATH:/usr/sbin slurmd -f " + conf() + " -N " + kNode, &rc);
    if (rc != 0) return "slurmd: " + out + logs();
    for (int i = 0; i < 300; ++i) {  // 30 s
      if (run(env() + "sinfo -h -o %t") == "idle\n") return "";
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return "the node did not become idle within 30 s: sinfo says '" +
           run(env() + "sinfo -h -o %t") + "'\n" + logs();
  }

  // "SLURM_CONF=<conf> ", to put before a Slurm client command.
  std::string env() const { return "SLURM_CONF=" + conf() + " "; }
  std::string logs() const {
    return "--- slurmctld.log\n" + test_tool::read_text(dir_ / "slurmctld.log") +
           "--- slurmd.log\n" + test_tool::read_text(dir_ / "slurmd.log");
  }

  // Cancels what is left, shuts the daemons down and kills any that did not exit within 10 s.
  void stop() {
    if (stopped_) return;
    stopped_ = true;
    if (fs::exists(conf())) {
      run(env() + "scancel --quiet --full --signal=KILL -u root --partition=" + kPartition);
      run(env() + "scontrol shutdown");
    }
    std::vector<pid_t> pids;
    for (const char* f : {"slurmctld.pid", "slurmd.pid", "munge/munged.pid"}) {
      const pid_t pid = static_cast<pid_t>(std::atol(test_tool::read_text(dir_ / f).c_str()));
      if (pid > 0) pids.push_back(pid);
    }
    if (munge_started_)
      run("PATH=$PATH:/usr/sbin munged -s --socket=" + (dir_ / "munge" / "munge.sock").string());
    for (int i = 0; i < 100; ++i) {
      bool alive = false;
      for (pid_t p : pids) alive |= ::kill(p, 0) == 0;
      if (!alive) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (pid_t p : pids) ::kill(p, SIGKILL);
  }

  static constexpr const char* kNode = "flnode";
  static constexpr const char* kPartition = "fltest";

 private:
  std::string conf() const { return (dir_ / "slurm.conf").string(); }

  void write_config(int cpus) const {
    const std::string d = dir_.string();
    std::ofstream c(conf());
    c << "ClusterName=faultline-test\n"
      << "SlurmctldHost=localhost(127.0.0.1)\n"
      << "SlurmctldPort=" << free_port() << "\n"
      << "SlurmdPort=" << free_port() << "\n"
      << "SlurmUser=root\nSlurmdUser=root\n"
      << "AuthType=auth/munge\nCredType=cred/munge\n"
      << "AuthInfo=socket=" << d << "/munge/munge.sock\n"
      << "StateSaveLocation=" << d << "/state\nSlurmdSpoolDir=" << d << "/spool\n"
      << "SlurmctldPidFile=" << d << "/slurmctld.pid\nSlurmdPidFile=" << d << "/slurmd.pid\n"
      << "SlurmctldLogFile=" << d << "/slurmctld.log\nSlurmdLogFile=" << d << "/slurmd.log\n"
      << "ProctrackType=proctrack/pgid\nTaskPlugin=task/none\n"
      << "JobCompType=jobcomp/none\nAccountingStorageType=accounting_storage/none\n"
      << "JobAcctGatherType=jobacct_gather/none\n"
      << "SchedulerType=sched/builtin\nSelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n"
      << "MpiDefault=none\nReturnToService=2\n"
      << "NodeName=" << kNode << " NodeAddr=127.0.0.1 CPUs=" << cpus << " State=UNKNOWN\n"
      << "PartitionName=" << kPartition << " Nodes=" << kNode
      << " Default=YES MaxTime=INFINITE State=UP\n";
  }

  fs::path dir_;
  bool munge_started_ = false;
  bool stopped_ = false;
};

}  // namespace faultline::test_slurm
