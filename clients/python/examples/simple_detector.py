#!/usr/bin/python3
"""A small colour-blob detector for Faultline's generated scenes, as an external Python detector.

Run it against a pipeline (it speaks the protocol of docs/protocol.md):
    /usr/bin/python3 clients/python/examples/simple_detector.py [--frames tcp://...] [--detections tcp://...]
It stops after the run's last sample (or --idle-timeout seconds without traffic).
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from faultline_client import FaultlineClient  # noqa: E402

import cv2  # noqa: E402  (python3-opencv)

# Body colours (BGR) and size priors (w, l, h) of the synthetic classes (lib/dataset/synth_palette.hpp).
CLASSES = {
    "car": ((30, 30, 220), (1.9, 4.6, 1.7)),
    "truck": ((0, 140, 255), (2.5, 7.5, 3.2)),
    "bus": ((0, 220, 240), (2.9, 11.5, 3.4)),
    "pedestrian": ((255, 0, 255), (0.65, 0.7, 1.75)),
    "motorcycle": ((255, 90, 0), (0.8, 2.1, 1.5)),
    "bicycle": ((230, 230, 0), (0.6, 1.75, 1.3)),
    "traffic_cone": ((140, 40, 255), (0.4, 0.4, 0.75)),
    "barrier": ((255, 0, 140), (2.3, 0.5, 1.0)),
}
ATTRIBUTE = {"car": "vehicle.parked", "truck": "vehicle.parked", "bus": "vehicle.moving",
             "pedestrian": "pedestrian.standing", "motorcycle": "cycle.with_rider", "bicycle": "cycle.with_rider"}


def class_hues():
    hues = {}
    for name, (bgr, _) in CLASSES.items():
        hsv = cv2.cvtColor(np.uint8([[bgr]]), cv2.COLOR_BGR2HSV)[0, 0]
        hues[name] = int(hsv[0])
    return hues


HUES = class_hues()


def yaw_of(rot: np.ndarray) -> float:
    return float(np.arctan2(rot[1, 0], rot[0, 0]))


def detect(sample, scale: float = 0.25):
    boxes = []
    for frame in sample.frames.values():
        if frame.image is None or frame.image.ndim != 3:
            continue
        small = cv2.resize(frame.image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        hsv = cv2.cvtColor(small, cv2.COLOR_BGR2HSV)
        sat_ok = (hsv[:, :, 1] > 120) & (hsv[:, :, 2] > 60)
        hue = hsv[:, :, 0].astype(np.int16)
        k_inv = np.linalg.inv(frame.intrinsics)
        cam_to_global = frame.ego_to_global @ frame.sensor_to_ego
        ground_z = frame.ego_to_global[2, 3]
        ego_yaw = yaw_of(frame.ego_to_global[:3, :3])
        for name, target in HUES.items():
            diff = np.abs(hue - target)
            diff = np.minimum(diff, 180 - diff)
            mask = (sat_ok & (diff <= 5)).astype(np.uint8)
            count, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
            for i in range(1, count):
                x, y, w, h, area = stats[i]
                if area < 6:
                    continue
                u = (x + w / 2.0) / scale
                v = (y + h) / scale
                ray = cam_to_global[:3, :3] @ (k_inv @ np.array([u, v, 1.0]))
                if ray[2] > -1e-6:
                    continue
                origin = cam_to_global[:3, 3]
                t = (ground_z - origin[2]) / ray[2]
                contact = origin + t * ray
                size = CLASSES[name][1]
                horiz = ray[:2] / (np.linalg.norm(ray[:2]) or 1.0)
                centre_xy = contact[:2] + horiz * (size[0] + size[1]) / 4.0
                boxes.append({
                    "translation": [centre_xy[0], centre_xy[1], ground_z + size[2] / 2.0],
                    "size": list(size),
                    "rotation": [np.cos(ego_yaw / 2), 0.0, 0.0, np.sin(ego_yaw / 2)],
                    "velocity": [0.0, 0.0],
                    "detection_name": name,
                    "detection_score": float(min(0.95, 0.2 + area / 400.0)),
                    "attribute_name": ATTRIBUTE.get(name, ""),
                })
    return merge(boxes)


def merge(boxes, radius: float = 1.5):
    """Keeps the highest-scoring box of each class within `radius` metres (one object seen twice)."""
    kept = []
    for b in sorted(boxes, key=lambda b: -b["detection_score"]):
        if all(k["detection_name"] != b["detection_name"] or
               np.hypot(k["translation"][0] - b["translation"][0], k["translation"][1] - b["translation"][1]) > radius
               for k in kept):
            kept.append(b)
    return kept


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", help="faulted frames endpoint (default $FAULTLINE_FRAMES)")
    ap.add_argument("--detections", help="sink endpoint (default $FAULTLINE_DETECTIONS)")
    ap.add_argument("--scale", type=float, default=0.25, help="processing scale (default 0.25)")
    ap.add_argument("--idle-timeout", type=float, default=60.0, help="stop after this many idle seconds")
    args = ap.parse_args()
    client = FaultlineClient(args.frames, args.detections, detector_name="simple_detector.py")
    n = 0
    for sample in client.samples(timeout_s=args.idle_timeout):
        t0 = time.monotonic_ns()
        boxes = detect(sample, args.scale)
        client.publish(sample.token, boxes, processing_ns=time.monotonic_ns() - t0)
        n += 1
    print(f"simple_detector: {n} samples, {client.frames_received} frames, "
          f"{client.transport_drops} transport drops, {client.malformed} malformed", file=sys.stderr)
    client.close()


if __name__ == "__main__":
    main()
