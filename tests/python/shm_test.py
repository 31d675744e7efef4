"""End to end: the injector publishes decoded bgr8 through its shared-memory ring and the official client receives
the same frames, byte for byte, as from an injector on the plain ZeroMQ path; ring files are removed at exit and a
stale one left by a killed injector does not stop a restart."""
import concurrent.futures
import glob
import hashlib
import os
import signal
import struct
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from pipeline_helpers import binary, count_camera_frames, synth_dataset  # noqa: E402
from faultline_client import FaultlineClient  # noqa: E402

WIDTH, HEIGHT = 320, 180


class ShmTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        root = tempfile.mkdtemp(prefix="faultline-synth-")
        subprocess.run([binary("faultline"), "dataset", "synth", "--out", root, "--scenes", "1", "--seconds", "2",
                        "--seed", "5", "--width", str(WIDTH), "--height", str(HEIGHT)], check=True,
                       capture_output=True)
        cls.data = root
        cls.frames, _ = count_camera_frames(root)

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="faultline-shm-")
        self.env = dict(os.environ, FAULTLINE_RUN_DIR=os.path.join(self.tmp, "graph"))
        self.procs = []

    def tearDown(self):
        for p in self.procs:
            if p.poll() is None:
                p.kill()
                p.wait()

    def start(self, name, args):
        log = open(os.path.join(self.tmp, name + ".log"), "w")
        p = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=self.env)
        self.procs.append(p)
        return p

    def log(self, name):
        return open(os.path.join(self.tmp, name + ".log")).read()

    def injector(self, name, output, shm, extra=()):
        args = [binary("fault_injector"), "--name", name, "-p", f"input_endpoints:=[ipc://{self.tmp}/player]",
                "-p", f"output_endpoint:={output}", "-p", "decode:=true", "-p", "input_hwm:=2000",
                "-p", "output_hwm:=2000", "-p", "wait_subscribers:=1", "-p", "wait_timeout_ms:=60000",
                "-p", "workers:=1"]
        if shm:
            args += ["-p", "output_shm:=true", "-p", f"output_shm_dir:={self.tmp}", "-p", "shm_slots:=2048",
                     "-p", f"shm_slot_bytes:={WIDTH * HEIGHT * 3}"]
        return self.start(name, args + list(extra))

    def rings(self):
        return glob.glob(os.path.join(self.tmp, "faultline-*.ring"))

    def ring_id(self):
        with open(self.rings()[0], "rb") as f:
            return struct.unpack_from("<Q", f.read(48), 40)[0]  # header field ring_id (docs/protocol.md §16)

    @staticmethod
    def receive(client):
        """(camera, source_seq) -> (topic seq, sha256 of the pixels), checking each frame is intact after use."""
        got = {}
        for f in client.frames(timeout_s=60):
            assert f.encoding == "bgr8" and f.image.shape == (HEIGHT, WIDTH, 3), (f.encoding, f.image.shape)
            digest = hashlib.sha256(f.image.tobytes()).hexdigest()
            assert f.intact()
            got[(f.camera, f.source_seq)] = (f.header.seq, digest)
        return got

    def test_shm_frames_are_byte_identical_to_zeromq_and_counted_exactly(self):
        plain = self.injector("inj_zmq", f"ipc://{self.tmp}/zmq", shm=False)
        shm = self.injector("inj_shm", f"ipc://{self.tmp}/shm", shm=True)
        a = FaultlineClient(f"ipc://{self.tmp}/zmq", "ipc:///dev/null/unused", rcv_hwm=4000)
        b = FaultlineClient(f"ipc://{self.tmp}/shm", "ipc:///dev/null/unused", rcv_hwm=4000)
        player = self.start("nusc_player", [binary("nusc_player"), "-p", f"dataroot:={self.data}", "-p",
                                            f"endpoint:=ipc://{self.tmp}/player", "-p", "rate:=0", "-p", "hwm:=2000",
                                            "-p", "wait_subscribers:=2", "-p", "wait_timeout_ms:=60000"])
        # Both read at once: an injector removes its ring file when it exits, so a client that has not mapped the
        # ring by then finds its frames gone (counted in shm_overwritten; reading b after a lost them a third of the
        # time on a loaded machine).
        with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
            zmq_future, shm_future = pool.submit(self.receive, a), pool.submit(self.receive, b)
            via_zmq, via_shm = zmq_future.result(), shm_future.result()
        self.assertEqual(player.wait(timeout=120), 0, self.log("nusc_player"))
        self.assertEqual(plain.wait(timeout=60), 0, self.log("inj_zmq"))
        self.assertEqual(shm.wait(timeout=60), 0, self.log("inj_shm"))
        self.assertIn("camera frames through shared memory", self.log("inj_shm"))
        self.assertEqual(len(via_zmq), self.frames, self.log("inj_zmq"))
        self.assertEqual(via_shm, via_zmq)  # same frames, same pixels, same per-topic seq
        for c in (a, b):
            self.assertEqual((c.frames_received, c.transport_drops, c.malformed), (self.frames, 0, 0))
        self.assertEqual(b.shm_overwritten, 0)
        self.assertEqual(len(b.shm.rings), 1)
        self.assertEqual(os.path.dirname(next(iter(b.shm.rings))), self.tmp)
        per_topic = {}
        for (camera, _), (seq, _) in via_shm.items():
            per_topic.setdefault(camera, []).append(seq)
        for camera, seqs in per_topic.items():
            self.assertEqual(sorted(seqs), list(range(1, len(seqs) + 1)), camera)
        self.assertEqual(self.rings(), [])  # removed at exit
        a.close()
        b.close()

    def test_a_stale_ring_of_a_killed_injector_does_not_stop_a_restart(self):
        endpoint = f"ipc://{self.tmp}/shm"
        first = self.injector("inj_a", endpoint, shm=True)
        deadline = time.monotonic() + 60
        while not self.rings() and time.monotonic() < deadline:
            time.sleep(0.05)
        self.assertEqual(len(self.rings()), 1, self.log("inj_a"))
        first.send_signal(signal.SIGKILL)
        first.wait()
        self.assertEqual(len(self.rings()), 1)  # left behind
        stale_id = self.ring_id()
        second = self.injector("inj_a", endpoint, shm=True)
        deadline = time.monotonic() + 60
        while "camera frames through shared memory" not in self.log("inj_a") and second.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.05)
        self.assertIn("camera frames through shared memory", self.log("inj_a"))
        self.assertIsNone(second.poll())
        self.assertEqual(len(self.rings()), 1)
        self.assertNotEqual(self.ring_id(), stale_id)  # a fresh ring replaced the stale one
        second.send_signal(signal.SIGTERM)
        self.assertEqual(second.wait(timeout=30), 0, self.log("inj_a"))
        self.assertEqual(self.rings(), [])


if __name__ == "__main__":
    unittest.main()
