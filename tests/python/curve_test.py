"""CURVE in the Python client (#22): keys from files as the C++ nodes read them, the right key passes every frame and
detection, a wrong key gets nothing and is refused (counted by the binding side's ZAP handler), bad key files are
named. The binding side is pyzmq here, with a ZAP handler that allows one client key, like Faultline's."""
import os
import subprocess
import sys
import tempfile
import threading
import unittest

import zmq
from zmq.utils import z85

sys.path.insert(0, os.path.dirname(__file__))
import pipeline_helpers  # noqa: E402  (puts clients/python on sys.path)
from faultline_client import CurveKeyError, FaultlineClient, read_curve_key  # noqa: E402


def write_pair(prefix):
    """PREFIX.secret and PREFIX.public, by `faultline keys generate` when it is built (the format the nodes read)."""
    if pipeline_helpers.BIN_DIR:
        subprocess.run([pipeline_helpers.binary("faultline"), "keys", "generate", prefix], check=True,
                       capture_output=True)
        return
    public, secret = zmq.curve_keypair()
    for suffix, key in ((".secret", secret), (".public", public)):
        with open(prefix + suffix, "w") as f:
            f.write(f"# Faultline CURVE key\n{key.decode()}\n")


class ZapHandler:
    """RFC 27 handler for the process's context: allows the CURVE client keys in `allowed`, counts the rest."""

    def __init__(self, ctx):
        self.allowed = set()  # 32-byte binary public keys
        self.accepted = 0
        self.refused = 0
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.ready = threading.Event()
        self.thread = threading.Thread(target=self.serve, args=(ctx,), daemon=True)
        self.thread.start()
        self.ready.wait(10)

    def serve(self, ctx):
        sock = ctx.socket(zmq.REP)
        sock.linger = 0
        sock.bind("inproc://zeromq.zap.01")
        self.ready.set()
        while not self.stop.is_set():
            if not sock.poll(50):
                continue
            request = sock.recv_multipart()
            ok = len(request) > 6 and request[5] == b"CURVE" and request[6] in self.allowed
            with self.lock:
                if ok:
                    self.accepted += 1
                else:
                    self.refused += 1
            sock.send_multipart([b"1.0", request[1], b"200" if ok else b"400", b"OK" if ok else b"not allowed",
                                 b"", b""])
        sock.close()

    def counts(self):
        with self.lock:
            return self.accepted, self.refused


def wait_until(done, timeout_s=30.0):
    """Polls `done` (each call may block briefly) until it holds or the bound passes."""
    import time
    deadline = time.monotonic() + timeout_s
    while not done():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


class CurveClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if not zmq.has("curve"):
            raise unittest.SkipTest("this libzmq has no CURVE support")
        cls.ctx = zmq.Context.instance()
        cls.zap = ZapHandler(cls.ctx)

    @classmethod
    def tearDownClass(cls):
        cls.zap.stop.set()
        cls.zap.thread.join(10)

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        for name in ("server", "good", "bad"):
            write_pair(os.path.join(self.dir, name))
        self.zap.allowed = {z85.decode(read_curve_key(self.key("good.public")))}
        self.zap.accepted = self.zap.refused = 0
        secret = read_curve_key(self.key("server.secret"))
        self.pub = self.server_socket(zmq.XPUB, secret)
        self.pull = self.server_socket(zmq.PULL, secret)
        self.frames = self.pub.getsockopt_string(zmq.LAST_ENDPOINT)
        self.detections = self.pull.getsockopt_string(zmq.LAST_ENDPOINT)
        self.clients = []

    def tearDown(self):
        for c in self.clients:
            c.close()
        self.pub.close(0)
        self.pull.close(0)
        self.tmp.cleanup()

    def key(self, name):
        return os.path.join(self.dir, name)

    def server_socket(self, kind, secret):
        s = self.ctx.socket(kind)
        s.linger = 0
        s.curve_server = True
        s.curve_secretkey = secret
        s.zap_domain = b"faultline-test"
        s.bind("tcp://127.0.0.1:*")
        return s

    def client(self, name, server_key="server"):
        c = FaultlineClient(self.frames, self.detections, curve_secret_key_file=self.key(name + ".secret"),
                            curve_server_public_key_file=self.key(server_key + ".public"))
        self.clients.append(c)
        return c

    def send_frames(self, msgs, count):
        for seq in range(1, count + 1):
            h = msgs.CameraFrame(camera="CAM_FRONT", encoding="bgr8", width=1, height=1, step=3, sample_token="s1",
                                 is_key_frame=True, payload_bytes=3)
            h.header.seq = seq
            h.header.publisher = "fault_injector"
            self.pub.send_multipart([b"/faulty/cam_front/image_raw", h.SerializeToString(), bytes([seq, 0, 0])])
        b = msgs.SampleBoundary(sample_token="s1", last_in_run=True)
        b.header.seq = 1
        self.pub.send_multipart([b"/sync/sample", b.SerializeToString()])

    def test_the_right_key_passes_every_frame_and_detection(self):
        c = self.client("good")
        for _ in range(3):  # frame prefix, sync and end topics subscribed: the handshake passed
            self.assertTrue(self.pub.poll(30000))
            self.pub.recv()
        self.send_frames(c.msgs, 7)
        samples = list(c.samples(timeout_s=30, decode=False))
        self.assertEqual([s.token for s in samples], ["s1"])
        self.assertEqual(c.frames_received, 7)
        self.assertEqual(c.transport_drops, 0)
        c.publish("s1", [])
        self.assertTrue(self.pull.poll(30000))
        topic, body = self.pull.recv_multipart()
        self.assertEqual((topic, c.msgs.DetectionArray.FromString(body).sample_token), (b"/detections", "s1"))
        self.assertEqual(self.zap.counts(), (2, 0))  # both sockets accepted, nobody refused

    def test_a_client_key_not_allowed_is_refused_and_gets_nothing(self):
        c = self.client("bad")
        self.assertTrue(wait_until(lambda: self.zap.counts()[1] >= 2))  # the SUB and the PUSH, each refused
        self.assertEqual(self.zap.counts(), (0, 2))
        self.assertEqual(self.pub.poll(0), 0)  # no subscription ever reached the publisher
        self.send_frames(c.msgs, 7)
        self.assertEqual(list(c.samples(timeout_s=0.5, decode=False)), [])
        self.assertEqual(c.frames_received, 0)

    def test_a_wrong_server_key_gets_nothing(self):
        c = self.client("good", server_key="bad")  # the server cannot answer this client's HELLO
        self.send_frames(c.msgs, 7)
        self.assertEqual(list(c.samples(timeout_s=0.5, decode=False)), [])
        self.assertEqual(c.frames_received, 0)
        self.assertEqual(self.zap.counts()[0], 0)

    def test_key_file_errors_name_the_file(self):
        def error_of(path):
            with self.assertRaises(CurveKeyError) as e:
                read_curve_key(path)
            return str(e.exception)

        self.assertIn(self.key("missing"), error_of(self.key("missing")))
        with open(self.key("big"), "w") as f:
            f.write("#" * 4097)
        self.assertIn("larger than the limit of 4 KiB", error_of(self.key("big")))
        self.assertIn("/dev/zero", error_of("/dev/zero"))
        self.assertIn(self.dir, error_of(self.dir))
        with open(self.key("short"), "w") as f:
            f.write("# a comment\nabc\n")
        self.assertIn("40-character Z85", error_of(self.key("short")))
        with open(self.key("two"), "w") as f:
            f.write(read_curve_key(self.key("good.public")).decode() + "\n" +
                    read_curve_key(self.key("bad.public")).decode() + "\n")
        self.assertIn("more than one key", error_of(self.key("two")))
        with self.assertRaises(CurveKeyError) as e:
            FaultlineClient(self.frames, self.detections, curve_secret_key_file=self.key("good.secret"))
        self.assertIn("curve_server_public_key_file", str(e.exception))


if __name__ == "__main__":
    unittest.main()
