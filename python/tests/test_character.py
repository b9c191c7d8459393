"""The shipped humanoid and a URDF file: walking from poses computed in Python, the cape stays on its back."""
import math

import numpy as np
import pytest

import capecloth
from conftest import REPO

WALK_SPEED = 1.4  # m/s, docs/SCENES.md's walk
STEP_HZ = 0.9


def python_gait(t):
    """Joint angles (rad) of a walk computed here, not by the library: legs and arms swing against each other."""
    p = 2 * math.pi * STEP_HZ * t
    return {
        "left_hip_pitch": 0.45 * math.sin(p),
        "right_hip_pitch": -0.45 * math.sin(p),
        "left_knee": 0.05 + 0.8 * max(0.0, math.cos(p)) ** 2,
        "right_knee": 0.05 + 0.8 * max(0.0, -math.cos(p)) ** 2,
        "left_shoulder_pitch": -0.3 * math.sin(p),
        "right_shoulder_pitch": 0.3 * math.sin(p),
        "left_elbow": 0.4,
        "right_elbow": 0.4,
    }


def behind(world_point, torso_pose, forward):
    """m behind the torso's origin along the walking direction (positive: behind)."""
    return -float(np.dot(world_point - torso_pose[:3], forward))


def test_the_humanoid_walks_from_python_poses_and_the_cape_stays_on_its_back():
    world = capecloth.World()
    human = world.add_humanoid()
    assert "left_shoulder" in human.link_names and "left_knee" in human.joint_names
    cape = human.attach_cape()
    assert "cape" in cape.description
    names = human.link_names
    torso = names.index("torso")
    root0 = human.link_poses()[0]
    forward = np.array([0.0, 0.0, -1.0])  # the Y-up scenes' character faces -Z
    frames = 240
    for f in range(1, frames + 1):
        t = f / 60
        root = root0.copy()
        root[:3] += forward * WALK_SPEED * t
        root[1] += 0.015 * math.sin(4 * math.pi * STEP_HZ * t)  # the bob
        human.set_motion(t, root, joints=python_gait(t))
        world.step()
        x = cape.positions
        assert np.isfinite(x).all(), f"frame {f}"
    poses = human.link_poses()
    assert poses[0][2] == pytest.approx(root0[2] - WALK_SPEED * frames / 60, abs=1e-6)
    centroid = x.mean(axis=0)
    assert 0.05 < behind(centroid, poses[torso], forward) < 0.6
    top = x[cape.pinned_particles]
    shoulder = poses[names.index("left_shoulder")]
    assert np.all(np.abs(top[:, 1] - shoulder[1]) < 0.1)  # the pins stay at the shoulders
    s = cape.summary()
    assert s["frames"] == frames and not s["blow_up"]
    assert s["max_strain"] < 0.3
    assert s["median_frame_max_strain"] < 0.05
    assert s["max_penetration"] < 0.02


def test_link_poses_fed_from_another_simulator_carry_the_cape():
    # The "other simulator": a humanoid walking by the library's gait in a world of its own, read as arrays.
    source_world = capecloth.World()
    source = source_world.add_humanoid(gait="walk")
    world = capecloth.World(up="y")
    robot = world.add_humanoid()
    cape = robot.attach_cape(resolution=16)
    start = cape.positions.mean(axis=0)
    for f in range(1, 181):
        source.advance_to(f / 60)
        robot.set_link_poses(source.link_poses())
        world.step()
    x = cape.positions
    assert np.isfinite(x).all()
    travelled = start[2] - x.mean(axis=0)[2]
    assert travelled == pytest.approx(WALK_SPEED * 3.0, abs=0.25)
    cols = world.colliders()
    torso = [i for i, o in enumerate(cols["owner"]) if o.endswith("/torso")][0]
    assert cols["poses"][torso][2] == pytest.approx(source.link_poses()[2][2], abs=1e-5)
    assert behind(x.mean(axis=0), cols["poses"][torso], np.array([0, 0, -1.0])) > 0.05
    assert cape.summary()["max_strain"] < 0.3


def test_a_urdf_file_in_a_z_up_world_with_its_gait():
    world = capecloth.World(up="z")
    human = world.load_urdf(str(REPO / "character" / "models" / "humanoid.urdf"), gait="walk")
    cape = human.attach_cape(pins="collar")
    assert "upper torso 'torso'" in cape.description
    for f in range(1, 121):
        human.advance_to(f / 60)
        world.step()
    x = cape.positions
    assert np.isfinite(x).all()
    assert x[:, 2].max() < 1.8 and x[:, 2].min() > 0.2  # hangs along z, above the ground
    assert x.mean(axis=0)[0] > 1.4 * 2.0 - 0.5  # a Z-up character faces +X and walked 2 s
    assert cape.summary()["max_strain"] < 0.3


def test_package_paths_find_a_urdf_mesh(tmp_path):
    pkg = tmp_path / "share" / "my_robot"
    pkg.mkdir(parents=True)
    corners = [(x, y, z) for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (0.0, 0.3)]
    faces = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2),
             (3, 4, 8), (3, 8, 7), (1, 3, 7), (1, 7, 5), (2, 6, 8), (2, 8, 4)]
    (pkg / "block.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners) +
                                   "".join(f"f {a} {b} {c}\n" for a, b, c in faces))
    urdf = tmp_path / "robot.urdf"
    urdf.write_text("""<?xml version="1.0"?>
<robot name="blockbot">
  <link name="base"><collision><geometry><mesh filename="package://my_robot/block.obj"/></geometry></collision></link>
</robot>""")
    # Without the package path the mesh is left out, and the warning says why.
    world = capecloth.World()
    alone = world.load_urdf(str(urdf))
    assert any("not found" in w and "package" in w for w in alone.warnings)
    assert world.colliders()["shape"] == []
    world = capecloth.World()
    robot = world.load_urdf(str(urdf), package_paths=[str(tmp_path / "share")])
    assert robot.link_names == ["base"]
    cols = world.colliders()
    assert cols["shape"] == ["convex_hull"] and cols["owner"] == ["blockbot0/base"]
    assert cols["radius"][0] == pytest.approx(np.linalg.norm([0.1, 0.1, 0.3]), abs=0.02)
