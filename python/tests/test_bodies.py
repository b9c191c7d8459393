"""Kinematic bodies of the user's, moved from NumPy arrays; the cape hangs on them and drapes over them."""
import numpy as np
import pytest

import capecloth
from conftest import quat_about


def test_the_readme_cape_hangs_behind_the_shoulders(shoulders_world):
    world, bodies, cape = shoulders_world
    start = cape.positions.copy()
    world.step(frames=120)
    x = cape.positions
    assert x.dtype == np.float32 and x.shape == (400, 3)
    assert np.isfinite(x).all()
    # The top corners stay on the shoulders' pin points; the rest has fallen below them.
    pinned = cape.pinned_particles
    assert len(pinned) == 2
    assert np.allclose(x[pinned], start[pinned], atol=5e-3)
    assert x[:, 1].min() < 0.7
    m = cape.metrics()
    assert not m["blow_up"]
    assert m["max_strain"] < 0.1
    assert m["pin_error"] < 5e-3
    assert cape.summary()["frames"] == 120


def test_mesh_arrays_have_their_shapes_and_types(shoulders_world):
    world, _, cape = shoulders_world
    world.step()
    n = cape.particle_count
    tris = cape.triangles
    assert tris.dtype == np.uint32 and tris.shape == (2 * 19 * 19, 3) and tris.max() == n - 1
    normals = cape.normals
    assert normals.shape == (n, 3) and normals.dtype == np.float32
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-4)
    uvs = cape.uvs
    assert uvs.shape == (n, 2) and uvs.min() >= 0.0 and uvs.max() <= 1.0
    assert cape.velocities.shape == (n, 3)


def test_a_moved_sphere_moves_its_collider_and_the_cape_drapes_over_it():
    world = capecloth.World()
    left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
    right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
    ball = world.add_sphere(0.2, pose=[0.0, 1.0, 3.0, 0, 0, 0, 1], name="ball")  # far away at first
    cape = world.add_cape([left, right])
    world.step(frames=90)
    hanging = cape.positions.copy()
    # Brought in from behind over 1 s to just behind the cape (z 0.15), the ball pushes its middle forward (-z):
    # the cape drapes over it.
    for k in range(1, 61):
        z = 3.0 + (0.3 - 3.0) * k / 60
        ball.set_pose(position=[0.0, 1.0, z])
        world.step()
    world.step(frames=60)
    cols = world.colliders()
    i = cols["owner"].index("ball")
    assert cols["shape"][i] == "sphere" and cols["radius"][i] == pytest.approx(0.2)
    assert np.allclose(cols["poses"][i][:3], [0.0, 1.0, 0.3], atol=1e-6)
    x = cape.positions
    centre = np.array([0.0, 1.0, 0.3])
    d = np.linalg.norm(x - centre, axis=1)
    assert d.min() > 0.2 - 1e-3  # nothing inside the ball
    near = d < 0.2 + 0.05
    assert near.sum() > 10  # particles lie on its surface
    # Those particles were pushed forward from where they hung.
    assert x[near, 2].mean() < hanging[near, 2].mean() - 0.02
    assert cape.metrics()["max_penetration"] < 2e-3


def test_poses_as_matrices_quaternions_and_orders_agree():
    world = capecloth.World(ground=False)
    a = world.add_box([0.1, 0.2, 0.3])
    b = world.add_capsule(0.05, 0.2, axis="z")
    q = quat_about([0, 0, 1], 0.7)
    M = np.eye(4)
    c, s = np.cos(0.7), np.sin(0.7)
    M[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    M[:3, 3] = [1, 2, 3]
    world.set_body_poses(np.array([[1, 2, 3, *q], [0, 0, 0, 0, 0, 0, 1]]))
    assert np.allclose(a.matrix, M, atol=1e-6)
    b.set_pose(M)
    assert np.allclose(b.pose(), [1, 2, 3, *q], atol=1e-6)
    wxyz = np.array([q[3], q[0], q[1], q[2]])
    b.set_pose(position=[0, 0, 0], quaternion=wxyz, order="wxyz")
    assert np.allclose(b.pose(order="wxyz")[3:], wxyz, atol=1e-6)
    world.set_body_poses(np.stack([M, M]))
    cols = world.colliders()
    assert cols["shape"] == ["box", "capsule"]
    assert np.allclose(cols["half_extents"][0], [0.1, 0.2, 0.3], atol=1e-6)
    assert cols["half_height"][1] == pytest.approx(0.2) and cols["axis"][1] == 2


def test_a_z_up_world_hangs_its_cape_down_z():
    world = capecloth.World(up="z")
    assert np.allclose(world.gravity, [0, 0, -9.81])
    # The scenes' Y-up character frame turned into Z-up: the shoulders are at height 1.52 along z.
    left = world.add_sphere(0.08, pose=[0, 0.3, 1.56, 0, 0, 0, 1])
    right = world.add_sphere(0.08, pose=[0, -0.3, 1.56, 0, 0, 0, 1])
    cape = world.add_cape([left, right])
    world.step(frames=120)
    x = cape.positions
    assert x[:, 2].min() < 0.7 and x[:, 2].max() < 1.6
    assert np.ptp(x[:, 1]) > 0.5  # spread between the shoulders, along y
