// Helpers shared by the libFuzzer targets (tests/<concern>/fuzz_*.cpp, cmake/fuzz.cmake).
#pragma once

#include <pthread.h>
#include <unistd.h>

#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>

namespace faultline::fuzz {

// A property the reader promises was broken: print it and abort, so libFuzzer (or the replay test)
// reports the input as a crash.
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz property violated: %s\n", what);
  std::abort();
}

// Runs `fn` on a thread with a 256 KiB stack and waits for it. A reader of nested text (JSON, YAML)
// must bound its depth; on the default 8 MB stack a recursive one only overflows on inputs far
// longer than the fuzzer tries, on a small stack it overflows on a few kilobytes of brackets, which
// the fuzzer does find. One worker thread serves every call (creating a thread per input would slow
// the fuzzer several times over).
inline void run_with_small_stack(const std::function<void()>& fn) {
  struct Worker {
    std::mutex mutex;
    std::condition_variable cv;
    const std::function<void()>* job = nullptr;
    bool done = false;
    Worker() {
      pthread_attr_t attr;
      pthread_attr_init(&attr);
      pthread_attr_setstacksize(&attr, 256 << 10);
      pthread_t thread;
      if (pthread_create(&thread, &attr, &Worker::loop, this) != 0) fail("pthread_create");
      pthread_attr_destroy(&attr);
      pthread_detach(thread);
    }
    static void* loop(void* arg) {
      auto* w = static_cast<Worker*>(arg);
      for (;;) {
        std::unique_lock<std::mutex> lock(w->mutex);
        w->cv.wait(lock, [w] { return w->job != nullptr; });
        (*w->job)();
        w->job = nullptr;
        w->done = true;
        w->cv.notify_all();
      }
    }
  };
  static auto* worker = new Worker();  // never destroyed: the thread outlives main's statics
  std::unique_lock<std::mutex> lock(worker->mutex);
  worker->job = &fn;
  worker->done = false;
  worker->cv.notify_all();
  worker->cv.wait(lock, [] { return worker->done; });
}

// /dev/shm when there is one (the fuzzer then does not wait on a disk), else the temp directory.
inline std::filesystem::path scratch_dir() {
  const std::filesystem::path shm("/dev/shm");
  return std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
}

// A scratch file for readers that take a path: one per process (libFuzzer runs one input at a
// time), in scratch_dir(). `write` replaces its content.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& stem) {
    path_ =
        (scratch_dir() / ("faultline_fuzz_" + stem + "_" + std::to_string(::getpid()))).string();
  }
  ~ScratchFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  const std::string& path() const { return path_; }
  void write(std::string_view bytes) const {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

 private:
  std::string path_;
};

}  // namespace faultline::fuzz
