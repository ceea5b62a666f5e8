"""A synthetic hand-held capture without poses, rendered by Blender (Cycles on the CPU).

Run through scripts/make-capture (which calls `blender -b --factory-startup -P make_capture.py --
ARGS`). Writes, under OUT:
  images/frame_NNNN.jpg   the photos: a textured object on a textured table, a camera walking
                          around it at two heights with hand-held jitter, lens distortion of the
                          OPENCV model, JPEG
  ground_truth.json       the true intrinsics, distortion and camera-to-world poses (OpenGL axes,
                          Blender's world: metres, +z up). The pose pipeline never reads it; tests
                          use it to check recovered poses after a similarity alignment.

Distortion: each photo is rendered as an ideal pinhole image wider than the photo (same focal
length, principal point at its centre); every photo pixel centre (u, v) is mapped to normalized
distorted coordinates ((u - cx) / fx, (v - cy) / fy), undistorted by Newton iterations on the OPENCV
model (COLMAP's and OpenCV's definition):
    r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2
    xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
    yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
and the pinhole render is sampled bilinearly there. Pixel centres are at (i + 0.5, j + 0.5), as in
COLMAP and pliant.
"""

import argparse
import json
import math
import os
import subprocess
import sys

import bpy
import numpy as np
from mathutils import Matrix, Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="make-capture")
    p.add_argument("out", help="output directory (images/ and ground_truth.json go there)")
    p.add_argument("--views", type=int, default=64, help="number of photos (two rings)")
    p.add_argument("--width", type=int, default=480)
    p.add_argument("--height", type=int, default=360)
    p.add_argument("--focal", type=float, default=400.0, help="focal length in pixels")
    p.add_argument("--samples", type=int, default=24, help="Cycles samples per pixel")
    p.add_argument("--quality", type=int, default=90, help="JPEG quality")
    p.add_argument("--seed", type=int, default=1)
    return p.parse_args(argv)


# Intrinsics of the photos: a principal point off centre and mild barrel distortion, as a phone
# calibration looks.
def intrinsics(args):
    return {
        "w": args.width, "h": args.height, "fl_x": args.focal, "fl_y": args.focal * 1.002,
        "cx": args.width / 2 + 3.5, "cy": args.height / 2 - 2.25,
        "k1": -0.11, "k2": 0.035, "p1": 0.0008, "p2": -0.0012, "camera_model": "OPENCV",
    }


def distort(x, y, k):
    r2 = x * x + y * y
    radial = 1 + k["k1"] * r2 + k["k2"] * r2 * r2
    xd = x * radial + 2 * k["p1"] * x * y + k["p2"] * (r2 + 2 * x * x)
    yd = y * radial + k["p1"] * (r2 + 2 * y * y) + 2 * k["p2"] * x * y
    return xd, yd


def undistort(xd, yd, k):
    """Newton iterations on distort(x, y) = (xd, yd), Jacobian by central differences."""
    x, y = xd.copy(), yd.copy()
    eps = 1e-7
    for _ in range(20):
        fx, fy = distort(x, y, k)
        rx, ry = fx - xd, fy - yd
        ax, ay = distort(x + eps, y, k)
        bx, by = distort(x - eps, y, k)
        j11, j21 = (ax - bx) / (2 * eps), (ay - by) / (2 * eps)
        ax, ay = distort(x, y + eps, k)
        bx, by = distort(x, y - eps, k)
        j12, j22 = (ax - bx) / (2 * eps), (ay - by) / (2 * eps)
        det = j11 * j22 - j12 * j21
        x = x - (j22 * rx - j12 * ry) / det
        y = y - (-j21 * rx + j11 * ry) / det
    fx, fy = distort(x, y, k)
    assert np.max(np.abs(fx - xd)) < 1e-9 and np.max(np.abs(fy - yd)) < 1e-9, "undistort failed"
    return x, y


