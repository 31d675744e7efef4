"""Runs the official Python client (clients/python/faultline_client) as a real-time subscriber for
`faultline bench python-client`: receives every frame as a numpy array, reads a subsample of its pixels, and prints
one JSON line: frames received, losses, added latency (client CLOCK_MONOTONIC when the image is available minus the
injector's publish_mono_ns) and the client's CPU time.

usage: client_rate.py CLIENT_DIR FRAMES_ENDPOINT [IDLE_TIMEOUT_S]
"""
import json
import sys
import time

sys.path.insert(0, sys.argv[1])
from faultline_client import FaultlineClient  # noqa: E402

import numpy as np  # noqa: E402

endpoint = sys.argv[2]
idle_s = float(sys.argv[3]) if len(sys.argv) > 3 else 20.0
client = FaultlineClient(endpoint, "ipc:///dev/null/unused", detector_name="bench_python_client")
print("ready", flush=True)  # subscribed: the bench may start the stream
latency_ms = []
torn = 0
checksum = 0
cpu0 = time.process_time()
wall0 = None
for frame in client.frames(timeout_s=idle_s):
    now = time.monotonic_ns()
    if wall0 is None:
        wall0 = now
    latency_ms.append((now - frame.header.publish_mono_ns) / 1e6)
    checksum += int(frame.image[::16, ::16].sum())  # a light read of the pixels, as a detector's first step
    if not frame.intact():
        torn += 1
cpu_s = time.process_time() - cpu0
wall_s = (time.monotonic_ns() - wall0) / 1e9 if wall0 else 0.0
lat = np.array(latency_ms) if latency_ms else np.zeros(1)
print(json.dumps({
    "received": client.frames_received, "transport_drops": client.transport_drops,
    "shm_overwritten": client.shm_overwritten, "torn": torn, "malformed": client.malformed,
    "latency_ms_p50": float(np.percentile(lat, 50)), "latency_ms_p99": float(np.percentile(lat, 99)),
    "cpu_s": cpu_s, "wall_s": wall_s, "checksum": checksum}), flush=True)
client.close()
