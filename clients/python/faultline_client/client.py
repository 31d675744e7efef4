"""Wire protocol of Faultline (docs/protocol.md) for Python perception stacks.

Frames arrive on a SUB socket as [topic][CameraFrame][payload]; after the last frame of a key-frame
sample the source sends [/sync/sample][SampleBoundary] on the same socket, so frames and boundaries
arrive in order. Detections go to the sink on a PUSH socket as [/detections][DetectionArray]. In
lockstep replays the sink acknowledges each sample to the player: sending the DetectionArray is the
detector's acknowledgement.
"""
import dataclasses
import glob
import importlib
import os
import sys
import time
from typing import Dict, Iterator, List, Optional, Tuple

import numpy as np
import zmq
from zmq.utils import z85

from .shm import ShmReader

# Key files as the C++ nodes read them (lib/transport/access.hpp): one 40-character Z85 key, '#' comment lines and
# blank lines ('#' is a Z85 digit, but never the first of a key: a group of five digits stays below 2**32).
MAX_KEY_FILE_BYTES = 4096
CAMERAS = ("CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT", "CAM_BACK", "CAM_BACK_LEFT", "CAM_BACK_RIGHT")
_RAW_CHANNELS = {"bgr8": 3, "rgb8": 3, "mono8": 1}


def load_messages(msgs_dir: Optional[str] = None):
    """Imports the generated *_pb2 modules; returns a namespace with CameraFrame, SampleBoundary, ...

    Looks in msgs_dir, $FAULTLINE_PYTHON_MSGS, then build*/python/faultline_msgs next to the repo.
    """
    candidates = [msgs_dir, os.environ.get("FAULTLINE_PYTHON_MSGS")]
    repo = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
    candidates += sorted(glob.glob(os.path.join(repo, "build*", "python", "faultline_msgs")))
    for path in candidates:
        if path and os.path.isfile(os.path.join(path, "camera_frame_pb2.py")):
            if path not in sys.path:
                sys.path.insert(0, path)  # generated modules import each other by bare name
            ns = type("Messages", (), {})()
            for module, names in (("camera_frame_pb2", ("CameraFrame", "SampleBoundary", "StreamEnd")),
                                  ("detection_pb2", ("Detection", "DetectionArray", "SampleAck")),
                                  ("fault_pb2", ("FaultEvent", "FaultState")),
                                  ("header_pb2", ("Header",))):
                mod = importlib.import_module(module)
                for name in names:
                    setattr(ns, name, getattr(mod, name))
            return ns
    raise ImportError("Faultline protobuf modules not found: build the project (cmake --build build) or set "
                      "FAULTLINE_PYTHON_MSGS to build/python/faultline_msgs")


@dataclasses.dataclass
class Frame:
    camera: str
    image: Optional[np.ndarray]      # H x W x 3 BGR (or H x W mono); None when a JPEG could not be decoded
    encoding: str                    # encoding on the wire ("jpeg", "bgr8", ...)
    intrinsics: np.ndarray           # 3 x 3
    sensor_to_ego: np.ndarray        # 4 x 4
    ego_to_global: np.ndarray        # 4 x 4
    capture_stamp_ns: int
    source_seq: int
    sample_token: str
    is_key_frame: bool
    fault: object                    # faultline.msgs.FaultState (what the injector did)
    header: object = None            # faultline.msgs.Header: seq, publisher, publish_mono_ns, ...
    # Set when the pixels are mapped from the publisher's shared-memory ring (docs/protocol.md §16).
    _shm: Optional[Tuple[ShmReader, object]] = dataclasses.field(default=None, repr=False)

    def intact(self) -> bool:
        """False when `image` lives in a shared-memory ring and its slot was overwritten since the frame was
        received (the pixels may be torn; counted in FaultlineClient.shm_overwritten). Check it after using image.
        Always True for frames that came over ZeroMQ."""
        return self._shm is None or self._shm[0].intact(self._shm[1])


@dataclasses.dataclass
class Sample:
    token: str
    scene_name: str
    timestamp_us: int
    frames: Dict[str, Frame]          # latest frame per camera for this sample (missing when dropped)
    last_in_run: bool
    # True when this sample's boundary was lost in transport: the sample is rebuilt from its key frames when the
    # next boundary arrives, timestamp_us is then the earliest frame's capture time and scene_name that of the
    # next boundary. A sample whose boundary and frames were all lost is only counted (boundaries_lost).
    boundary_lost: bool = False


