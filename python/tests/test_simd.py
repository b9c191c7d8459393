"""The solver kernels' instruction set (cape/core/Simd.h): every one gives the same bits."""
import numpy as np
import pytest

import capecloth


def walk_positions():
    world = capecloth.World()
    human = world.add_humanoid()
    cape = human.attach_cape()
    root = human.link_poses()[0]
    for frame in range(1, 91):
        pose = root.copy()
        pose[2] -= 1.4 * frame / 60
        human.set_motion(frame / 60, pose)
        world.step()
    return np.array(cape.positions)


def test_every_instruction_set_gives_the_same_cape():
    before = capecloth.simd_level()
    assert capecloth.simd_available() in ("portable", "avx2")
    levels = ["portable"] + (["avx2"] if capecloth.simd_available() == "avx2" else [])
    results = []
    try:
        for level in levels:
            capecloth.set_simd_level(level)
            assert capecloth.simd_level() == level
            results.append(walk_positions())
    finally:
        capecloth.set_simd_level(before)
    for r in results:
        assert np.all(np.isfinite(r))
        assert np.array_equal(r, results[0])  # bit for bit


def test_a_bad_instruction_set_is_refused():
    before = capecloth.simd_level()
    with pytest.raises(ValueError, match="portable"):
        capecloth.set_simd_level("sse9")
    if capecloth.simd_available() == "portable":
        with pytest.raises(ValueError, match="AVX2"):
            capecloth.set_simd_level("avx2")
    assert capecloth.simd_level() == before
