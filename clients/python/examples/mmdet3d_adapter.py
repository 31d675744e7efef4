#!/usr/bin/python3
"""Where an mmdetection3d-style camera model plugs into Faultline (no torch needed to run this file).

mmdet3d's multi-view detectors (BEVFormer, DETR3D, PETR, BEVDet) take per sample: the six images in
a fixed camera order, each camera's intrinsics and its lidar2img (here: ego2img) projection, and
return boxes in the ego/lidar frame. This adapter builds that input from a Faultline Sample, calls
`model(inputs)`, and converts the result to nuScenes global boxes for the sink. Replace
`StandInModel` with your torch model wrapped the same way (inputs dict in, list of boxes out).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from faultline_client import FaultlineClient  # noqa: E402
from faultline_client.client import CAMERAS  # noqa: E402

import simple_detector  # noqa: E402


def build_inputs(sample):
    """mmdet3d-like input: images (N, H, W, 3) BGR uint8, cam2img (N, 3, 3), ego2img (N, 4, 4)."""
    imgs, cam2img, ego2img, present = [], [], [], []
    for cam in CAMERAS:
        f = sample.frames.get(cam)
        if f is None or f.image is None:  # frame lost / dropped by the injector: feed black, as RoboBEV does
            imgs.append(np.zeros((900, 1600, 3), np.uint8))
            cam2img.append(np.eye(3))
            ego2img.append(np.eye(4))
            present.append(False)
            continue
        viewpad = np.eye(4)
        viewpad[:3, :3] = f.intrinsics
        ego2img.append(viewpad @ np.linalg.inv(f.sensor_to_ego))
        cam2img.append(f.intrinsics)
        imgs.append(f.image)
        present.append(True)
    return {"img": np.stack(imgs), "cam2img": np.stack(cam2img), "ego2img": np.stack(ego2img),
            "present": present, "img_metas": {"sample_idx": sample.token, "scene": sample.scene_name}}


class StandInModel:
    """Plays the role of a torch model; here the colour-blob detector on the sample's frames."""

    def __init__(self, sample_lookup):
        self.sample_lookup = sample_lookup

    def __call__(self, inputs):
        return simple_detector.detect(self.sample_lookup[inputs["img_metas"]["sample_idx"]])


def main():
    client = FaultlineClient(detector_name="mmdet3d_adapter.py")
    current = {}
    model = StandInModel(current)
    for sample in client.samples(timeout_s=60.0):
        current.clear()
        current[sample.token] = sample
        boxes = model(build_inputs(sample))  # a real model returns ego-frame boxes: map them to global here
        client.publish(sample.token, boxes)
    client.close()


if __name__ == "__main__":
    main()