def _quat_to_matrix(q) -> np.ndarray:
    w, x, y, z = q.w, q.x, q.y, q.z
    n = np.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _transform(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = _quat_to_matrix(t.rotation)
    m[:3, 3] = (t.translation.x, t.translation.y, t.translation.z)
    return m


class CurveKeyError(ValueError):
    """A CURVE key file that cannot be used; the message names the file."""


def _is_z85_key(text: str) -> bool:
    if len(text) != 40:
        return False
    try:
        return len(z85.decode(text.encode("ascii"))) == 32
    except (ValueError, KeyError, UnicodeEncodeError):
        return False


def read_curve_key(path: str) -> bytes:
    """The Z85 key (40 bytes) held in a key file written by `faultline keys generate`."""
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_KEY_FILE_BYTES + 1)
    except OSError as e:
        raise CurveKeyError(f"CURVE key file {path}: cannot read: {e.strerror}") from None
    if len(data) > MAX_KEY_FILE_BYTES:
        raise CurveKeyError(f"CURVE key file {path}: larger than the limit of {MAX_KEY_FILE_BYTES // 1024} KiB")
    keys = []
    for line in data.decode("ascii", errors="replace").splitlines():
        line = line.strip(" \t\r")
        if line and not line.startswith("#"):
            keys.append(line)
    if len(keys) > 1:
        raise CurveKeyError(f"CURVE key file {path}: more than one key")
    if not keys or not _is_z85_key(keys[0]):
        raise CurveKeyError(f"CURVE key file {path}: expected one 40-character Z85 key (faultline keys generate)")
    return keys[0].encode("ascii")


def curve_client_options(curve_secret_key_file: Optional[str],
                         curve_server_public_key_file: Optional[str]) -> Dict[int, bytes]:
    """Socket options that make a socket a CURVE client (set them before it connects), as a connecting C++ node
    with the same two parameters; {} without curve_secret_key_file."""
    if not curve_secret_key_file:
        return {}
    if not zmq.has("curve"):
        raise CurveKeyError("curve_secret_key_file is set but this libzmq has no CURVE support")
    if not curve_server_public_key_file:
        raise CurveKeyError("curve_server_public_key_file: required to connect with CURVE (the binding peer's key)")
    secret = read_curve_key(curve_secret_key_file)
    try:
        public = zmq.curve_public(secret)
    except zmq.ZMQError:
        raise CurveKeyError(f"CURVE key file {curve_secret_key_file}: not a valid secret key") from None
    return {zmq.CURVE_SERVERKEY: read_curve_key(curve_server_public_key_file), zmq.CURVE_PUBLICKEY: public,
            zmq.CURVE_SECRETKEY: secret}


def decode_payload(header, payload: memoryview) -> Optional[np.ndarray]:
    """Pixels of a frame as numpy (BGR order for colour); JPEG is decoded with OpenCV."""
    if header.encoding == "jpeg":
        import cv2  # python3-opencv
        return cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_COLOR)
    channels = _RAW_CHANNELS.get(header.encoding)
    if channels is None:
        raise ValueError(f"unsupported encoding {header.encoding!r}")
    rows = np.frombuffer(payload, np.uint8).reshape(header.height, header.step)
    img = rows[:, : header.width * channels].reshape(header.height, header.width, channels)
    if header.encoding == "rgb8":
        img = img[:, :, ::-1]
    return img if channels == 3 else img[:, :, 0]


