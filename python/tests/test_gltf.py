"""glTF export: a valid GLB whose header length is the file's size, with the cape's mesh and animation."""
import json
import struct

import capecloth


def test_a_recorded_walk_is_a_valid_glb(tmp_path, shoulders_world):
    world, (torso, left, right), cape = shoulders_world
    world.start_recording()
    for f in range(30):
        for b in (torso, left, right):
            p = b.pose()
            p[2] -= 0.01
            b.set_pose(p)
        world.step()
    assert world.recorded_frames == 31
    path = tmp_path / "walk.glb"
    assert world.write_gltf(path) == 31
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and length == len(data)
    chunk_length, chunk_type = struct.unpack_from("<II", data, 12)
    assert chunk_type == 0x4E4F534A  # JSON
    doc = json.loads(data[20 : 20 + chunk_length])
    assert doc["asset"]["version"] == "2.0"
    assert len(doc["animations"]) >= 1
    # The cape's mesh has one morph target per frame after the first; the colliders are nodes of their own.
    targets = max(len(p.get("targets", [])) for m in doc["meshes"] for p in m["primitives"])
    assert targets == 30
    assert len(doc["nodes"]) >= 4
    bin_length, bin_type = struct.unpack_from("<II", data, 20 + chunk_length)
    assert bin_type == 0x004E4942 and 28 + chunk_length + bin_length == len(data)
    assert not world.recording


def test_recording_freezes_what_is_in_the_world(shoulders_world):
    world, _, _ = shoulders_world
    world.start_recording()
    try:
        world.add_sphere(0.1)
        raise AssertionError("a body was added while recording")
    except RuntimeError as e:
        assert "recording" in str(e)
