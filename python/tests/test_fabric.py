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
