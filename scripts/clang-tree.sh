# Sourced by scripts/fuzz.sh and scripts/sanitize.sh: configures build-fuzz/, the one clang tree that is both the
# libFuzzer build and the ASan+UBSan test build (docs/reliability.md, "Fuzzing and sanitizers"). -DFAULTLINE_FUZZ=ON
# instruments every library, node and test with -fsanitize=fuzzer-no-link,address,undefined (cmake/fuzz.cmake), so
# the code the fuzz targets link is compiled once for both jobs. -O1 -g with assertions on: fast enough to fuzz,
# exact stack traces. C too (msgs/ros2: the DDS types idlc generates): gcc knows none of the sanitizer flags above.
configure_clang_tree() {
  local launcher=()
  if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
  cmake -S . -B build-fuzz -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DFAULTLINE_FUZZ=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DFAULTLINE_BUILD_BENCH=OFF \
    "${launcher[@]}" >/dev/null
}
