"""Counts frames and seq-gap drops of a real-time stream without decoding; prints one JSON line."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
import pipeline_helpers  # noqa: E402,F401
from faultline_client import FaultlineClient  # noqa: E402

client = FaultlineClient(sys.argv[1], "ipc:///dev/null/unused", detector_name="counter")
samples = sum(1 for _ in client.samples(timeout_s=30, decode=False))
print(json.dumps({"received": client.frames_received, "transport_drops": client.transport_drops,
                  "samples": samples, "malformed": client.malformed}))
client.close()
