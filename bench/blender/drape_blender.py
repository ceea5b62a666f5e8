"""The drape scene in Blender's cloth solver, timed per frame, every frame exported as OBJ.

Run (Blender 3.4, headless):

    blender -b --factory-startup --python bench/blender/drape_blender.py -- --out DIR [--frames N]

Builds, from an empty scene, the drape scene of scenes/drape.json: a 2 m x 2 m sheet of
134 x 134 quads split into 35,912 triangles (the same vertex order and the same triangles as
pliant's geometry::make_grid_sheet), 1.2 m above a sphere of radius 0.5 m at the origin, gravity
-9.81 m/s^2 along z, 24 fps. The cloth modifier runs quality 5 with self-collision, collision
distances 5 mm, the Cotton preset (vertex mass 0.3 kg: pliant's 0.15 kg/m^2 does not drape in
Blender, see MATCHED_VERTEX_MASS), a speed multiplier that makes a frame 1/24 s, and the sphere's
default outer thickness of 20 mm (SETTINGS below lists every value set, bench/blender/README.md
explains the three deviations).

Timing: the frames are stepped in order with scene.frame_set(f); the cloth modifier simulates
one frame (quality substeps) on each frame change, into its in-memory point cache. Each
frame_set is timed with time.perf_counter; exporting the frame is not included.

Frames: Blender's scene frame 1 is the rest state (pliant's frame 0); scene frames 2 ... N + 1
are the N simulated frames (pliant's frames 1 ... N). Writes DIR/frames/frame_NNNN.obj for
NNNN = 0 ... N (vertices and triangles only, the same triangles every frame) and
DIR/stats.json.
"""

import argparse
import json
import os
import platform
import sys
import time
from array import array

import bpy

QUADS = 134
SIZE = 2.0
HEIGHT = 1.2
SPHERE_RADIUS = 0.5
AREAL_DENSITY = 0.15  # kg/m^2, pliant's material.areal_density
FPS = 24
GRAVITY = -9.81
NUM_VERTICES = (QUADS + 1) * (QUADS + 1)
# pliant's areal density as a Blender "Vertex Mass" (kg per vertex): 3.29e-5. Not the default:
# Blender's stiffness, damping and drag are forces that do not scale with the mass, and with this
# mass its implicit solver's conjugate gradient (100 iterations at most) no longer converges: the
# sheet sinks at a few mm per frame and never reaches the sphere in 72 frames (README.md). Use
# --set cloth.mass=3.2922e-05 --set cloth.air_damping=0.0016461 to run it anyway (air damping
# then matches pliant's damping of 0.5/s: Blender's drag is -0.01 * air_damping * v per vertex).
MATCHED_VERTEX_MASS = AREAL_DENSITY * SIZE * SIZE / NUM_VERTICES
# Blender's cloth measures time in frames whatever the fps (gravity is scaled by 0.001 per
# frame^2, i.e. one frame is sqrt(0.001) s = 1/31.6 s): at 24 fps and a speed multiplier of 1 it
# falls at 0.576 g. This speed multiplier makes one frame 1/24 s, as in pliant's scene.
TIME_SCALE = (1000.0 ** 0.5) / FPS

