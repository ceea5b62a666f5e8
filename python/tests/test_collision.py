"""Self-collision from Python: the broad phase against the cloth-funnel oracle and the CLI, and
against a brute force on a small random mesh; CCD on known hits and misses; the narrow phase;
exact intersecting pairs."""

import json
import os
import subprocess

import numpy as np
import pytest

import pliant


def test_funnel_swept_step_matches_the_oracle_and_the_cli(funnel_frames):
    t0, t1 = funnel_frames
    m0, m1 = pliant.read_mesh(t0), pliant.read_mesh(t1)
    assert (m0.num_vertices, m0.num_triangles) == (9450, 18484)
    broad_phase = pliant.BroadPhase(m0.triangles, m0.num_vertices)
    pairs = broad_phase.update(m0.positions, m1.positions, inflation=0.0)
    assert pairs.num_vertex_face == 7319
    assert pairs.num_edge_edge == 33770
    assert pairs.vertex_face.shape == (7319, 2) and pairs.vertex_face.dtype == np.int32
    assert pairs.edge_edge.shape == (33770, 2)

    report = pliant.collide(m0, m1.positions)
    assert (report["vf_pairs"], report["ee_pairs"]) == (7319, 33770)
    assert report["swept"] is True and report["inflation"] == 0.0

    cli = os.environ.get("PLIANT_CLI")
    if cli and os.path.exists(cli):
        out = subprocess.run(
            [cli, "collide", str(t0), "--to", str(t1), "--json"],
            check=True, capture_output=True, text=True,
        ).stdout
        from_cli = json.loads(out)
        for key in ("vertices", "triangles", "edges", "triangle_pairs", "vf_pairs", "ee_pairs"):
            assert report[key] == from_cli[key], key


def test_funnel_narrow_phase_misses_no_ground_truth_contact(funnel_frames):
    t0, t1 = funnel_frames
    m0, m1 = pliant.read_mesh(t0), pliant.read_mesh(t1)
    broad_phase = pliant.BroadPhase(m0.triangles, m0.num_vertices)
    pairs = broad_phase.update(m0.positions, m1.positions)
    result = pliant.continuous_narrow_phase(
        m0.positions, m1.positions, m0.triangles, broad_phase.edges, pairs
    )
    # The Mathematica ground truth marks 27 VF and 107 EE of these pairs as colliding.
    assert result.vf_hits >= 27 and result.ee_hits >= 107
    assert result.vf_hits <= pairs.num_vertex_face
    assert 0.0 <= result.earliest_toi < 1.0
    assert result.hits.num_vertex_face == result.vf_hits


def random_swept_sheet(seed):
    rng = np.random.default_rng(seed)
    mesh = pliant.grid_sheet(6, 5, 1.0, 1.0)
    p0 = mesh.positions + rng.normal(scale=0.05, size=mesh.positions.shape)
    p1 = p0 + rng.normal(scale=0.1, size=p0.shape)
    return mesh.triangles.copy(), p0, p1


