"""Unit tests of the Python client over inproc sockets (no nodes involved)."""
import os
import sys
import unittest

import numpy as np
import zmq

sys.path.insert(0, os.path.dirname(__file__))
import pipeline_helpers  # noqa: E402,F401  (puts clients/python on sys.path)
from faultline_client import FaultlineClient  # noqa: E402
from faultline_client.client import decode_payload  # noqa: E402


class ClientTest(unittest.TestCase):
    count = 0

    def setUp(self):
        ClientTest.count += 1  # fresh endpoints per test: closing a socket releases its name asynchronously
        frames, detections = f"inproc://frames-{self.count}", f"inproc://detections-{self.count}"
        self.ctx = zmq.Context.instance()
        self.pub = self.ctx.socket(zmq.XPUB)
        self.pub.bind(frames)
        self.pull = self.ctx.socket(zmq.PULL)
        self.pull.bind(detections)
        self.client = FaultlineClient(frames, detections)
        self.msgs = self.client.msgs
        for _ in range(2):  # both subscriptions reached the publisher: no slow-joiner loss
            self.assertTrue(self.pub.poll(5000))
            self.pub.recv()

    def tearDown(self):
        self.client.close()
        self.pub.close(0)
        self.pull.close(0)

    def send_frame(self, camera, seq, token, pixels, key=True):
        h = self.msgs.CameraFrame()
        h.header.seq = seq
        h.header.publisher = "fault_injector"
        h.camera = camera
        h.encoding = "bgr8"
        h.height, h.width = pixels.shape[:2]
        h.step = h.width * 3
        h.sample_token = token
        h.is_key_frame = key
        h.intrinsics.extend([100, 0, 2, 0, 100, 2, 0, 0, 1])
        h.sensor_to_ego.rotation.w = 1
        h.ego_pose.rotation.w = 1
        h.payload_bytes = pixels.nbytes
        self.pub.send_multipart([b"/faulty/" + camera.lower().encode() + b"/image_raw", h.SerializeToString(),
                                 pixels.tobytes()])

    def send_boundary(self, token, last=False):
        b = self.msgs.SampleBoundary(sample_token=token, scene_name="scene-0103", last_in_run=last)
        self.pub.send_multipart([b"/sync/sample", b.SerializeToString()])

    def test_groups_frames_per_sample_and_counts_gaps_and_malformed(self):
        img = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
        self.send_frame("CAM_FRONT", 1, "s1", img)
        self.send_frame("CAM_BACK", 1, "s1", img)  # seq counts per (publisher, topic)
        self.pub.send_multipart([b"/faulty/cam_back/image_raw", b"\xff\xfe garbage"])  # wrong frame count
        self.send_boundary("s1")
        self.send_frame("CAM_FRONT", 4, "s2", img)  # CAM_FRONT seq 2 and 3 lost in transport
        self.send_boundary("s2", last=True)
        samples = list(self.client.samples(timeout_s=5))
        self.assertEqual([s.token for s in samples], ["s1", "s2"])
        self.assertEqual(sorted(samples[0].frames), ["CAM_BACK", "CAM_FRONT"])
        np.testing.assert_array_equal(samples[0].frames["CAM_FRONT"].image, img)
        self.assertEqual(samples[0].frames["CAM_FRONT"].intrinsics[0, 0], 100)
        self.assertTrue(samples[1].last_in_run)
        self.assertEqual(self.client.transport_drops, 2)
        self.assertEqual(self.client.malformed, 1)

    def test_a_lost_boundary_is_counted_and_its_sample_rebuilt_from_its_frames(self):
        # #22 item 6: the boundary of s2 (seq 2) is lost; its frames still arrived. s3's frames were all lost too.
        img = np.zeros((2, 2, 3), dtype=np.uint8)

        def boundary(token, seq, last=False):
            b = self.msgs.SampleBoundary(sample_token=token, scene_name="scene-0103", last_in_run=last,
                                         timestamp_us=seq * 500_000)
            b.header.seq = seq
            b.header.publisher = "fault_injector"
            self.pub.send_multipart([b"/sync/sample", b.SerializeToString()])

        self.send_frame("CAM_FRONT", 1, "s1", img)
        boundary("s1", 1)
        self.send_frame("CAM_FRONT", 2, "s2", img)
        self.send_frame("CAM_BACK", 1, "s2", img)
        self.send_frame("CAM_FRONT", 3, "s4", img)
        boundary("s4", 4, last=True)  # boundaries 2 (s2) and 3 (s3) lost
        samples = list(self.client.samples(timeout_s=5))
        self.assertEqual([s.token for s in samples], ["s1", "s2", "s4"])
        self.assertEqual([s.boundary_lost for s in samples], [False, True, False])
        self.assertEqual(sorted(samples[1].frames), ["CAM_BACK", "CAM_FRONT"])
        self.assertEqual(sorted(samples[2].frames), ["CAM_FRONT"])
        self.assertEqual(self.client.boundaries_lost, 2)
        self.assertEqual(self.client.transport_drops, 0)

    def test_stream_end_ends_the_run_at_once_and_is_not_malformed(self):
        # The end wait is long, so only the StreamEnd can end the iteration before the timeout.
        self.client.end_wait_s = 30
        img = np.zeros((2, 2, 3), dtype=np.uint8)
        self.send_frame("CAM_FRONT", 1, "s1", img)
        b = self.msgs.SampleBoundary(sample_token="s1", scene_name="scene-0103", last_in_run=True,
                                     stream_end_follows=True)
        self.pub.send_multipart([b"/sync/sample", b.SerializeToString()])
        self.send_frame("CAM_FRONT", 2, "s1", img, key=False)  # a trailing sweep of the last sample
        self.pub.send_multipart([b"/sync/end", self.msgs.StreamEnd().SerializeToString()])
        samples = list(self.client.samples(timeout_s=20))
        self.assertEqual([s.token for s in samples], ["s1"])
        self.assertEqual(self.client.malformed, 0)
        self.assertEqual(self.client.frames_received, 2)

    def test_publish_sends_a_detection_array(self):
        self.client.publish("s1", [{"translation": [1, 2, 0.5], "size": [1.9, 4.6, 1.7], "rotation": [1, 0, 0, 0],
                                    "velocity": [0.5, 0], "detection_name": "car", "detection_score": 0.8,
                                    "attribute_name": "vehicle.moving"}], processing_ns=42)
        self.assertTrue(self.pull.poll(5000))
        topic, body = self.pull.recv_multipart()
        self.assertEqual(topic, b"/detections")
        arr = self.msgs.DetectionArray.FromString(body)
        self.assertEqual(arr.sample_token, "s1")
        self.assertEqual(arr.processing_ns, 42)
        self.assertEqual(list(arr.detections[0].translation), [1, 2, 0.5])
        self.assertEqual(arr.detections[0].detection_name, "car")

    def test_decode_payload_honours_step_and_rgb(self):
        h = self.msgs.CameraFrame(encoding="rgb8", width=2, height=1, step=8)
        payload = bytes([1, 2, 3, 4, 5, 6, 0, 0])
        out = decode_payload(h, memoryview(payload))
        np.testing.assert_array_equal(out, [[[3, 2, 1], [6, 5, 4]]])


if __name__ == "__main__":
    unittest.main()
