"""Reads a .vtu file written by pliant (VTK XML UnstructuredGrid, binary base64 arrays with UInt64
headers) with Python's own xml, base64 and struct modules, independently of pliant, and prints
its piece counts and every DataArray's values as JSON. When VTK's Python module is importable,
also reads it with vtkXMLUnstructuredGridReader and adds what VTK sees under "vtk".
Used by tests/io/vtu_test.cpp.

    /usr/bin/python3 vtu_readback.py FILE.vtu
"""
import base64
import json
import struct
import sys
import xml.etree.ElementTree as ET

FORMATS = {"Float32": "f", "Float64": "d", "Int64": "q", "Int32": "i", "UInt8": "B"}


def decode(array):
    raw = base64.b64decode(array.text.strip())
    (count,) = struct.unpack_from("<Q", raw, 0)
    if len(raw) != 8 + count:
        raise ValueError(f"{array.get('Name')}: header says {count} bytes, got {len(raw) - 8}")
    code = FORMATS[array.get("type")]
    n = count // struct.calcsize(code)
    return list(struct.unpack_from(f"<{n}{code}", raw, 8))


def main(path):
    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid", root.get("type")
    piece = root.find("UnstructuredGrid/Piece")
    out = {"points": int(piece.get("NumberOfPoints")), "cells": int(piece.get("NumberOfCells")),
           "arrays": {}}
    for section in ("Points", "Cells", "PointData", "CellData"):
        for array in piece.findall(f"{section}/DataArray"):
            out["arrays"][f"{section}/{array.get('Name')}"] = {
                "components": int(array.get("NumberOfComponents", "1")),
                "values": decode(array)}
    try:
        import vtk  # optional: python3-vtk9
    except ImportError:
        vtk = None
    if vtk is not None:
        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(path)
        reader.Update()
        grid = reader.GetOutput()
        out["vtk"] = {"points": grid.GetNumberOfPoints(), "cells": grid.GetNumberOfCells(),
                      "cell_type": grid.GetCellType(0) if grid.GetNumberOfCells() else -1}
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])
