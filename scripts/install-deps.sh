#!/usr/bin/env bash
# Installs Faultline's build and test dependencies from Debian packages (idempotent: only what is missing).
# Usage: scripts/install-deps.sh [--with-browser]   (--with-browser adds what only the tests and CI need: chromium for
#                                                   the report render test, nodejs + npm for the MCAP validator,
#                                                   clang-format-14 for the format check)
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libzmq3-dev cppzmq-dev                 # transport
  libprotobuf-dev protobuf-compiler      # messages
  libopencv-dev libturbojpeg0-dev        # images
  libjpeg62-turbo-dev                    # libjpeg API: transport_corruption's restart markers
  libspdlog-dev libfmt-dev               # logging
  libyaml-cpp-dev                        # node parameters and launch files
  rapidjson-dev                          # JSON: SAX streaming for big tables, NaN literals like the devkit
  libcli11-dev                           # command line
  libzstd-dev liblz4-dev zlib1g-dev      # MCAP chunk compression and CRC
  libv4l-dev                             # V4L2 capture
  cyclonedds-dev cyclonedds-tools        # live ROS 2 topics over DDS (lib/ros2dds; idlc compiles msgs/ros2)
  libfastrtps-dev libfastcdr-dev fastddsgen  # tests: the Fast DDS peer of the cross-vendor ROS 2 test
  libgtest-dev libgmock-dev libbenchmark-dev
  libssl-dev                             # tests: SHA-256 of golden outputs
  python3-zmq python3-protobuf python3-numpy python3-opencv
  slurmctld slurmd slurm-client munge    # tests: the Slurm job-array test starts a one-node cluster (docs/cluster.md)
)
if [[ "${1:-}" == "--with-browser" ]]; then packages+=(chromium clang-format-14); fi
# Node.js runs the independent MCAP validator (tests/mcap_js); a node already on PATH (any install) is kept.
if [[ "${1:-}" == "--with-browser" ]] && ! command -v node >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
