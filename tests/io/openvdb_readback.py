"""Reads a .vdb file with OpenVDB's own Python module and prints, as JSON, every grid's name,
value type, metadata of interest, active voxel count, and each active voxel (or tile) with its
index box, its value and the world position of its index (the voxel centre). Used by
tests/io/openvdb_python_test.cpp: an independent reader of the files pliant writes.

    /usr/bin/python3 openvdb_readback.py FILE.vdb
Exit code 3 when pyopenvdb is not installed (the test skips).
"""
import json
import sys

try:
    import pyopenvdb as vdb
except ImportError:
    sys.exit(3)


def main(path):
    out = {}
    for header in vdb.readAllGridMetadata(path):
        grid = vdb.read(path, header.name)
        voxels = []
        for item in grid.citerOnValues():
            value = item.value
            value = list(value) if isinstance(value, tuple) else [value]
            voxels.append({"min": list(item.min), "max": list(item.max), "value": value,
                           "world": list(grid.transform.indexToWorld(item.min))})
        meta = dict(grid.metadata)
        out[grid.name] = {
            "type": grid.valueTypeName,
            "class": meta.get("class", ""),
            "background": grid.background if not isinstance(grid.background, tuple)
            else list(grid.background),
            "active": grid.activeVoxelCount(),
            "pliant_dims": list(meta.get("pliant_dims", ())),
            "pliant_voxel_type": meta.get("pliant_voxel_type", ""),
            "voxels": voxels,
        }
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])
