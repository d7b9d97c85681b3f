#!/usr/bin/env python3
"""Writes the shipped camera rigs in assets/rigs/ as OpenCV FileStorage YAML.

Run from the repository root: tools/generate_rigs.py. Each camera is placed at a position and
aimed at a target (OpenCV camera frame: x right, y down, z forward; world: +Y up, -Z forward).
"""
import math
import os


def sub(a, b): return [a[i] - b[i] for i in range(3)]
def cross(a, b): return [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]
def norm(a):
    n = math.sqrt(sum(x*x for x in a))
    return [x / n for x in a]


def look_at(position, target):
    z = norm(sub(target, position))
    # Image y down towards the floor; looking straight down, towards world +Z instead.
    x = norm(cross(z, [0.0, 0.0, 1.0] if abs(z[1]) > 0.999999 else [0.0, 1.0, 0.0]))
    y = cross(z, x)
    rotation = [x, y, z]  # rows of cam_from_world's rotation
    translation = [-sum(rotation[r][c] * position[c] for c in range(3)) for r in range(3)]
    return rotation, translation


def matrix(name, rows, cols, values, indent):
    data = ", ".join(repr(float(round(v, 12))) for v in values)
    pad = " " * indent
    return (f"{pad}{name}: !!opencv-matrix\n{pad}   rows: {rows}\n{pad}   cols: {cols}\n"
            f"{pad}   dt: d\n{pad}   data: [ {data} ]\n")


def write_rig(path, rig_name, cameras, volume_centre, volume_size):
    out = ["%YAML:1.0\n---\n", f"rig_name: \"{rig_name}\"\n", "cameras:\n"]
    for cam in cameras:
        rotation, translation = look_at(cam["position"], cam["target"])
        w, h, f = cam["width"], cam["height"], cam["f"]
        out.append(f"   -\n      name: \"{cam['name']}\"\n      image_width: {w}\n      image_height: {h}\n")
        out.append(matrix("camera_matrix", 3, 3, [f, 0, (w - 1) / 2, 0, f, (h - 1) / 2, 0, 0, 1], 6))
        out.append(matrix("distortion_coefficients", 1, 5, cam["dist"], 6))
        out.append(matrix("rotation", 3, 3, [v for row in rotation for v in row], 6))
        out.append(matrix("translation", 3, 1, translation, 6))
    out.append(matrix("volume_centre", 3, 1, volume_centre, 0))
    out.append(matrix("volume_size", 3, 1, volume_size, 0))
    with open(path, "w") as fh:
        fh.write("".join(out))


