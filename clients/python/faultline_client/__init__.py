"""Faultline Python client: subscribe to faulted camera frames, publish detections.

Uses only Debian's python3-zmq, python3-protobuf, python3-numpy (and python3-opencv to decode JPEG).
The protobuf modules are generated from msgs/*.proto at build time into build/python/faultline_msgs.
"""
from .client import Frame, Sample, FaultlineClient, load_messages  # noqa: F401
from .client import CurveKeyError, read_curve_key  # noqa: F401
