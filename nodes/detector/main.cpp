// detector: the reference detector for the synthetic scenes; faulted camera frames in,
// DetectionArray out.
#include "detector/detector_loop.hpp"
#include "runtime/node_main.hpp"

int main(int argc, char** argv) {
  namespace det = faultline::detector;
  return faultline::runtime::run_node<det::DetectorLoopConfig>(
      argc, argv, "detector",
      "reference colour detector: camera frames -> DetectionArray per sample",
      [](const auto& cfg, const auto& opts, auto log, const auto& stop) {
        det::DetectorLoop loop(cfg, opts.name, log);
        log->info("starting: {}", faultline::config::describe(cfg));
        const int rc = loop.run(stop);
        const auto& c = loop.counts();
        log->info(
            "done: {} frames, {} samples sent, {} send failures ({} refused by the sink), {} "
            "malformed, {} undecodable, {} boundaries lost, {} incomplete samples ({} key frames "
            "missing), {} stream breaks, {} shm frames overwritten",
            c.frames, c.arrays_sent, c.send_failures, loop.refused_by_peer(), c.malformed,
            c.undecodable, c.boundaries_lost, c.incomplete_samples, c.key_frames_missing,
            c.stream_breaks, c.shm_overwritten);
        return rc;
      });
}
