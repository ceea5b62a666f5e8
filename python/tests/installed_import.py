"""The installed-package check (ctest python_installed, run by install_test.cmake).

Usage: installed_import.py PREFIX SHARED_DATA_DIR

`import pliant` must come from PREFIX (not the build tree) and, when the cloth-funnel frames are
in SHARED_DATA_DIR, reproduce `pliant collide 227.ply --to 228.ply`: 7,319 vertex-face and
33,770 edge-edge pairs (swept, no inflation).
"""

import os
import sys


def main() -> int:
    prefix = os.path.realpath(sys.argv[1])
    data = sys.argv[2]
    import pliant

    where = os.path.realpath(pliant.__file__)
    if not where.startswith(prefix + os.sep):
        print(f"pliant imported from {where}, not from {prefix}", file=sys.stderr)
        return 1
    print(f"pliant {pliant.__version__} from {os.path.dirname(where)}")

    frames = os.path.join(data, "cloth-funnel", "frames")
    t0, t1 = os.path.join(frames, "227.ply"), os.path.join(frames, "228.ply")
    if not (os.path.exists(t0) and os.path.exists(t1)):
        print(f"cloth-funnel frames not found under {frames}: import checked only")
        return 0
    m0, m1 = pliant.read_mesh(t0), pliant.read_mesh(t1)
    broad_phase = pliant.BroadPhase(m0.triangles, m0.num_vertices)
    pairs = broad_phase.update(m0.positions, m1.positions, inflation=0.0)
    vf, ee = pairs.num_vertex_face, pairs.num_edge_edge
    print(f"cloth-funnel 227 -> 228: {vf:,} vertex-face, {ee:,} edge-edge pairs")
    if (vf, ee) != (7319, 33770):
        print("expected 7,319 vertex-face and 33,770 edge-edge pairs", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