def boxes_overlap(lo_a, hi_a, lo_b, hi_b):
    return np.all(lo_a <= hi_b, axis=-1) & np.all(lo_b <= hi_a, axis=-1)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_broad_phase_equals_brute_force_on_a_random_mesh(seed):
    triangles, p0, p1 = random_swept_sheet(seed)
    h = 0.01
    broad_phase = pliant.BroadPhase(triangles, len(p0))
    pairs = broad_phase.update(p0, p1, inflation=h)

    lo = np.minimum(p0, p1) - h
    hi = np.maximum(p0, p1) + h
    edges = broad_phase.edges
    unique_edges = {tuple(sorted((int(t[a]), int(t[b])))) for t in triangles
                    for a, b in ((0, 1), (1, 2), (2, 0))}
    assert {tuple(e) for e in edges.tolist()} == unique_edges

    # Vertex-face: the vertex not in the face, the vertex box against the face's box.
    face_lo = lo[triangles].min(axis=1)
    face_hi = hi[triangles].max(axis=1)
    expected_vf = set()
    for v in range(len(p0)):
        hit = boxes_overlap(lo[v], hi[v], face_lo, face_hi)
        for f in np.nonzero(hit)[0]:
            if v not in triangles[f]:
                expected_vf.add((v, int(f)))
    # Edge-edge: edges sharing no vertex, edge boxes overlapping, each unordered pair once.
    edge_lo = lo[edges].min(axis=1)
    edge_hi = hi[edges].max(axis=1)
    expected_ee = set()
    for a in range(len(edges)):
        hit = boxes_overlap(edge_lo[a], edge_hi[a], edge_lo[a + 1:], edge_hi[a + 1:])
        for b in np.nonzero(hit)[0] + a + 1:
            if not set(edges[a].tolist()) & set(edges[b].tolist()):
                expected_ee.add((a, int(b)))

    got_vf = [tuple(p) for p in pairs.vertex_face.tolist()]
    got_ee = [tuple(p) for p in pairs.edge_edge.tolist()]
    assert len(got_vf) == len(set(got_vf)) and len(got_ee) == len(set(got_ee))
    assert set(got_vf) == expected_vf
    assert set(got_ee) == expected_ee
    assert len(expected_vf) > 0 and len(expected_ee) > 0


def test_broad_phase_results_do_not_depend_on_the_thread_count():
    triangles, p0, p1 = random_swept_sheet(7)
    before = pliant.num_threads()
    try:
        results = []
        for n in (1, 2):
            pliant.set_num_threads(n)
            pairs = pliant.BroadPhase(triangles, len(p0)).update(p0, p1, inflation=0.02)
            results.append((pairs.vertex_face.copy(), pairs.edge_edge.copy()))
    finally:
        pliant.set_num_threads(before)
    assert np.array_equal(results[0][0], results[1][0])
    assert np.array_equal(results[0][1], results[1][1])


def test_vertex_face_ccd_finds_a_vertex_falling_through_a_triangle():
    f = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    hit = pliant.vertex_face_ccd((0.25, 0.25, 1), *f, (0.25, 0.25, -1), *f)
    assert hit.hit
    assert 0.5 - 1e-5 <= hit.toi <= 0.5
    miss = pliant.vertex_face_ccd((2, 2, 1), *f, (2, 2, -1), *f)
    assert not miss.hit and miss.toi == 1.0


def test_edge_edge_ccd_finds_crossing_edges():
    eb = [(0.5, -0.5, 0), (0.5, 0.5, 0)]
    hit = pliant.edge_edge_ccd((0, 0, 1), (1, 0, 1), *eb, (0, 0, -1), (1, 0, -1), *eb)
    assert hit.hit and 0.5 - 1e-5 <= hit.toi <= 0.5
    miss = pliant.edge_edge_ccd((0, 2, 1), (1, 2, 1), *eb, (0, 2, -1), (1, 2, -1), *eb)
    assert not miss.hit
    # A minimum separation turns a near miss into a contact.
    near = pliant.edge_edge_ccd((0, 0.6, 1), (1, 0.6, 1), *eb, (0, 0.6, -1), (1, 0.6, -1), *eb,
                                min_separation=0.2)
    assert near.hit


def test_intersecting_pairs_are_counted_exactly():
    flat = pliant.grid_sheet(4, 4)
    assert pliant.count_intersecting_pairs(flat.positions, flat.triangles) == 0
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                          [0.2, 0.2, -1], [0.2, 0.2, 1], [1.5, 1.5, 0]], dtype=np.float64)
    triangles = np.array([[0, 1, 2], [3, 4, 5]])
    assert pliant.count_intersecting_pairs(positions, triangles) == 1
    assert pliant.find_intersecting_pairs(positions, triangles).tolist() == [[0, 1]]