class FaultlineClient:
    """Subscribes to faulted frames and publishes detections.

    frames_endpoint / detections_endpoint default to $FAULTLINE_FRAMES and $FAULTLINE_DETECTIONS
    (set by `faultline benchmark --detector-cmd`), else tcp://127.0.0.1:5601 and :5602.
    With curve_secret_key_file (this client's secret key) and curve_server_public_key_file (the injector's and the
    sink's server key), both sockets use ZeroMQ CURVE, as the C++ nodes' parameters of the same names do; a key
    file that cannot be used raises CurveKeyError naming it. A refused key shows as no traffic at all (libzmq does
    not report it to the client).
    """

    def __init__(self, frames_endpoint: Optional[str] = None, detections_endpoint: Optional[str] = None,
                 frame_prefix: Optional[str] = None, sync_topic: str = "/sync/sample",
                 end_topic: str = "/sync/end", end_wait_s: float = 10.0, detector_name: str = "python", rcv_hwm: int = 256, msgs_dir: Optional[str] = None,
                 curve_secret_key_file: Optional[str] = None, curve_server_public_key_file: Optional[str] = None):
        self.msgs = load_messages(msgs_dir)
        self.frames_endpoint = frames_endpoint or os.environ.get("FAULTLINE_FRAMES", "tcp://127.0.0.1:5601")
        self.detections_endpoint = detections_endpoint or os.environ.get("FAULTLINE_DETECTIONS",
                                                                         "tcp://127.0.0.1:5602")
        self.frame_prefix = (frame_prefix or os.environ.get("FAULTLINE_FRAME_PREFIX", "/faulty/")).encode()
        self.sync_topic = sync_topic.encode()
        self.end_topic = end_topic.encode()
        self.end_wait_s = end_wait_s
        self.detector_name = detector_name
        curve = curve_client_options(curve_secret_key_file, curve_server_public_key_file)  # raises before any socket
        self.ctx = zmq.Context.instance()
        self.sub = self.ctx.socket(zmq.SUB)
        self.sub.setsockopt(zmq.RCVHWM, rcv_hwm)
        self.sub.setsockopt(zmq.LINGER, 0)
        self.sub.setsockopt(zmq.MAXMSGSIZE, 64 << 20)
        self.sub.setsockopt(zmq.SUBSCRIBE, self.frame_prefix)
        self.sub.setsockopt(zmq.SUBSCRIBE, self.sync_topic)
        self.sub.setsockopt(zmq.SUBSCRIBE, self.end_topic)
        for option, value in curve.items():
            self.sub.setsockopt(option, value)
        self.sub.connect(self.frames_endpoint)
        self.push = self.ctx.socket(zmq.PUSH)
        self.push.setsockopt(zmq.LINGER, 2000)
        self.push.setsockopt(zmq.IMMEDIATE, 1)
        for option, value in curve.items():
            self.push.setsockopt(option, value)
        self.push.connect(self.detections_endpoint)
        self.seq = 0
        self.malformed = 0
        self.frames_received = 0
        self.transport_drops = 0
        self.boundaries_lost = 0  # SampleBoundary messages lost in transport (seq gaps on the sync topic)
        self._last_seq: Dict[bytes, int] = {}
        self.shm = ShmReader()  # maps publishers' shared-memory rings on first use

    @property
    def shm_overwritten(self) -> int:
        """Shared-memory frames lost because their slot was reused before they were read (not in frames_received)
        or while they were in use (Frame.intact() False)."""
        return self.shm.overwritten

    def close(self):
        self.sub.close(0)
        self.push.close()

    def _gap(self, topic: bytes, header) -> int:
        """Messages lost before this one on (topic, publisher), from the publisher's seq."""
        key = topic + b"|" + header.publisher.encode()
        last = self._last_seq.get(key)
        self._last_seq[key] = header.seq
        return header.seq - last - 1 if last is not None and header.seq > last + 1 else 0

    def _count_gap(self, topic: bytes, header) -> None:
        self.transport_drops += self._gap(topic, header)

    def _frame(self, topic: bytes, parts, h, decode: bool, keep: bool) -> Optional[Frame]:
        """Checks and counts one camera frame message (header `h` parsed): [topic][CameraFrame][payload], or
        [topic][CameraFrame] with the pixels in a shared-memory ring. None when it is not kept (keep False, or its
        shared-memory slot was already reused: counted in shm_overwritten, not in frames_received). Raises
        ValueError on a malformed message."""
        shm = len(parts) == 2
        if shm and not h.HasField("shm"):
            raise ValueError("2-frame camera message without shm descriptor")
        payload = None if shm else parts[2].buffer
        if payload is not None and h.payload_bytes and h.payload_bytes != len(payload):
            raise ValueError("payload size mismatch")
        self._count_gap(topic, h.header)
        if shm:
            payload = self.shm.pixels(h)  # a view into the ring, no copy
            if payload is None:
                return None
        self.frames_received += 1
        if not keep:
            return None
        image = decode_payload(h, payload) if decode else None
        return Frame(h.camera, image, h.encoding, np.array(h.intrinsics, float).reshape(3, 3),
                     _transform(h.sensor_to_ego), _transform(h.ego_pose), h.header.capture_stamp_ns, h.source_seq,
                     h.sample_token, h.is_key_frame, h.fault, h.header, (self.shm, h) if shm else None)

    def frames(self, timeout_s: Optional[float] = None, decode: bool = True) -> Iterator[Frame]:
        """Yields every camera frame (key frames and sweeps) in arrival order, e.g. for temporal models; boundaries
        are only counted (boundaries_lost). Ends at /sync/end, at a last_in_run boundary without a stream end
        following, or after timeout_s without traffic. With shared memory the image is a view into the ring: use it
        before about shm slot_count more frames arrive, and check Frame.intact() after use."""
        poller = zmq.Poller()
        poller.register(self.sub, zmq.POLLIN)
        while True:
            if self.sub not in dict(poller.poll(None if timeout_s is None else int(timeout_s * 1000))):
                return
            parts = self.sub.recv_multipart(copy=False)
            topic = parts[0].bytes
            try:
                if topic == self.sync_topic and len(parts) == 2:
                    b = self.msgs.SampleBoundary.FromString(parts[1].bytes)
                    self.boundaries_lost += self._gap(topic, b.header)
                    if b.last_in_run and not b.stream_end_follows:
                        return
                elif topic == self.end_topic and len(parts) == 2:
                    return
                elif len(parts) == 3 or (len(parts) == 2 and topic.startswith(self.frame_prefix)):
                    h = self.msgs.CameraFrame.FromString(parts[1].bytes)
                    frame = self._frame(topic, parts, h, decode, keep=True)
                    if frame is not None:
                        yield frame
                else:
                    raise ValueError(f"{len(parts)} frames")
            except Exception:  # a malformed message is counted and skipped, never fatal
                self.malformed += 1

    def samples(self, timeout_s: Optional[float] = None, decode: bool = True) -> Iterator[Sample]:
        """Yields one Sample per SampleBoundary; stops after last_in_run or timeout_s without traffic.

        When the last boundary announces a stream end (stream_end_follows), the frames still coming (sweeps after the
        last sample) are read and counted up to /sync/end, for at most end_wait_s, so frames_received and
        transport_drops account for every frame the injector sent."""
        pending: Dict[Tuple[str, str], Frame] = {}  # (sample token, camera) -> latest key frame
        poller = zmq.Poller()
        poller.register(self.sub, zmq.POLLIN)
        draining_until = None  # monotonic deadline once the last sample was yielded
        while True:
            wait_s = timeout_s
            if draining_until is not None:
                left = max(0.0, draining_until - time.monotonic())
                wait_s = left if wait_s is None else min(wait_s, left)
            events = dict(poller.poll(None if wait_s is None else int(wait_s * 1000)))
            if self.sub not in events:
                return
            parts = self.sub.recv_multipart(copy=False)
            topic = parts[0].bytes
            try:
                if topic == self.sync_topic and len(parts) == 2:
                    b = self.msgs.SampleBoundary.FromString(parts[1].bytes)
                    self.boundaries_lost += self._gap(topic, b.header)
                    # Frames of other samples are still pending only when their boundary was lost (one socket keeps
                    # order: a sample's frames come before its boundary): deliver those samples first.
                    orphans: Dict[str, Dict[str, Frame]] = {}
                    for (token, c), f in pending.items():
                        if token != b.sample_token:
                            orphans.setdefault(token, {})[c] = f
                    for token, frames in sorted(orphans.items(),
                                                key=lambda kv: min(f.capture_stamp_ns for f in kv[1].values())):
                        first_us = min(f.capture_stamp_ns for f in frames.values()) // 1000
                        yield Sample(token, b.scene_name, first_us, frames, False, boundary_lost=True)
                    frames = {c: f for (token, c), f in pending.items() if token == b.sample_token}
                    pending = {}
                    yield Sample(b.sample_token, b.scene_name, b.timestamp_us, frames, b.last_in_run)
                    if b.last_in_run:
                        if not b.stream_end_follows:
                            return
                        draining_until = time.monotonic() + self.end_wait_s
                elif topic == self.end_topic and len(parts) == 2:
                    self.msgs.StreamEnd.FromString(parts[1].bytes)
                    return
                elif len(parts) == 3 or (len(parts) == 2 and topic.startswith(self.frame_prefix)):
                    # Sweeps are counted only (a temporal model would consume them: see frames()).
                    h = self.msgs.CameraFrame.FromString(parts[1].bytes)
                    keep = h.is_key_frame and draining_until is None
                    frame = self._frame(topic, parts, h, decode, keep)
                    if frame is not None:
                        pending[(frame.sample_token, frame.camera)] = frame
                else:
                    raise ValueError(f"{len(parts)} frames")
            except Exception:  # a malformed message is counted and skipped, never fatal
                self.malformed += 1

    def publish(self, sample_token: str, boxes: List[dict], processing_ns: int = 0) -> None:
        """Sends nuScenes boxes (dicts with translation, size, rotation, velocity, detection_name,
        detection_score, attribute_name) for one sample to the sink."""
        arr = self.msgs.DetectionArray()
        self.seq += 1
        arr.header.seq = self.seq
        arr.header.publish_stamp_ns = time.time_ns()
        arr.header.publish_mono_ns = time.monotonic_ns()
        arr.header.publisher = self.detector_name
        arr.sample_token = sample_token
        arr.detector = self.detector_name
        arr.processing_ns = processing_ns
        for b in boxes:
            d = arr.detections.add()
            d.translation.extend(float(v) for v in b["translation"])
            d.size.extend(float(v) for v in b["size"])
            d.rotation.extend(float(v) for v in b["rotation"])
            d.velocity.extend(float(v) for v in b.get("velocity", (0.0, 0.0)))
            d.detection_name = b["detection_name"]
            d.detection_score = float(b["detection_score"])
            d.attribute_name = b.get("attribute_name", "")
        self.push.send_multipart([b"/detections", arr.SerializeToString()])
