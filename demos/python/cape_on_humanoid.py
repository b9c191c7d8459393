#!/usr/bin/env python3
"""A cape on the shipped humanoid, stepped from poses computed in Python, with its metrics printed.

The humanoid walks: its root moves along the facing direction and its hips, knees, shoulders and elbows swing
by a gait computed here (not the library's), fed every frame through Character.set_motion. At the end the
run's metrics are printed; --gltf writes the run as a glTF binary. Nothing is written unless asked.

    PYTHONPATH=build/python python3 demos/python/cape_on_humanoid.py --seconds 5 --gltf /tmp/walk.glb
"""
import argparse
import math
import sys
import time

import numpy as np

import capecloth


def joint_angles(t, step_hz, swing):
    """Anatomical joint angles (rad) of the shipped humanoid at time t (s): legs and arms swing in opposition."""
    p = 2.0 * math.pi * step_hz * t
    return {
        "left_hip_pitch": swing * math.sin(p),
        "right_hip_pitch": -swing * math.sin(p),
        "left_knee": 0.05 + 0.8 * max(0.0, math.cos(p)) ** 2,
        "right_knee": 0.05 + 0.8 * max(0.0, -math.cos(p)) ** 2,
        "left_ankle": 0.0,
        "right_ankle": 0.0,
        "left_shoulder_pitch": -0.6 * swing * math.sin(p),
        "right_shoulder_pitch": 0.6 * swing * math.sin(p),
        "left_elbow": 0.4 + 0.2 * (1 - math.sin(p)) / 2,
        "right_elbow": 0.4 + 0.2 * (1 + math.sin(p)) / 2,
    }


def positive(kind):
    def parse(text):
        value = kind(text)
        if not math.isfinite(value) or value <= 0:
            raise argparse.ArgumentTypeError(f"must be a finite number > 0, not {text}")
        return value

    return parse


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=positive(float), default=4.0, help="simulated time, s (default 4)")
    parser.add_argument("--speed", type=float, default=1.4, help="walking speed, m/s (default 1.4)")
    parser.add_argument("--step-hz", type=positive(float), default=0.9, help="leg cycles per second (default 0.9)")
    parser.add_argument("--swing", type=float, default=0.45, help="hip swing amplitude, rad (default 0.45)")
    parser.add_argument("--resolution", type=int, default=20, help="cape particles per side (default 20)")
    parser.add_argument("--pins", choices=["corners", "collar"], default="corners")
    parser.add_argument("--up", choices=["y", "z"], default="y", help="the world's up axis (default y)")
    parser.add_argument("--wind", type=float, default=0.0, help="aerodynamic wind speed from the front, m/s")
    parser.add_argument("--self-collision", action="store_true", help="keep the cape from passing through itself")
    parser.add_argument("--gltf", metavar="FILE.glb", help="write the run as a glTF binary (default: nothing)")
    parser.add_argument("--version", action="version", version=f"%(prog)s (capecloth {capecloth.__version__})")
    args = parser.parse_args(argv)
    if not math.isfinite(args.speed) or not math.isfinite(args.swing) or not math.isfinite(args.wind):
        parser.error("--speed, --swing and --wind must be finite")

    world = capecloth.World(up=args.up)
    human = world.add_humanoid()
    settings = capecloth.CapeSettings()
    settings.self_collision = args.self_collision
    if args.wind > 0:
        settings.wind.model = capecloth.WindSettings.Model.AERODYNAMIC
        settings.wind.speed = args.wind
    cape = human.attach_cape(resolution=args.resolution, pins=args.pins, settings=settings)
    print(cape.description)

    # The character's facing direction in the world: the Y-up scenes face -Z, a Z-up world faces +X.
    forward = np.array([0.0, 0.0, -1.0]) if args.up == "y" else np.array([1.0, 0.0, 0.0])
    up = np.array([0.0, 1.0, 0.0]) if args.up == "y" else np.array([0.0, 0.0, 1.0])
    if args.wind > 0:
        w = cape.wind
        w.direction = -forward  # blowing into the character's face
        cape.wind = w
    root0 = human.link_poses()[0]
    if args.gltf:
        world.start_recording()
    frames = int(round(args.seconds * 60))
    wall = 0.0
    for f in range(1, frames + 1):
        t = f / 60.0
        root = root0.copy()
        root[:3] += forward * args.speed * t + up * 0.015 * math.sin(4 * math.pi * args.step_hz * t)
        human.set_motion(t, root, joints=joint_angles(t, args.step_hz, args.swing))
        begin = time.perf_counter()
        world.step()
        wall += time.perf_counter() - begin

    s = cape.summary()
    torso = human.link_poses()[human.link_names.index("torso")]
    centre = cape.positions.mean(axis=0)
    print(f"frames {s['frames']}, {1e3 * wall / frames:.2f} ms a frame (world.step)")
    print(f"max strain {100 * s['max_strain']:.2f} %, median of the frames' max {100 * s['median_frame_max_strain']:.2f} %")
    print(f"max penetration {1e3 * s['max_penetration']:.2f} mm, pin error max {1e3 * s['pin_error_max']:.2f} mm")
    print(f"cape centre {-np.dot(centre - torso[:3], forward):.3f} m behind the torso; blow-up: {s['blow_up']}")
    for w in cape.warnings:
        print("warning:", w)
    if args.gltf:
        n = world.write_gltf(args.gltf)
        print(f"wrote {args.gltf} ({n} frames)")
    return 1 if s["blow_up"] else 0


if __name__ == "__main__":
    sys.exit(main())
