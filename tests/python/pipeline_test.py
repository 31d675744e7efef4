"""End to end: player -> injector -> a Python detector process -> sink, then the official metric."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from pipeline_helpers import Pipeline, REPO, binary, count_camera_frames, synth_dataset  # noqa: E402

EXAMPLES = os.path.join(REPO, "clients", "python", "examples")


class PipelineTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.data = synth_dataset(tempfile.mkdtemp(prefix="faultline-synth-"), scenes=2, seconds=2)
        cls.frames, cls.samples = count_camera_frames(cls.data)

    def test_python_detector_in_lockstep_is_scored(self):
        p = Pipeline(self.data, lockstep=True, rate=0.0, subscribers=2)
        try:
            p.start_sink()
            p.start_injector()
            p.start_external("python_detector", ["/usr/bin/python3", os.path.join(EXAMPLES, "simple_detector.py"),
                                                 "--frames", p.frames_ep, "--detections", p.detections_ep,
                                                 "--idle-timeout", "60"])
            p.start_player()
            self.assertEqual(p.wait("nusc_player"), 0, p.log("nusc_player"))
            self.assertEqual(p.wait("python_detector"), 0, p.log("python_detector"))
            self.assertEqual(p.wait("detection_sink"), 0, p.log("detection_sink"))
            self.assertEqual(p.wait("fault_injector", timeout=30), 0, p.log("fault_injector"))
        finally:
            p.stop()
        results = json.load(open(p.results))
        self.assertEqual(len(results["results"]), self.samples)
        detector_log = p.log("python_detector")
        forwarded = p.injector_out()
        self.assertEqual(forwarded, self.frames)  # sweeps after the last sample included
        self.assertIn(f"{self.samples} samples, {forwarded} frames, 0 transport drops", detector_log)
        out = os.path.join(p.tmp, "score")
        r = subprocess.run([binary("faultline"), "score", "--results", p.results, "--dataroot", self.data,
                            "--version", "v1.0-mini", "--eval_set", "mini_val", "--output_dir", out],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        summary = json.load(open(os.path.join(out, "metrics_summary.json")))
        self.assertGreater(summary["mean_ap"], 0.05)  # it really detects objects from pixels
        self.assertGreater(summary["nd_score"], 0.05)

    def test_python_subscriber_reports_its_drops_in_real_time(self):
        p = Pipeline(self.data, lockstep=False, rate=1.0, subscribers=2)
        counter = os.path.join(os.path.dirname(__file__), "count_subscriber.py")
        try:
            p.start_sink()
            p.start_injector()
            p.start_external("subscriber", ["/usr/bin/python3", counter, p.frames_ep])
            p.start_player()
            self.assertEqual(p.wait("nusc_player"), 0, p.log("nusc_player"))
            self.assertEqual(p.wait("subscriber", timeout=60), 0, p.log("subscriber"))
            self.assertEqual(p.wait("fault_injector", timeout=30), 0, p.log("fault_injector"))
        finally:
            p.stop()
        counts = json.loads(p.log("subscriber").strip().splitlines()[-1])
        # Every frame the injector sent is either received or reported as a seq-gap drop.
        self.assertEqual(counts["received"] + counts["transport_drops"], p.injector_out(), counts)
        self.assertEqual(counts["samples"], self.samples)


if __name__ == "__main__":
    unittest.main()