def procedural_material(name, scale, colors, bump=0.3, voronoi=True):
    """A diffuse material with noise and Voronoi colour texture: plenty of SIFT features."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    bsdf = nt.nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.8
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    noise.inputs["Detail"].default_value = 15.0
    noise.inputs["Roughness"].default_value = 0.65
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = colors[0]
    ramp.color_ramp.elements[1].color = colors[1]
    ramp.color_ramp.elements[0].position = 0.38  # noise values cluster near 0.5: stretch them
    ramp.color_ramp.elements[1].position = 0.62
    nt.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    out = ramp.outputs["Color"]
    if voronoi:
        vor = nt.nodes.new("ShaderNodeTexVoronoi")
        vor.inputs["Scale"].default_value = scale * 0.6
        mix = nt.nodes.new("ShaderNodeMixRGB")
        mix.blend_type = "MULTIPLY"
        mix.inputs["Fac"].default_value = 0.35
        nt.links.new(out, mix.inputs["Color1"])
        nt.links.new(vor.outputs["Color"], mix.inputs["Color2"])
        out = mix.outputs["Color"]
    nt.links.new(out, bsdf.inputs["Base Color"])
    return m


# Image files go through ffmpeg (a pliant dependency) as raw RGB24, so their bytes are what
# Blender wrote (display-referred sRGB, "Standard" view) without another colour conversion.
def read_png(path, width, height):
    raw = subprocess.run(["ffmpeg", "-hide_banner", "-loglevel", "error", "-i", path, "-f",
                          "rawvideo", "-pix_fmt", "rgb24", "-"], check=True,
                         stdout=subprocess.PIPE).stdout
    return np.frombuffer(raw, dtype=np.uint8).reshape(height, width, 3)


def write_jpeg(path, rgb, quality):
    # ffmpeg's mjpeg -q:v runs 2 (best) … 31; map quality 100 … 0 onto it.
    q = max(2, min(31, round(2 + (100 - quality) * 29 / 100)))
    h, w, _ = rgb.shape
    subprocess.run(["ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo",
                    "-pix_fmt", "rgb24", "-s", "%dx%d" % (w, h), "-i", "-", "-pix_fmt", "yuvj444p",
                    "-q:v", str(q), path], check=True, input=rgb.tobytes())


def build_scene(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.seed = args.seed
    scene.cycles.max_bounces = 3
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.55, 0.6, 0.7, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world

    sun_data = bpy.data.lights.new("sun", "SUN")
    sun_data.energy = 3.0
    sun_data.angle = math.radians(10)
    sun = bpy.data.objects.new("sun", sun_data)
    sun.rotation_euler = (math.radians(40), math.radians(15), math.radians(30))
    scene.collection.objects.link(sun)

    # The table: a 4 m square with a stone-like texture.
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 0, 0))
    bpy.context.object.data.materials.append(
        procedural_material("table", 40.0, [(0.15, 0.1, 0.06, 1), (0.85, 0.7, 0.5, 1)]))

    # The object: a monkey head on a box, and a torus beside them.
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(0, 0, 0.25))
    bpy.context.object.data.materials.append(
        procedural_material("box", 14.0, [(0.05, 0.2, 0.5, 1), (0.9, 0.9, 0.8, 1)]))
    bpy.ops.mesh.primitive_monkey_add(size=0.6, location=(0, 0, 0.78))
    head = bpy.context.object
    head.rotation_euler = (math.radians(-10), 0, math.radians(-90))
    mod = head.modifiers.new("subsurf", "SUBSURF")
    mod.levels = mod.render_levels = 2
    bpy.ops.object.shade_smooth()
    head.data.materials.append(
        procedural_material("head", 16.0, [(0.6, 0.15, 0.05, 1), (0.95, 0.85, 0.3, 1)]))
    bpy.ops.mesh.primitive_torus_add(major_radius=0.22, minor_radius=0.07, location=(0.45, -0.3, 0.07))
    bpy.context.object.data.materials.append(
        procedural_material("torus", 20.0, [(0.1, 0.4, 0.1, 1), (0.9, 0.9, 0.9, 1)]))
    return scene


def camera_path(args):
    """Two rings around the object (heights 0.9 m and 1.7 m), a walk with hand-held jitter."""
    rng = np.random.default_rng(args.seed)
    n_low = args.views // 2
    poses = []
    for i in range(args.views):
        ring = 0 if i < n_low else 1
        k = i if ring == 0 else i - n_low
        n = n_low if ring == 0 else args.views - n_low
        angle = 2 * math.pi * (k + rng.normal(0, 0.08)) / n + (0.0 if ring == 0 else math.pi / n)
        radius = (2.4 if ring == 0 else 2.1) + rng.normal(0, 0.05)
        height = (0.9 if ring == 0 else 1.7) + rng.normal(0, 0.04)
        eye = Vector((radius * math.cos(angle), radius * math.sin(angle), height))
        target = Vector((0, 0, 0.45)) + Vector(tuple(rng.normal(0, 0.06, 3)))
        forward = (target - eye).normalized()
        up_world = Vector((0, 0, 1))
        right = forward.cross(up_world).normalized()
        up = right.cross(forward)
        roll = math.radians(rng.normal(0, 3.0))
        right, up = (math.cos(roll) * right + math.sin(roll) * up,
                     -math.sin(roll) * right + math.cos(roll) * up)
        # OpenGL camera-to-world: columns x = right, y = up, z = -forward, translation = eye.
        m = Matrix((
            (right.x, up.x, -forward.x, eye.x),
            (right.y, up.y, -forward.y, eye.y),
            (right.z, up.z, -forward.z, eye.z),
            (0, 0, 0, 1)))
        poses.append(m)
    return poses


def main():
    args = parse_args()
    k = intrinsics(args)
    images_dir = os.path.join(args.out, "images")
    os.makedirs(images_dir, exist_ok=True)

    # Where the photo's pixel centres land in the ideal pinhole image.
    u, v = np.meshgrid(np.arange(args.width) + 0.5, np.arange(args.height) + 0.5)
    x, y = undistort((u - k["cx"]) / k["fl_x"], (v - k["cy"]) / k["fl_y"], k)
    # The pinhole render: square pixels of focal `focal`, centred principal point, wide enough.
    f = args.focal
    half_w = math.ceil(max(np.abs(x).max() * f, 1) + 4)
    half_h = math.ceil(max(np.abs(y).max() * f, 1) + 4)
    rw, rh = 2 * half_w, 2 * half_h
    src_x = x * f + rw / 2 - 0.5  # continuous index into the render (pixel centres at i + 0.5)
    src_y = y * f + rh / 2 - 0.5

    scene = build_scene(args)
    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.sensor_width = 36.0
    cam_data.lens = f * 36.0 / rw
    cam_data.clip_start = 0.05
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x = rw
    scene.render.resolution_y = rh
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_depth = "8"
    tmp_png = os.path.join(args.out, "render_tmp.png")
    scene.render.filepath = tmp_png

    frames = []
    for i, pose in enumerate(camera_path(args)):
        cam.matrix_world = pose
        bpy.ops.render.render(write_still=True)
        px = read_png(tmp_png, rw, rh).astype(np.float64)
        # Bilinear sampling at (src_x, src_y).
        x0 = np.clip(np.floor(src_x).astype(int), 0, rw - 2)
        y0 = np.clip(np.floor(src_y).astype(int), 0, rh - 2)
        ax = (src_x - x0)[..., None]
        ay = (src_y - y0)[..., None]
        out = ((1 - ax) * (1 - ay) * px[y0, x0] + ax * (1 - ay) * px[y0, x0 + 1] +
               (1 - ax) * ay * px[y0 + 1, x0] + ax * ay * px[y0 + 1, x0 + 1])
        name = "frame_%04d.jpg" % i
        write_jpeg(os.path.join(images_dir, name), np.clip(np.rint(out), 0, 255).astype(np.uint8),
                   args.quality)
        frames.append({"file_path": "images/" + name,
                       "transform_matrix": [list(row) for row in pose]})
        print("make-capture: %d/%d %s" % (i + 1, args.views, name), flush=True)
    os.remove(tmp_png)

    truth = dict(k)
    truth["comment"] = ("ground truth of a synthetic capture made by scripts/make-capture; "
                        "camera-to-world in OpenGL axes, Blender world (metres, +z up); "
                        "not read by the pose pipeline")
    truth["frames"] = frames
    with open(os.path.join(args.out, "ground_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1)


main()