def main():
    os.makedirs("assets/rigs", exist_ok=True)
    webcam = dict(width=1280, height=720, f=900.0, dist=[-0.05, 0.01, 0.0, 0.0, 0.0])
    # Seated: a 1 x 1 x 1 m volume above a desk (table top at 0.74 m, user at the origin).
    centre = [0.0, 1.1, -0.45]
    seated = [dict(webcam, name=n, position=p, target=centre) for n, p in [
        ("front-left", [-0.8, 1.9, -1.3]), ("front-right", [0.8, 1.9, -1.3]),
        ("back-left", [-0.8, 1.9, 0.35]), ("back-right", [0.8, 1.9, 0.35])]]
    write_rig("assets/rigs/seated-4.yaml", "seated-4", seated, centre, [1.0, 1.0, 1.0])
    # Room: about 4 x 4 x 2 m, cameras on the walls at 2.4 m looking at the middle at 1 m.
    room_centre = [0.0, 1.0, 0.0]
    room = []
    for i in range(8):
        a = 2 * math.pi * i / 8
        room.append(dict(webcam, name=f"wall-{i}", position=[2.2 * math.cos(a), 2.4, 2.2 * math.sin(a)], target=room_centre))
    write_rig("assets/rigs/room-8.yaml", "room-8", room, room_centre, [3.0, 1.6, 3.0])
    # Stage: a 10 x 10 m floor tracked up to 2 m, 32 cameras with wider lenses (about 84 degrees
    # across). 7 on each wall at 3.5 m, 1.5 m apart and 0.5 m outside the volume, each aimed 3.5 m
    # into the volume at 1 m (so each sees about its own third of the floor), and 4 on the ceiling
    # at 6 m above the quarters' centres, looking straight down a little off vertical.
    stage_lens = dict(width=1280, height=720, f=700.0, dist=[-0.08, 0.015, 0.0, 0.0, 0.0])
    stage = []
    for wall, (nx, nz) in enumerate([(0, -1), (1, 0), (0, 1), (-1, 0)]):
        for k in range(7):
            along = -4.5 + 1.5 * k
            tx, tz = -nz, nx  # along the wall
            x, z = 5.5 * nx + along * tx, 5.5 * nz + along * tz
            target = [x - 4.0 * nx, 1.0, z - 4.0 * nz]
            stage.append(dict(stage_lens, name=f"wall-{wall}-{k}", position=[x, 3.5, z], target=target))
    for k, (qx, qz) in enumerate([(-2.5, -2.5), (2.5, -2.5), (2.5, 2.5), (-2.5, 2.5)]):
        stage.append(dict(stage_lens, name=f"ceiling-{k}", position=[qx, 6.0, qz], target=[qx * 0.9, 0.0, qz * 0.9 + 0.3]))
    write_rig("assets/rigs/stage-32.yaml", "stage-32", stage, [0.0, 1.0, 0.0], [10.0, 2.0, 10.0])
    # Seed 000's Wiimote set-ups (chapter 8, "Setup Toolkit"): parallel Wiimotes 1 m apart along
    # X and Z, looking straight down from 7 m, tracking up to 2 m above the floor. The Wiimote:
    # 1024 x 768, focal length 1360 px (seed 000's alpha, section 4: about 41 x 31 degrees), no
    # distortion; the long side of the image along X. 4.6 x 4.6 x 2 m: 10 Wiimotes, 5 along X by 2
    # along Z; 8 x 8 x 2 m: 54 Wiimotes, 9 by 6.
    seed_wiimote = dict(width=1024, height=768, f=1360.0, dist=[0.0, 0.0, 0.0, 0.0, 0.0])
    for name, (nx, nz), side in [("seed-wiimote-10", (5, 2), 4.6), ("seed-wiimote-54", (9, 6), 8.0)]:
        cams = []
        for j in range(nz):
            for i in range(nx):
                x, z = i - (nx - 1) / 2, j - (nz - 1) / 2
                cams.append(dict(seed_wiimote, name=f"wiimote-{j * nx + i}", position=[x, 7.0, z], target=[x, 0.0, z]))
        write_rig(f"assets/rigs/{name}.yaml", name, cams, [0.0, 1.0, 0.0], [side, 2.0, side])
    # Stereo pair: 20 cm baseline above the user's head, looking at the desk volume (Wiimote-like
    # 1024 x 768 infrared cameras, about 45 degrees across).
    wiimote = dict(width=1024, height=768, f=1280.0, dist=[0.0, 0.0, 0.0, 0.0, 0.0])
    stereo = [dict(wiimote, name="left", position=[-0.1, 1.6, 0.3], target=[-0.1, 1.0, -0.45]),
              dict(wiimote, name="right", position=[0.1, 1.6, 0.3], target=[0.1, 1.0, -0.45])]
    write_rig("assets/rigs/stereo-2.yaml", "stereo-2", stereo, [0.0, 1.0, -0.45], [0.6, 0.6, 0.6])
    # Seed 002's RHOT set-up: two Raspberry Pi cameras (640 x 480, about 54 degrees across, a
    # little barrel distortion) 30 cm apart, above and behind the user's hands, about 1 m from them.
    pi = dict(width=640, height=480, f=630.0, dist=[0.02, -0.04, 0.0, 0.0, 0.0])
    pair = [dict(pi, name="left", position=[-0.15, 1.65, 0.2], target=[0.0, 0.95, -0.45]),
            dict(pi, name="right", position=[0.15, 1.65, 0.2], target=[0.0, 0.95, -0.45])]
    write_rig("assets/rigs/stereo-640.yaml", "stereo-640", pair, [0.0, 0.95, -0.45], [0.6, 0.4, 0.5])


if __name__ == "__main__":
    main()
