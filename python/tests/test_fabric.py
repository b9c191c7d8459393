"""Fabric presets, wind and self-collision reach the cape."""
import numpy as np
import pytest

import capecloth


def test_fabric_presets_set_the_springs_for_the_grid():
    names = capecloth.fabric_names()
    assert "silk" in names and "leather" in names
    silk = capecloth.fabric_material("silk")
    assert silk["areal_density"] > 0 and silk["source"]
    world = capecloth.World()
    a = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
    b = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
    silky = world.add_cape([a, b], fabric="silk")
    stiff = world.add_cape([a, b], fabric="leather")
    plain = world.add_cape([a, b])
    assert "silk" in silky.description
    assert stiff.settings.bending_rigidity > silky.settings.bending_rigidity
    assert silky.settings.bending_rigidity == pytest.approx(silk["bending_rigidity"])
    assert plain.settings.bending_rigidity == 0.0 and silky.settings.bend_stiffness == 0.0
    with pytest.raises(ValueError, match="silk"):
        world.add_cape([a, b], fabric="tinfoil")
    with pytest.raises(ValueError, match="tinfoil"):
        capecloth.fabric_material("tinfoil")


def test_wind_blows_the_cape_downwind():
    def hang(wind_speed):
        world = capecloth.World()
        a = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
        b = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
        cape = world.add_cape([a, b])
        w = capecloth.WindSettings()
        w.model = capecloth.WindSettings.Model.AERODYNAMIC
        w.speed = wind_speed
        w.direction = [0, 0, 1]
        cape.wind = w
        assert cape.wind.speed == pytest.approx(wind_speed)
        world.step(frames=120)
        return cape.positions[:, 2].mean()

    assert hang(8.0) > hang(0.0) + 0.1


def test_self_collision_is_set_and_counted():
    world = capecloth.World()
    a = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
    b = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
    cape = world.add_cape([a, b])
    cape.self_collision = True
    cape.count_self_intersections = True
    assert cape.settings.self_collision
    world.step(frames=30)
    assert cape.metrics()["self_intersections"] == 0
    assert np.isfinite(cape.positions).all()


def test_strain_ceiling_holds_a_shaken_capes_springs():
    # The shoulders shaken sideways (0.3 m at 2 Hz) whip a cape hung by its two top corners; a ceiling of
    # 2 % holds its rows' and columns' springs after their solve (measured: a peak of 45 % without, 24 %
    # with it: the collisions with the shoulders come after it).
    def peak_strain(ceiling):
        world = capecloth.World()
        a = world.add_sphere(0.08, pose=[-0.22, 1.52, 0, 0, 0, 0, 1])
        b = world.add_sphere(0.08, pose=[0.22, 1.52, 0, 0, 0, 0, 1])
        settings = capecloth.CapeSettings()
        settings.strain_ceiling = ceiling
        settings.strain_ceiling_passes = 4
        cape = world.add_cape([a, b], settings=settings)
        assert cape.settings.strain_ceiling == pytest.approx(ceiling)
        assert cape.settings.strain_ceiling_passes == 4
        n = int(round(len(cape.positions) ** 0.5))
        rest = cape.positions.reshape(n, n, 3).copy()  # the flat grid it starts as
        worst = 0.0
        for frame in range(120):
            shift = 0.3 * np.sin(2.0 * np.pi * 2.0 * frame / 60.0)
            a.set_pose([shift - 0.22, 1.52, 0, 0, 0, 0, 1])
            b.set_pose([shift + 0.22, 1.52, 0, 0, 0, 0, 1])
            world.step(1.0 / 60.0)
            x = cape.positions.reshape(n, n, 3)
            assert np.isfinite(x).all()
            for axis in (0, 1):
                length = np.linalg.norm(np.diff(x, axis=axis), axis=2)
                rest_length = np.linalg.norm(np.diff(rest, axis=axis), axis=2)
                worst = max(worst, (length / rest_length - 1.0).max())
        return worst

    free, held = peak_strain(0.0), peak_strain(0.02)
    assert free > 0.3
    assert held < 0.65 * free
    bad = capecloth.CapeSettings()
    bad.strain_ceiling = -0.5
    with pytest.raises(ValueError, match="strainCeiling"):
        bad.validate()
    bad.strain_ceiling = 0.1
    bad.strain_ceiling_passes = 0
    with pytest.raises(ValueError, match="strainCeilingPasses"):
        bad.validate()
