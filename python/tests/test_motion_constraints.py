"""Motion constraints, weight maps and levels of detail, from Python."""
import numpy as np
import pytest

import capecloth


def shaken(cape, world, left, right, frames):
    """Shakes the two shoulder spheres sideways (0.3 m at 2 Hz), one frame at a time, yielding each frame."""
    for k in range(1, frames + 1):
        dx = 0.3 * np.sin(2 * np.pi * 2 * k / 60)
        left.set_pose(position=[-0.22 + dx, 1.52, 0])
        right.set_pose(position=[0.22 + dx, 1.52, 0])
        world.step()
        yield k


def test_a_max_distance_weight_map_from_the_uvs_holds_the_cape():
    world = capecloth.World()
    left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
    right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
    cape = world.add_cape([left, right])
    reach = 0.02 + 0.1 * cape.uvs[:, 1]  # 2 cm at the collar (v = 0), 12 cm at the hem
    cape.set_motion_constraints(max_distance=reach)
    worst, farthest = -1.0, 0.0
    for _ in shaken(cape, world, left, right, 90):
        d = np.linalg.norm(cape.positions - cape.animated_positions, axis=1)
        worst = max(worst, float((d - reach).max()))
        farthest = max(farthest, float(d.max()))
    assert worst < 1e-4
    assert farthest > 0.05  # the hem uses its reach


def test_a_drive_of_one_holds_the_animated_pose_and_bad_values_raise():
    world = capecloth.World()
    left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
    right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
    cape = world.add_cape([left, right])
    cape.set_motion_constraints(drive=1.0)
    for _ in shaken(cape, world, left, right, 30):
        assert np.abs(cape.positions - cape.animated_positions).max() < 1e-4
    n = cape.particle_count
    with pytest.raises(ValueError, match="MotionConstraints"):
        cape.set_motion_constraints(max_distance=np.ones(n - 1))
    with pytest.raises(ValueError, match="MotionConstraints"):
        cape.set_motion_constraints(drive=1.5)
    with pytest.raises(ValueError, match="MotionConstraints"):
        cape.set_motion_constraints(max_distance=np.full(n, np.nan))
    with pytest.raises(ValueError, match="1-D"):
        cape.set_motion_constraints(max_distance=np.ones((n, 2)))
    cape.set_motion_constraints()  # all off
    for _ in shaken(cape, world, left, right, 30):
        pass
    assert np.abs(cape.positions - cape.animated_positions).max() > 0.01


def test_mass_and_stiffness_weight_maps_reach_the_cape():
    def hang(mass=None, stiffness=None):
        world = capecloth.World()
        left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
        right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
        cape = world.add_cape([left, right])
        if mass is not None:
            cape.set_mass_scale(mass(cape))
        if stiffness is not None:
            cape.set_stiffness_scale(stiffness(cape))
        for _ in range(60):
            world.step()
        return cape

    plain = hang()
    ones = hang(mass=lambda c: 1.0, stiffness=lambda c: np.ones(len(c.uvs)))
    assert np.array_equal(plain.positions, ones.positions)  # a scale of one changes no bit
    heavy_hem = hang(mass=lambda c: 1.0 + 9.0 * c.uvs[:, 1])  # ten times heavier at the hem (v = 1)
    assert not np.array_equal(plain.positions, heavy_hem.positions)
    with pytest.raises(ValueError, match="setMassScale"):
        plain.set_mass_scale(np.zeros(len(plain.uvs)))
    with pytest.raises(ValueError, match="setStiffnessScale"):
        plain.set_stiffness_scale(np.ones(3))
    with pytest.raises(ValueError):
        plain.set_stiffness_scale(np.ones((2, 2)))
    plain.set_mass_scale(None)
    plain.set_stiffness_scale(None)


def test_a_level_of_detail_steps_the_cape_less_often_and_bad_levels_raise():
    def hang(level=None):
        world = capecloth.World()
        left = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
        right = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
        cape = world.add_cape([left, right])
        if level is not None:
            cape.set_detail_level(*level)
        for _ in range(60):
            world.step()
        return cape

    full = hang()
    assert full.detail_level == (1, 0, False)
    assert np.array_equal(full.positions, hang((1, 0)).positions)  # full detail changes no bit
    coarse = hang((4, 2))
    assert coarse.detail_level == (4, 2, False)
    assert np.isfinite(coarse.positions).all()
    gap = np.linalg.norm(coarse.positions - full.positions, axis=1).max()
    assert 0 < gap < 0.05  # another solve of the same hang, a few cm at most from it
    # On the grid's coarse level (10 x 10 for the 20 x 20 cape), interpolated: as close to the full hang.
    halved = hang((4, 2, True))
    assert halved.detail_level == (4, 2, True)
    assert halved.positions.shape == full.positions.shape
    assert 0 < np.linalg.norm(halved.positions - full.positions, axis=1).max() < 0.05
    for bad in [(0, 0), (65, 0), (1, -1)]:
        with pytest.raises(ValueError, match="DetailLevel"):
            coarse.set_detail_level(*bad)
    assert coarse.detail_level == (4, 2, False)
