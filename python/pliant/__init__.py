"""pliant: cloth with fast self-collision, and deformable volumes, from Python.

Thin bindings over the C++ library (python/src/*.cpp): every function and class here calls the
library's own code, the same that the `pliant` command line runs.

Arrays are numpy arrays and, where the layout allows, views of the library's memory (no copy)
that keep their owner alive:

- points: (N, 3) float64 (meshes, cloth) or float32 (tet meshes, soft bodies);
- triangles (T, 3), tets (T, 4), edges and feature pairs (P, 2): int32;
- volumes: Volume.array, shape (nz, ny, nx) or (nz, ny, nx, 4) for RGBA, array[k, j, i] being
  voxel (i, j, k);
- images: (H, W, 3) uint8 (rendered) or float32 in [0, 1] (datasets), row 0 at the top.

Errors: pliant.Error and its subclasses InvalidInput (a ValueError), IoError (an OSError),
Unsupported (a NotImplementedError) and InternalError (a RuntimeError), with the library's
message. Long calls (cloth steps, broad phases, rendering, training) release the GIL.
"""

import atexit as _atexit

from ._pliant import *  # noqa: F401,F403
from ._pliant import __version__, set_log_handler as _set_log_handler

# A Python log handler must not outlive the interpreter (the library holds it in a static).
_atexit.register(_set_log_handler, None)
