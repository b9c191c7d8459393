"""Shared helpers for the capecloth tests: the module comes from PYTHONPATH (ctest sets it to the build)."""
import math
import os
import pathlib

import numpy as np
import pytest

import capecloth

REPO = pathlib.Path(os.environ.get("CAPECLOTH_REPO", pathlib.Path(__file__).resolve().parents[2]))


def quat_about(axis, angle):
    """Unit quaternion (x, y, z, w) turning `angle` rad about `axis`."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    s = math.sin(angle / 2)
    return np.array([a[0] * s, a[1] * s, a[2] * s, math.cos(angle / 2)])


@pytest.fixture
def shoulders_world():
    """The README's world: a torso box and two shoulder spheres (r 0.08 m at (+-0.22, 1.52, 0)), a cape on them."""
    world = capecloth.World()
    torso = world.add_box([0.2, 0.3, 0.1], pose=[0, 1.2, 0, 0, 0, 0, 1], name="torso")
    left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1], name="left")
    right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1], name="right")
    cape = world.add_cape([left, right])
    return world, (torso, left, right), cape
