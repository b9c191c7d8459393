"""demos/python/cape_on_humanoid.py runs, prints its metrics, and writes only what it is asked to."""
import os
import subprocess
import sys

from conftest import REPO

EXAMPLE = REPO / "demos" / "python" / "cape_on_humanoid.py"


def run(*args, cwd):
    return subprocess.run([sys.executable, str(EXAMPLE), *args], cwd=cwd, env=os.environ.copy(),
                          capture_output=True, text=True, timeout=600)


def test_help_lists_the_options(tmp_path):
    r = run("--help", cwd=tmp_path)
    assert r.returncode == 0 and "--gltf" in r.stdout and "--seconds" in r.stdout


def test_the_example_walks_and_prints_metrics_writing_nothing(tmp_path):
    r = run("--seconds", "2", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "max strain" in r.stdout and "behind the torso" in r.stdout and "blow-up: False" in r.stdout
    assert list(tmp_path.iterdir()) == []


def test_the_example_writes_a_gltf_when_asked(tmp_path):
    out = tmp_path / "walk.glb"
    r = run("--seconds", "1", "--up", "z", "--self-collision", "--wind", "5", "--gltf", str(out), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:4] == b"glTF"


def test_bad_arguments_are_refused(tmp_path):
    r = run("--seconds", "-1", cwd=tmp_path)
    assert r.returncode == 2 and "seconds" in r.stderr