# Every value set on the cloth modifier and the collision object (a fresh cloth modifier's
# default is given where it differs).
SETTINGS = {
    "cloth": {
        "quality": 5,  # substeps per frame (default 5)
        # The Cotton preset (presets/cloth/Cotton.py); only shear differs from the defaults.
        "mass": 0.3,  # "Vertex Mass", kg (see MATCHED_VERTEX_MASS above)
        "air_damping": 1.0,
        "tension_stiffness": 15.0,
        "compression_stiffness": 15.0,
        "shear_stiffness": 15.0,  # (default 5)
        "bending_stiffness": 0.5,
        "tension_damping": 5.0,
        "compression_damping": 5.0,
        "shear_damping": 5.0,
        "bending_damping": 0.5,
        "bending_model": "ANGULAR",
        "time_scale": TIME_SCALE,  # "Speed Multiplier" (default 1; see TIME_SCALE above)
        "gravity_effector_weight": 1.0,
    },
    "collision": {
        "use_collision": True,
        "distance_min": 0.005,  # m, "Object Collisions > Distance" (default 0.015)
        "collision_quality": 2,  # (default 2)
        "impulse_clamp": 0.0,
        "use_self_collision": True,  # (default off)
        "self_distance_min": 0.005,  # m, "Self Collisions > Distance" (default 0.015)
        "self_friction": 5.0,  # default: Coulomb 0.05 (pliant: no friction between layers)
        "self_impulse_clamp": 0.0,
    },
    "sphere": {
        "mesh": "UV sphere, 64 segments x 32 rings, smooth shading",
        "radius": SPHERE_RADIUS,
        # Blender keeps the cloth at distance_min + this outer thickness from the obstacle
        # (collision.c: epsilon + the obstacle BVH's epsilon), here 25 mm. The default, kept:
        # with the smallest value Blender accepts, 0.001 (6 mm in all), the sheet passes
        # through the sphere at impact (its object collisions are discrete; README.md).
        "thickness_outer": 0.02,
        # Coulomb coefficient x 100 (collision.c: pdef_cfrict * 0.01): pliant's kinetic 0.3
        # (Blender has one coefficient; pliant's static one is 0.4). Default 5.
        "cloth_friction": 30.0,
        "damping": 0.1,  # default
        "use_culling": True,  # default
    },
    "scene": {"fps": FPS, "gravity": [0.0, 0.0, GRAVITY]},
}


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="drape_blender.py")
    parser.add_argument("--out", required=True, help="output directory")
    parser.add_argument("--frames", type=int, default=72, help="simulated frames (default 72)")
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                        help="override one of SETTINGS (experiments only; recorded in stats)")
    args = parser.parse_args(argv)
    for item in args.set:
        key, _, value = item.partition("=")
        section, _, name = key.partition(".")
        if section not in SETTINGS or name not in SETTINGS[section]:
            parser.error("--set %s: unknown setting" % item)
        old = SETTINGS[section][name]
        SETTINGS[section][name] = (value.lower() in ("1", "true", "on") if isinstance(old, bool)
                                   else type(old)(value))
        SETTINGS.setdefault("overridden", []).append(item)
    if args.frames < 0:
        parser.error("--frames must be >= 0")
    return args


def grid_sheet():
    """pliant's geometry::make_grid_sheet(134, 134, 2, 2), translated to z = HEIGHT."""
    n = QUADS
    verts = [(SIZE * (i / n - 0.5), SIZE * (j / n - 0.5), HEIGHT)
             for j in range(n + 1) for i in range(n + 1)]
    tris = []
    for j in range(n):
        for i in range(n):
            a, b = j * (n + 1) + i, j * (n + 1) + i + 1
            c, d = (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            if (i + j) % 2 == 0:
                tris += [(a, b, c), (a, c, d)]
            else:
                tris += [(a, b, d), (b, c, d)]
    return verts, tris


def build_scene(frames):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = FPS
    scene.render.fps_base = 1.0
    scene.use_gravity = True
    scene.gravity = (0.0, 0.0, GRAVITY)
    scene.frame_start = 1
    scene.frame_end = frames + 1

    verts, tris = grid_sheet()
    mesh = bpy.data.meshes.new("sheet")
    mesh.from_pydata(verts, [], tris)
    mesh.update()
    cloth = bpy.data.objects.new("sheet", mesh)
    scene.collection.objects.link(cloth)

    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=SPHERE_RADIUS,
                                         location=(0.0, 0.0, 0.0))
    sphere = bpy.context.active_object
    sphere.name = "sphere"
    bpy.ops.object.shade_smooth()
    sphere.modifiers.new("Collision", "COLLISION")
    col = sphere.collision
    s = SETTINGS["sphere"]
    col.thickness_outer = s["thickness_outer"]
    col.cloth_friction = s["cloth_friction"]
    col.damping = s["damping"]
    col.use_culling = s["use_culling"]

    mod = cloth.modifiers.new("Cloth", "CLOTH")
    cs = mod.settings
    c = SETTINGS["cloth"]
    for key in ("quality", "mass", "air_damping", "tension_stiffness", "compression_stiffness",
                "shear_stiffness", "bending_stiffness", "tension_damping", "compression_damping",
                "shear_damping", "bending_damping", "bending_model", "time_scale"):
        setattr(cs, key, c[key])
    cs.effector_weights.gravity = c["gravity_effector_weight"]
    cc = mod.collision_settings
    for key, value in SETTINGS["collision"].items():
        setattr(cc, key, value)
    mod.point_cache.frame_start = 1
    mod.point_cache.frame_end = frames + 1
    # Read back what Blender stored (floats are single precision).
    SETTINGS["cloth"]["mass"] = cs.mass
    SETTINGS["cloth"]["air_damping"] = cs.air_damping
    SETTINGS["cloth"]["time_scale"] = cs.time_scale
    return scene, cloth, tris


