"""Fixed depth cameras in a MuJoCo scene's MJCF: one ``<camera>`` per
:class:`~dynfab.perception.camera_spec.CameraSpec`, named :func:`camera_name`, for depth
rendering (:mod:`dynfab.sim.depth_render`)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from dynfab.perception.camera_spec import CameraSpec
from dynfab.sim.mjcf_values import mjcf_numbers

__all__ = ["add_camera", "camera_name"]


def camera_name(k: int) -> str:
    """The MJCF name of the ``k``-th camera of a scene."""
    return f"depth_camera{k}"


def add_camera(world: ET.Element, buffer: ET.Element, k: int, camera: CameraSpec) -> None:
    """Camera ``k`` fixed in ``world`` (MJCF's ``xyaxes`` are the image's right and up axes in
    the world frame, ``fovy`` its vertical field of view [deg]); the offscreen ``buffer``
    (``<visual><global>``) grows to hold its image."""
    axes = camera.rotation
    ET.SubElement(world, "camera", name=camera_name(k), pos=mjcf_numbers(camera.position),
                  xyaxes=mjcf_numbers(np.concatenate([axes[:, 0], axes[:, 1]])), fovy=repr(camera.fov))
    for attribute, size in (("offwidth", camera.width), ("offheight", camera.height)):
        buffer.set(attribute, str(max(int(buffer.get(attribute)), size)))
