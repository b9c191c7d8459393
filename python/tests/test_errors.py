"""Bad input from Python is an exception with the library's message, never a crash."""
import math

import numpy as np
import pytest

import capecloth


def test_nan_and_badly_shaped_poses_raise(shoulders_world):
    world, (torso, left, right), cape = shoulders_world
    with pytest.raises(ValueError, match="not finite"):
        left.set_pose([0, math.nan, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="7 numbers"):
        left.set_pose([0, 1, 0])
    with pytest.raises(ValueError, match="zero quaternion"):
        left.set_pose([0, 1, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="rotation"):
        left.set_pose(np.diag([2.0, 1, 1, 1]))
    with pytest.raises(ValueError, match="not an array of numbers"):
        left.set_pose("up there")
    with pytest.raises(ValueError, match="one pose per body"):
        world.set_body_poses(np.zeros((2, 7)) + [0, 0, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match=r"\(N, 7\)"):
        world.set_body_poses(np.zeros((3, 6)))
    with pytest.raises(ValueError, match="from the origin"):
        left.set_pose([1e9, 0, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="order"):
        left.pose(order="zyx")
    # Nothing moved, and the world still steps.
    world.step()
    assert np.isfinite(cape.positions).all()


def test_absurd_sizes_and_settings_raise():
    world = capecloth.World()
    with pytest.raises(ValueError, match="radius"):
        world.add_sphere(-1.0)
    with pytest.raises(ValueError, match="radius"):
        world.add_sphere(1e9)
    with pytest.raises(ValueError, match="half extent"):
        world.add_box([0.1, 0.0, 0.1])
    with pytest.raises(ValueError, match="axis"):
        world.add_capsule(0.1, 0.2, axis="w")
    s = world.add_sphere(0.1)
    with pytest.raises(ValueError, match="resolution"):
        world.add_cape([s], resolution=100000)
    with pytest.raises(ValueError, match="pins"):
        world.add_cape([s], pins="everywhere")
    with pytest.raises(ValueError, match="at least one body"):
        world.add_cape([])
    bad = capecloth.CapeSettings()
    bad.substeps = 0
    with pytest.raises(ValueError, match="substeps"):
        bad.validate()
    with pytest.raises(ValueError, match="substeps"):
        world.add_cape([s], settings=bad)
    cape = world.add_cape([s])
    bad = cape.settings
    bad.damping = -3.0
    with pytest.raises(ValueError, match="damping"):
        cape.settings = bad
    with pytest.raises(ValueError, match="dt"):
        world.step(math.inf)
    with pytest.raises(ValueError, match="max_substeps"):
        world.step(0.5)
    with pytest.raises(ValueError, match="up"):
        capecloth.World(up="x")


def test_urdf_errors_carry_the_library_message(tmp_path):
    world = capecloth.World()
    with pytest.raises(FileNotFoundError, match="nowhere.urdf"):
        world.load_urdf(str(tmp_path / "nowhere.urdf"))
    broken = tmp_path / "broken.urdf"
    broken.write_text('<robot name="r"><link name="a"></robot>')
    with pytest.raises(ValueError, match="line"):
        world.load_urdf(str(broken))
    with pytest.raises(ValueError, match="(?i)robot"):
        world.load_urdf_string('<?xml version="1.0"?><notarobot/>')
    with pytest.raises(ValueError, match="gait"):
        world.add_humanoid(gait="moonwalk")
    human = world.add_humanoid()
    with pytest.raises(ValueError, match="no_such_joint"):
        human.set_motion(0.1, [0, 0, 1, 0, 0, 0, 1], joints={"no_such_joint": 0.3})
    with pytest.raises(ValueError, match="one pose per link"):
        human.set_link_poses(np.zeros((2, 7)) + [0, 0, 0, 0, 0, 0, 1])


def test_gltf_errors():
    world = capecloth.World()
    with pytest.raises(RuntimeError, match="add a cape"):
        world.start_recording()
    with pytest.raises(RuntimeError, match="start_recording"):
        world.write_gltf("x.glb")
