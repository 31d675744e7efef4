"""Starts Faultline node processes for the Python tests (ipc endpoints in a private temp dir)."""
import json
import os
import re
import subprocess
import sys
import tempfile

BIN_DIR = os.environ.get("FAULTLINE_BIN_DIR", "")
REPO = os.environ.get("FAULTLINE_SOURCE_DIR", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
sys.path.insert(0, os.path.join(REPO, "clients", "python"))


def binary(name):
    path = os.path.join(BIN_DIR, name)
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: build the project first")
    return path


def synth_dataset(root, scenes=2, seconds=2, seed=3):
    subprocess.run([binary("faultline"), "dataset", "synth", "--out", root, "--scenes", str(scenes),
                    "--seconds", str(seconds), "--seed", str(seed)], check=True, capture_output=True)
    return root


def count_camera_frames(dataroot, version="v1.0-mini"):
    """Camera sample_data records in the tables (what the player publishes)."""
    tables = os.path.join(dataroot, version)
    load = lambda name: json.load(open(os.path.join(tables, name + ".json")))
    sensors = {s["token"]: s for s in load("sensor")}
    calib = {c["token"]: sensors[c["sensor_token"]] for c in load("calibrated_sensor")}
    cams = [sd for sd in load("sample_data") if calib[sd["calibrated_sensor_token"]]["modality"] == "camera"]
    keys = {sd["sample_token"] for sd in cams if sd["is_key_frame"]}
    return len(cams), len(keys)


class Pipeline:
    """player -> injector -> (external detector) -> sink over ipc; call start_* then wait()."""

    def __init__(self, dataroot, lockstep=True, rate=0.0, subscribers=2):
        self.tmp = tempfile.mkdtemp(prefix="faultline-py-")
        ep = lambda n: f"ipc://{self.tmp}/{n}"
        self.player_ep, self.frames_ep, self.detections_ep, self.ack_ep = ep("player"), ep("frames"), ep("det"), ep("ack")
        self.results = os.path.join(self.tmp, "results.json")
        self.dataroot, self.lockstep, self.rate, self.subscribers = dataroot, lockstep, rate, subscribers
        self.procs = {}
        env = dict(os.environ)
        env["FAULTLINE_RUN_DIR"] = os.path.join(self.tmp, "graph")
        self.env = env

    def _start(self, name, args):
        log = open(os.path.join(self.tmp, name + ".log"), "w")
        self.procs[name] = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=self.env)

    def start_sink(self):
        self._start("detection_sink", [binary("detection_sink"), "-p", f"detections_endpoint:={self.detections_ep}",
                                       "-p", f"sync_endpoints:=[{self.frames_ep}]", "-p", f"output:={self.results}",
                                       "-p", f"lockstep:={str(self.lockstep).lower()}", "-p",
                                       f"ack_endpoint:={self.ack_ep}", "-p", "finalize_grace_ms:=20000"])

    def start_injector(self):
        self._start("fault_injector", [binary("fault_injector"), "-p", f"input_endpoints:=[{self.player_ep}]",
                                       "-p", f"output_endpoint:={self.frames_ep}", "-p", "input_hwm:=256",
                                       "-p", "output_hwm:=256", "-p", f"wait_subscribers:={self.subscribers}",
                                       "-p", "wait_timeout_ms:=30000"])

    def start_player(self):
        self._start("nusc_player", [binary("nusc_player"), "-p", f"dataroot:={self.dataroot}", "-p",
                                    f"endpoint:={self.player_ep}", "-p", f"rate:={self.rate}", "-p", "hwm:=256",
                                    "-p", f"lockstep:={str(self.lockstep).lower()}", "-p",
                                    f"ack_endpoint:={self.ack_ep}", "-p", "wait_subscribers:=1",
                                    "-p", "wait_timeout_ms:=30000"])

    def start_external(self, name, args):
        self._start(name, args)

    def wait(self, name, timeout=180):
        return self.procs[name].wait(timeout=timeout)

    def log(self, name):
        return open(os.path.join(self.tmp, name + ".log")).read()

    def injector_out(self):
        """Frames the injector forwarded (its end-of-run line); trailing sweeps after the run's last
        sample boundary are not forwarded, so this can be below the dataset's camera frame count."""
        m = re.search(r"injector done: in (\d+) out (\d+)", self.log("fault_injector"))
        if not m:
            raise AssertionError("no end-of-run line in the injector log:\n" + self.log("fault_injector"))
        return int(m.group(2))

    def stop(self):
        for p in self.procs.values():
            if p.poll() is None:
                p.terminate()
        for p in self.procs.values():
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()
