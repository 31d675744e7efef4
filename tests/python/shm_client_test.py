"""The Python client's shared-memory path against a ring written here from the documented layout
(docs/protocol.md §16), over inproc sockets (no nodes involved)."""
import mmap
import os
import struct
import sys
import tempfile
import unittest

import numpy as np
import zmq

sys.path.insert(0, os.path.dirname(__file__))
import pipeline_helpers  # noqa: E402,F401  (puts clients/python on sys.path)
from faultline_client import FaultlineClient  # noqa: E402

SLOTS, SLOT_BYTES, STRIDE, DATA, SLOT_HEADER = 2, 60, 4096, 4096, 64


class Ring:
    """A version-1 ring written by hand: header, then SLOTS slots of STRIDE bytes."""

    def __init__(self, path, ring_id=77):
        self.path, self.ring_id, self.position = path, ring_id, 0
        with open(path, "wb") as f:
            f.truncate(DATA + SLOTS * STRIDE)
        fd = os.open(path, os.O_RDWR)
        self.mm = mmap.mmap(fd, 0)
        os.close(fd)
        struct.pack_into("<QIIQQQQQQQ", self.mm, 0, 0x474E524D4853464C, 1, SLOTS, SLOT_BYTES, STRIDE, DATA, ring_id,
                         os.getpid(), 0, SLOT_HEADER)

    def write(self, pixels: bytes):
        slot = self.position % SLOTS
        start = DATA + slot * STRIDE
        sequence = 2 * self.position + 2
        struct.pack_into("<Q", self.mm, start, sequence - 1)
        self.mm[start + SLOT_HEADER:start + SLOT_HEADER + len(pixels)] = pixels
        struct.pack_into("<QQ", self.mm, start, sequence, len(pixels))
        self.position += 1
        return slot, sequence, start + SLOT_HEADER


class ShmClientTest(unittest.TestCase):
    count = 0

    def setUp(self):
        ShmClientTest.count += 1
        frames = f"inproc://shm-frames-{self.count}"
        self.ctx = zmq.Context.instance()
        self.pub = self.ctx.socket(zmq.XPUB)
        self.pub.bind(frames)
        self.client = FaultlineClient(frames, f"inproc://shm-det-{self.count}")
        self.msgs = self.client.msgs
        for _ in range(3):  # /faulty/, /sync/sample, /sync/end reached the publisher
            self.assertTrue(self.pub.poll(5000))
            self.pub.recv()
        self.tmp = tempfile.mkdtemp(prefix="faultline-shm-client-")
        self.ring = Ring(os.path.join(self.tmp, "ring"))

    def tearDown(self):
        self.client.close()
        self.pub.close(0)

    def send(self, seq, pixels, key=True, token="s1"):
        slot, sequence, offset = self.ring.write(pixels.tobytes())
        h = self.msgs.CameraFrame(camera="CAM_FRONT", encoding="bgr8", height=pixels.shape[0], width=pixels.shape[1],
                                  step=pixels.shape[1] * 3, sample_token=token, is_key_frame=key,
                                  payload_bytes=pixels.nbytes)
        h.header.seq, h.header.publisher = seq, "fault_injector"
        h.intrinsics.extend([1, 0, 0, 0, 1, 0, 0, 0, 1])
        h.shm.path, h.shm.ring_id, h.shm.slot, h.shm.sequence, h.shm.offset = \
            self.ring.path, self.ring.ring_id, slot, sequence, offset
        self.pub.send_multipart([b"/faulty/cam_front/image_raw", h.SerializeToString()])

    def end(self):
        self.pub.send_multipart([b"/sync/end", self.msgs.StreamEnd().SerializeToString()])

    def test_frames_are_views_into_the_ring_and_overwrites_are_counted(self):
        imgs = [np.full((4, 5, 3), i, np.uint8) for i in range(4)]
        self.send(1, imgs[0])
        self.send(2, imgs[1])
        self.send(3, imgs[2])  # reuses slot 0 before frame 1 is read: overwritten before read
        self.end()
        got = list(self.client.frames(timeout_s=5))
        self.assertEqual([f.header.seq for f in got], [2, 3])
        np.testing.assert_array_equal(got[0].image, imgs[1])
        ring = next(iter(self.client.shm.rings.values()))
        self.assertTrue(np.shares_memory(got[0].image, ring.bytes))  # no copy
        self.assertFalse(got[0].image.flags.writeable)
        self.assertTrue(got[0].intact())
        self.ring.write(imgs[3].tobytes())  # slot 1 again, while frame 2 is held
        self.assertFalse(got[0].intact())
        self.assertTrue(got[1].intact())
        self.assertEqual((self.client.frames_received, self.client.transport_drops), (2, 0))
        self.assertEqual((self.client.shm.overwritten_before_read, self.client.shm.overwritten_during_use), (1, 1))
        self.assertEqual(self.client.shm_overwritten, 2)

    def test_samples_keep_key_frames_from_the_ring_and_a_bad_descriptor_is_malformed(self):
        img = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
        self.send(1, img)
        h = self.msgs.CameraFrame(camera="CAM_BACK", encoding="bgr8", height=4, width=5, step=15, payload_bytes=60)
        h.shm.path, h.shm.ring_id, h.shm.slot, h.shm.sequence, h.shm.offset = self.ring.path, 77, 1, 2, 123
        self.pub.send_multipart([b"/faulty/cam_back/image_raw", h.SerializeToString()])  # offset not the slot's
        self.pub.send_multipart([b"/sync/sample", self.msgs.SampleBoundary(sample_token="s1",
                                                                           last_in_run=True).SerializeToString()])
        samples = list(self.client.samples(timeout_s=5))
        self.assertEqual(list(samples[0].frames), ["CAM_FRONT"])
        np.testing.assert_array_equal(samples[0].frames["CAM_FRONT"].image, img)
        self.assertEqual(self.client.malformed, 1)

    def test_a_missing_ring_counts_the_frame_as_lost(self):
        self.send(1, np.zeros((4, 5, 3), np.uint8))
        os.unlink(self.ring.path)  # the publisher exited before the frame was read
        self.end()
        self.assertEqual(list(self.client.frames(timeout_s=5)), [])
        self.assertEqual((self.client.shm_overwritten, self.client.frames_received, self.client.malformed), (1, 0, 0))


if __name__ == "__main__":
    unittest.main()