def evaluated_positions(cloth, depsgraph):
    ev = cloth.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    co = array("f", [0.0]) * (len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    npoly = len(mesh.polygons)
    loops = array("i", [0]) * len(mesh.loops)
    mesh.loops.foreach_get("vertex_index", loops)
    totals = array("i", [0]) * npoly
    mesh.polygons.foreach_get("loop_total", totals)
    ev.to_mesh_clear()
    m = ev.matrix_world
    if m != m.Identity(4):
        raise RuntimeError("the cloth object has a non-identity transform")
    return co, loops, totals


def write_obj(path, co, faces_text):
    lines = ["v %.9g %.9g %.9g\n" % (co[k], co[k + 1], co[k + 2]) for k in range(0, len(co), 3)]
    tmp = path + ".tmp-blender"
    with open(tmp, "w") as f:
        f.write("".join(lines))
        f.write(faces_text)
    os.replace(tmp, path)


def main():
    args = parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(os.path.join(out, "frames"), exist_ok=True)
    load_start = os.getloadavg()
    scene, cloth, tris = build_scene(args.frames)
    faces_text = "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in tris)
    expected_loops = array("i", [v for t in tris for v in t])

    def export(number, co, loops, totals):
        if len(co) != 3 * NUM_VERTICES or len(totals) != len(tris) or any(
                t != 3 for t in totals) or loops != expected_loops:
            raise RuntimeError("frame %d: the evaluated cloth mesh is not the sheet's %d "
                               "vertices and %d triangles" % (number, NUM_VERTICES, len(tris)))
        write_obj(os.path.join(out, "frames", "frame_%04d.obj" % number), co, faces_text)
        zs = co[2::3]
        xs, ys = co[0::3], co[1::3]
        return {"min": [min(xs), min(ys), min(zs)], "max": [max(xs), max(ys), max(zs)]}

    t0 = time.perf_counter()
    scene.frame_set(1)
    init_ms = (time.perf_counter() - t0) * 1e3
    depsgraph = bpy.context.evaluated_depsgraph_get()
    export(0, *evaluated_positions(cloth, depsgraph))

    frames = []
    wall0 = time.perf_counter()
    for n in range(1, args.frames + 1):
        t0 = time.perf_counter()
        scene.frame_set(n + 1)
        ms = (time.perf_counter() - t0) * 1e3
        depsgraph = bpy.context.evaluated_depsgraph_get()
        t1 = time.perf_counter()
        bbox = export(n, *evaluated_positions(cloth, depsgraph))
        export_ms = (time.perf_counter() - t1) * 1e3
        frames.append({"frame": n, "scene_frame": n + 1, "ms": ms, "export_ms": export_ms,
                       "bbox": bbox})
        print("blender frame %d/%d: %.1f ms (min z %.4f)" % (n, args.frames, ms, bbox["min"][2]),
              flush=True)
    wall_s = time.perf_counter() - wall0

    ms_list = [f["ms"] for f in frames]
    stats = {
        "tool": "blender",
        "blender_version": bpy.app.version_string,
        "blender_build": {"hash": bpy.app.build_hash.decode(errors="replace"),
                          "binary": bpy.app.binary_path},
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "scene": "drape (scenes/drape.json), built in bench/blender/drape_blender.py",
        "vertices": NUM_VERTICES,
        "triangles": len(tris),
        "fps": FPS,
        "timing": "scene.frame_set(f) for f = 2 ... N + 1 in order, each timed with "
                  "time.perf_counter (the cloth modifier simulates one frame into its in-memory "
                  "point cache on each frame change); exporting is not included",
        "init_ms": init_ms,
        "frames": frames,
        "mean_ms_per_frame": sum(ms_list) / len(ms_list) if ms_list else 0.0,
        "min_ms_per_frame": min(ms_list) if ms_list else 0.0,
        "max_ms_per_frame": max(ms_list) if ms_list else 0.0,
        "wall_seconds": wall_s,
        "loadavg_start": list(load_start),
        "loadavg_end": list(os.getloadavg()),
        "settings": SETTINGS,
        "areal_density": SETTINGS["cloth"]["mass"] * NUM_VERTICES / (SIZE * SIZE),
        "pliant_matched_vertex_mass": MATCHED_VERTEX_MASS,
    }
    tmp = os.path.join(out, "stats.json.tmp-blender")
    with open(tmp, "w") as f:
        json.dump(stats, f, indent=1)
        f.write("\n")
    os.replace(tmp, os.path.join(out, "stats.json"))
    print("blender: %d frames, mean %.1f ms per frame -> %s" % (
        len(frames), stats["mean_ms_per_frame"], out), flush=True)


if __name__ == "__main__":
    try:
        main()
    except SystemExit as e:
        # argparse errors: leave Blender with a non-zero exit code.
        sys.stdout.flush()
        os._exit(e.code if isinstance(e.code, int) else 2)
    except Exception:
        import traceback
        traceback.print_exc()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(1)
    sys.stdout.flush()
    os._exit(0)
