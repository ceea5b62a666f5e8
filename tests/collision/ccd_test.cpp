#include "pliant/collision/ccd.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "pliant/collision/point_triangle.hpp"
#include "pliant/collision/segment_segment.hpp"
#include "pliant/io/ccd_queries.hpp"

namespace pliant::collision {
namespace {

constexpr double TOLERANCE = CcdOptions{}.tolerance;

// The 8 positions of one query in the Sample-Queries order: VF (v, f0, f1, f2) at t0 then t1; EE
// (ea0, ea1, eb0, eb1) at t0 then t1.
using Positions = std::array<Vec3d, 8>;

CcdResult run_vf(const Positions& p, const CcdOptions& options = {}) {
    return vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], options);
}

CcdResult run_ee(const Positions& p, const CcdOptions& options = {}) {
    return edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], options);
}

Positions scaled(const Positions& p, double scale) {
    Positions out = p;
    for (Vec3d& x : out) {
        x = x * scale;
    }
    return out;
}

// Expects a hit whose toi is a lower bound of true_toi and within a few tolerances of it: a
// terminal box is at most `tolerance` wide in t, or its values span at most tolerance × (F's
// range over the step), which for these unit-speed motions is a few tolerances in t.
void expect_hit_at(const CcdResult& result, double true_toi) {
    EXPECT_TRUE(result.hit);
    EXPECT_FALSE(result.hit_iteration_limit);
    EXPECT_LE(result.toi, true_toi);
    EXPECT_GE(result.toi, true_toi - 4.0 * TOLERANCE);
}

void expect_no_hit(const CcdResult& result) {
    EXPECT_FALSE(result.hit);
    EXPECT_EQ(result.toi, 1.0);
    EXPECT_FALSE(result.hit_iteration_limit);
    EXPECT_GT(result.iterations, 0);
}

// Static triangle in the plane z = 0 with corners (0, 0), (1, 0), (0, 1).
constexpr Vec3d F0{0.0, 0.0, 0.0};
constexpr Vec3d F1{1.0, 0.0, 0.0};
constexpr Vec3d F2{0.0, 1.0, 0.0};

Positions vf_static_face(Vec3d v_t0, Vec3d v_t1) {
    return {v_t0, F0, F1, F2, v_t1, F0, F1, F2};
}

// Edge b static along y through the origin, edge a moving.
constexpr Vec3d EB0{0.0, -1.0, 0.0};
constexpr Vec3d EB1{0.0, 1.0, 0.0};

Positions ee_static_b(Vec3d ea0_t0, Vec3d ea1_t0, Vec3d ea0_t1, Vec3d ea1_t1) {
    return {ea0_t0, ea1_t0, EB0, EB1, ea0_t1, ea1_t1, EB0, EB1};
}

// ---------------------------------------------------------------------------------------------
// Vertex-face analytic cases.

TEST(CcdVertexFace, VertexFallingThroughInterior) {
    // z(t) = 0.7 - t crosses 0 at t = 0.7.
    const Positions p = vf_static_face({0.25, 0.3, 0.7}, {0.25, 0.3, -0.3});
    expect_hit_at(run_vf(p), 0.7);
}

TEST(CcdVertexFace, MovingFaceHitsStaticVertex) {
    // The face rises as z(t) = -0.2 + 0.5 t and reaches the vertex at z = 0.1 at t = 0.6.
    const Vec3d lift{0.0, 0.0, -0.2};
    const Vec3d lifted{0.0, 0.0, 0.3};
    const Vec3d v{0.2, 0.2, 0.1};
    const Positions p = {v, F0 + lift,   F1 + lift,   F2 + lift,
                         v, F0 + lifted, F1 + lifted, F2 + lifted};
    expect_hit_at(run_vf(p), 0.6);
}

TEST(CcdVertexFace, VertexPassingBesideTriangle) {
    expect_no_hit(run_vf(vf_static_face({0.6, 0.6, 1.0}, {0.6, 0.6, -1.0})));
    expect_no_hit(run_vf(vf_static_face({-0.01, 0.5, 1.0}, {-0.01, 0.5, -1.0})));
}

TEST(CcdVertexFace, CoplanarMotionTouchesEdge) {
    // In the face's plane, x(t) = 2 - 1.75 t reaches the edge x + y = 1 (y = 0.25) at t = 5 / 7.
    expect_hit_at(run_vf(vf_static_face({2.0, 0.25, 0.0}, {0.25, 0.25, 0.0})), 5.0 / 7.0);
    // Coplanar but staying outside.
    expect_no_hit(run_vf(vf_static_face({2.0, 0.25, 0.0}, {0.9, 0.25, 0.0})));
}

TEST(CcdVertexFace, ContactAtStartAndEnd) {
    const CcdResult at_start = run_vf(vf_static_face({0.25, 0.25, 0.0}, {0.25, 0.25, 1.0}));
    EXPECT_TRUE(at_start.hit);
    EXPECT_EQ(at_start.toi, 0.0);
    expect_hit_at(run_vf(vf_static_face({0.25, 0.25, 1.0}, {0.25, 0.25, 0.0})), 1.0);
    // Ending 1e-12 short of the face: no contact.
    expect_no_hit(run_vf(vf_static_face({0.25, 0.25, 1.0}, {0.25, 0.25, 1e-12})));
}

// Heights z0 > c for which the lerp z0 + 1 * (c - z0) rounds above c: a vertex descending from z0
// to exactly c touches a face at height c at t = 1, but evaluated naively it stops short of it.
std::pair<double, double> heights_stopping_short_in_floating_point() {
    for (int k = 1; k < 100000; ++k) {
        const double z0 = 1.0 + 0.37 * k;
        const double c = 0.1 * k;
        if (z0 + 1.0 * (c - z0) > c) {
            return {z0, c};
        }
    }
    ADD_FAILURE() << "no rounding case found";
    return {1.0, 0.0};
}

TEST(CcdVertexFace, ContactAtEndSurvivesRounding) {
    const auto [z0, c] = heights_stopping_short_in_floating_point();
    const Vec3d up{0.0, 0.0, c};
    const Positions p = {Vec3d{0.25, 0.25, z0}, F0 + up, F1 + up, F2 + up,
                         Vec3d{0.25, 0.25, c},  F0 + up, F1 + up, F2 + up};
    const CcdResult result = run_vf(p);
    EXPECT_TRUE(result.hit) << "z0 " << z0 << " c " << c;
    EXPECT_GE(result.toi, 1.0 - 2.0 * TOLERANCE);
}

TEST(CcdVertexFace, VertexMovingAlongEdgeLine) {
    // Along the line of edge f0-f1: enters the edge at x = 0, t = 2 / 3.
    expect_hit_at(run_vf(vf_static_face({-1.0, 0.0, 0.0}, {0.5, 0.0, 0.0})), 2.0 / 3.0);
    // On the edge's line but stopping before it.
    expect_no_hit(run_vf(vf_static_face({-2.0, 0.0, 0.0}, {-0.5, 0.0, 0.0})));
    // Sliding along the hypotenuse u + v = 1 the whole step.
    const CcdResult sliding = run_vf(vf_static_face({0.9, 0.1, 0.0}, {0.1, 0.9, 0.0}));
    EXPECT_TRUE(sliding.hit);
    EXPECT_EQ(sliding.toi, 0.0);
}

TEST(CcdVertexFace, DegenerateFace) {
    // Zero-area face (collinear corners on the x axis); the vertex crosses its segment at t = 0.4.
    const Vec3d a{0.0, 0.0, 0.0};
    const Vec3d b{1.0, 0.0, 0.0};
    const Vec3d c{2.0, 0.0, 0.0};
    expect_hit_at(run_vf({Vec3d{1.5, 0.4, 0.0}, a, b, c, Vec3d{1.5, -0.6, 0.0}, a, b, c}), 0.4);
    expect_no_hit(run_vf({Vec3d{2.5, 0.4, 0.0}, a, b, c, Vec3d{2.5, -0.6, 0.0}, a, b, c}));
    // A needle face (c 2^-30 off the line of a and b) and a vertex sliding along the needle's
    // line 2^-30 off its plane: near contact along the whole face for the whole step.
    const Vec3d needle{2.0, 0x1p-30, 0.0};
    const CcdResult sliding =
        run_vf({Vec3d{-1.0, 0.0, 0x1p-30}, a, b, needle, Vec3d{3.0, 0.0, 0x1p-30}, a, b, needle});
    expect_no_hit(sliding);
    EXPECT_LT(sliding.iterations, 10'000);
}

TEST(CcdVertexFace, StaticConfigurations) {
    const CcdResult touching = run_vf(vf_static_face({0.3, 0.3, 0.0}, {0.3, 0.3, 0.0}));
    EXPECT_TRUE(touching.hit);
    EXPECT_EQ(touching.toi, 0.0);
    expect_no_hit(run_vf(vf_static_face({0.3, 0.3, 0.5}, {0.3, 0.3, 0.5})));
}

TEST(CcdVertexFace, MinSeparationTurnsNearMissIntoHit) {
    // Sliding across the face 0.01 above it; enters the face's footprint at x = 0, t = 0.5.
    const Positions p = vf_static_face({-0.5, 0.25, 0.01}, {0.5, 0.25, 0.01});
    expect_no_hit(run_vf(p));
    const CcdResult near = run_vf(p, {.min_separation = 0.02});
    EXPECT_TRUE(near.hit);
    // Within 0.02 (L∞) of the face from x = -0.02, t = 0.48.
    EXPECT_LE(near.toi, 0.48);
    EXPECT_GE(near.toi, 0.48 - 2.0 * TOLERANCE);
    expect_no_hit(run_vf(p, {.min_separation = 0.005}));
    // A negative separation is treated as 0.
    expect_no_hit(run_vf(p, {.min_separation = -1.0}));
}

TEST(CcdVertexFace, ScaleInvariance) {
    for (const double scale : {1e-6, 1e6}) {
        SCOPED_TRACE(scale);
        expect_hit_at(run_vf(scaled(vf_static_face({0.25, 0.3, 0.7}, {0.25, 0.3, -0.3}), scale)),
                      0.7);
        expect_no_hit(run_vf(scaled(vf_static_face({0.6, 0.6, 1.0}, {0.6, 0.6, -1.0}), scale)));
    }
}

TEST(CcdVertexFace, NonFiniteInputIsAConservativeHit) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const CcdResult result = run_vf(vf_static_face({nan, 0.0, 1.0}, {0.6, 0.6, -1.0}));
    EXPECT_TRUE(result.hit);
    EXPECT_EQ(result.toi, 0.0);
}

TEST(CcdVertexFace, IterationLimitReportsConservativeHit) {
    // A miss that no whole-step test can exclude: the vertex passes over the face (at t = 0.3 it
    // is above (0.7, 0.1)) and crosses the plane at (0.5, -0.1), outside it.
    const Positions p = vf_static_face({1.0, 0.4, 1.0}, {0.0, -0.6, -1.0});
    expect_no_hit(run_vf(p));
    const CcdResult limited = run_vf(p, {.max_iterations = 1});
    EXPECT_TRUE(limited.hit);
    EXPECT_TRUE(limited.hit_iteration_limit);
    EXPECT_EQ(limited.iterations, 1);  // the root box
    EXPECT_EQ(limited.toi, 0.0);
    // Excluded by the root box alone: no hit even with one iteration.
    expect_no_hit(run_vf(vf_static_face({0.3, 0.3, 1.0}, {0.3, 0.3, 2.0}), {.max_iterations = 1}));
}

// ---------------------------------------------------------------------------------------------
// Edge-edge analytic cases.

TEST(CcdEdgeEdge, EdgesCrossingAtKnownTime) {
    // Edge a along x at height z(t) = 0.6 - t crosses edge b (along y) at t = 0.6.
    expect_hit_at(
        run_ee(ee_static_b({-1.0, 0.3, 0.6}, {1.0, 0.3, 0.6}, {-1.0, 0.3, -0.4}, {1.0, 0.3, -0.4})),
        0.6);
    // Both moving: a descends from 0.5, b rises from -0.5 at the same speed: meet at t = 0.5.
    const Positions both = {Vec3d{-1.0, 0.0, 0.5}, Vec3d{1.0, 0.0, 0.5},   Vec3d{0.2, -1.0, -0.5},
                            Vec3d{0.2, 1.0, -0.5}, Vec3d{-1.0, 0.0, -0.5}, Vec3d{1.0, 0.0, -0.5},
                            Vec3d{0.2, -1.0, 0.5}, Vec3d{0.2, 1.0, 0.5}};
    expect_hit_at(run_ee(both), 0.5);
}

TEST(CcdEdgeEdge, EdgesPassingBesideEachOther) {
    // Edge a descends past edge b but beyond b's end (y = 1).
    expect_no_hit(run_ee(
        ee_static_b({-1.0, 1.1, 0.6}, {1.0, 1.1, 0.6}, {-1.0, 1.1, -0.4}, {1.0, 1.1, -0.4})));
}

TEST(CcdEdgeEdge, ParallelEdgesSlidingPast) {
    // Parallel to b, 0.1 away in x, sliding along y the whole length of b and beyond.
    expect_no_hit(
        run_ee(ee_static_b({0.1, -3.0, 0.0}, {0.1, -2.0, 0.0}, {0.1, 2.0, 0.0}, {0.1, 3.0, 0.0})));
    // The same at distance 0: collinear overlap from the start.
    const CcdResult collinear =
        run_ee(ee_static_b({0.0, -3.0, 0.0}, {0.0, -2.0, 0.0}, {0.0, 2.0, 0.0}, {0.0, 3.0, 0.0}));
    EXPECT_TRUE(collinear.hit);
    // a's upper end y = -2 + 5 t reaches b's lower end y = -1 at t = 0.2.
    EXPECT_LE(collinear.toi, 0.2);
    EXPECT_GE(collinear.toi, 0.2 - 2.0 * TOLERANCE);
}

TEST(CcdEdgeEdge, CoplanarMotionTouching) {
    // In the plane z = 0, edge a along x (x ∈ [-1, 1]) moves in y from 2 to 0: its line reaches
    // b's end y = 1 at t = 0.5.
    expect_hit_at(
        run_ee(ee_static_b({-1.0, 2.0, 0.0}, {1.0, 2.0, 0.0}, {-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0})),
        0.5);
    // Rotating in the plane about its end, never reaching b.
    expect_no_hit(
        run_ee(ee_static_b({0.5, 0.0, 0.0}, {1.5, 0.0, 0.0}, {0.5, 0.0, 0.0}, {0.5, 1.0, 0.0})));
}

TEST(CcdEdgeEdge, ContactAtStartAndEnd) {
    const CcdResult at_start =
        run_ee(ee_static_b({-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {-1.0, 0.0, 1.0}, {1.0, 0.0, 1.0}));
    EXPECT_TRUE(at_start.hit);
    EXPECT_EQ(at_start.toi, 0.0);
    expect_hit_at(
        run_ee(ee_static_b({-1.0, 0.0, 1.0}, {1.0, 0.0, 1.0}, {-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0})),
        1.0);
    expect_no_hit(run_ee(
        ee_static_b({-1.0, 0.0, 1.0}, {1.0, 0.0, 1.0}, {-1.0, 0.0, 1e-12}, {1.0, 0.0, 1e-12})));
}

TEST(CcdEdgeEdge, ContactAtEndSurvivesRounding) {
    const auto [z0, c] = heights_stopping_short_in_floating_point();
    const Positions p = ee_static_b({-1.0, 0.0, z0}, {1.0, 0.0, z0}, {-1.0, 0.0, c}, {1.0, 0.0, c});
    const Positions lifted_b = {p[0], p[1], EB0 + Vec3d{0.0, 0.0, c}, EB1 + Vec3d{0.0, 0.0, c},
                                p[4], p[5], EB0 + Vec3d{0.0, 0.0, c}, EB1 + Vec3d{0.0, 0.0, c}};
    const CcdResult result = run_ee(lifted_b);
    EXPECT_TRUE(result.hit) << "z0 " << z0 << " c " << c;
    EXPECT_GE(result.toi, 1.0 - 2.0 * TOLERANCE);
}

TEST(CcdEdgeEdge, EndpointOnEdge) {
    // Edge a's endpoint descends onto b's interior at t = 0.5 (a vertical segment above b).
    expect_hit_at(
        run_ee(ee_static_b({0.0, 0.5, 0.5}, {0.0, 0.5, 1.5}, {0.0, 0.5, -0.5}, {0.0, 0.5, 0.5})),
        0.5);
    // Endpoints meeting: a's end descends onto b's endpoint (0, 1, 0) at t = 0.25.
    expect_hit_at(run_ee(ee_static_b({0.0, 1.0, 0.25}, {0.0, 2.0, 0.25}, {0.0, 1.0, -0.75},
                                     {0.0, 2.0, -0.75})),
                  0.25);
}

TEST(CcdEdgeEdge, ZeroLengthEdge) {
    // A point moving across edge b at t = 0.3.
    expect_hit_at(
        run_ee(ee_static_b({-0.3, 0.2, 0.0}, {-0.3, 0.2, 0.0}, {0.7, 0.2, 0.0}, {0.7, 0.2, 0.0})),
        0.3);
    expect_no_hit(
        run_ee(ee_static_b({-0.3, 0.2, 0.1}, {-0.3, 0.2, 0.1}, {0.7, 0.2, 0.1}, {0.7, 0.2, 0.1})));
    // Two points meeting.
    const Vec3d o{0.0, 0.0, 0.0};
    expect_hit_at(run_ee({Vec3d{-1.0, 0.0, 0.0}, Vec3d{-1.0, 0.0, 0.0}, o, o, Vec3d{1.0, 0.0, 0.0},
                          Vec3d{1.0, 0.0, 0.0}, o, o}),
                  0.5);
}

TEST(CcdEdgeEdge, StaticConfigurations) {
    const CcdResult crossing =
        run_ee(ee_static_b({-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}));
    EXPECT_TRUE(crossing.hit);
    EXPECT_EQ(crossing.toi, 0.0);
    expect_no_hit(
        run_ee(ee_static_b({-1.0, 0.0, 0.5}, {1.0, 0.0, 0.5}, {-1.0, 0.0, 0.5}, {1.0, 0.0, 0.5})));
}

TEST(CcdEdgeEdge, MinSeparationTurnsNearMissIntoHit) {
    // Edge a slides across b 0.01 above it; its line is over b from t = 0.5.
    const Positions p =
        ee_static_b({-1.0, -2.0, 0.01}, {1.0, -2.0, 0.01}, {-1.0, 0.0, 0.01}, {1.0, 0.0, 0.01});
    expect_no_hit(run_ee(p));
    const CcdResult near = run_ee(p, {.min_separation = 0.02});
    EXPECT_TRUE(near.hit);
    // y(t) = -2 + 2 t reaches -1.02 at t = 0.49.
    EXPECT_LE(near.toi, 0.49);
    EXPECT_GE(near.toi, 0.49 - 2.0 * TOLERANCE);
    expect_no_hit(run_ee(p, {.min_separation = 0.005}));
}

// Two edges of a folded cloth layer lying on each other (the cloth-funnel case): b is a within
// a few 1e-6 (coordinates about 0.5) and passes through it. Every (u, u) is then within ~1e-6 of
// contact for a long stretch of t, and a search that refines u and v before t needs ~1e6 boxes
// (the search before the separating directions of ccd.hpp hit its 1,000,000-box limit here).
// All coordinates are dyadic, so the positions below are exact.
constexpr Vec3d LAYER_A0{0.25, -0.0625, -0.5};
constexpr Vec3d LAYER_D{0x1p-8, 0x1p-9, -0x1p-9};  // a1 - a0
constexpr Vec3d LAYER_W{0x1p-20, 0.0, -0x1p-18};   // offset of b at t = 0, -W at t = 1

// b = a + (1 - 2t) W, with b1 tilted by `tilt`, plus a constant `offset`.
Positions layered_edges(Vec3d tilt, Vec3d offset) {
    const Vec3d a1 = LAYER_A0 + LAYER_D;
    return {LAYER_A0, a1, LAYER_A0 + LAYER_W + offset, a1 + LAYER_W + tilt + offset,
            LAYER_A0, a1, LAYER_A0 - LAYER_W + offset, a1 - LAYER_W + tilt + offset};
}

constexpr int FEW_BOXES = 10'000;

TEST(CcdEdgeEdge, NearlyCoincidentEdgesPassingThroughEachOther) {
    // Nearly parallel (b tilted by 2^-28): the endpoints a0 and b0 meet exactly at t = 0.5,
    // and before t = 0.5 - 1e-3 the edges are at least ~1e-9 apart, far above rounding.
    const CcdResult crossing = run_ee(layered_edges({0x1p-28, 0.0, 0.0}, {}));
    EXPECT_TRUE(crossing.hit);
    EXPECT_FALSE(crossing.hit_iteration_limit);
    EXPECT_LE(crossing.toi, 0.5);
    EXPECT_GE(crossing.toi, 0.5 - 1e-3);
    EXPECT_LT(crossing.iterations, FEW_BOXES);
    // Exactly parallel and overlapping along their whole length at t = 0.5.
    const CcdResult parallel = run_ee(layered_edges({}, {}));
    EXPECT_TRUE(parallel.hit);
    EXPECT_LE(parallel.toi, 0.5);
    EXPECT_GE(parallel.toi, 0.5 - 1e-3);
    EXPECT_LT(parallel.iterations, FEW_BOXES);
}

TEST(CcdEdgeEdge, NearlyCoincidentEdgesMissingByNanometres) {
    // The parallel layers shifted by 2^-30 (~1e-9) along y, out of the plane of W and D: they
    // pass each other without touching (the offset is independent of W and D).
    const CcdResult miss = run_ee(layered_edges({}, {0.0, 0x1p-30, 0.0}));
    expect_no_hit(miss);
    EXPECT_LT(miss.iterations, FEW_BOXES);
    // With a minimum separation of 1e-8 they are in contact, from before t = 0.5.
    const CcdResult near = run_ee(layered_edges({}, {0.0, 0x1p-30, 0.0}), {.min_separation = 1e-8});
    EXPECT_TRUE(near.hit);
    EXPECT_LE(near.toi, 0.5);
    EXPECT_LT(near.iterations, FEW_BOXES);
}

TEST(CcdEdgeEdge, ScaleInvariance) {
    for (const double scale : {1e-6, 1e6}) {
        SCOPED_TRACE(scale);
        expect_hit_at(run_ee(scaled(ee_static_b({-1.0, 0.3, 0.6}, {1.0, 0.3, 0.6},
                                                {-1.0, 0.3, -0.4}, {1.0, 0.3, -0.4}),
                                    scale)),
                      0.6);
        expect_no_hit(run_ee(scaled(
            ee_static_b({-1.0, 1.1, 0.6}, {1.0, 1.1, 0.6}, {-1.0, 1.1, -0.4}, {1.0, 1.1, -0.4}),
            scale)));
    }
}

// ---------------------------------------------------------------------------------------------
// Random motions against dense sampling of the proximity kernels.

constexpr int NUM_SAMPLES = 2000;

Vec3d lerp(Vec3d a, Vec3d b, double t) {
    return a + (b - a) * t;
}

// Distance of the two features at time t.
double distance_at(bool is_vertex_face, const Positions& p, double t) {
    std::array<Vec3d, 4> x;
    for (int k = 0; k < 4; ++k) {
        x[k] = lerp(p[k], p[k + 4], t);
    }
    return is_vertex_face ? point_triangle_proximity(x[0], x[1], x[2], x[3]).distance
                          : segment_segment_proximity(x[0], x[1], x[2], x[3]).distance;
}

// Lipschitz constant of the distance in t: the largest relative speed of two feature points.
double distance_lipschitz(bool is_vertex_face, const Positions& p) {
    double speed[4];
    for (int k = 0; k < 4; ++k) {
        speed[k] = norm(p[k + 4] - p[k]);
    }
    return is_vertex_face ? speed[0] + std::max({speed[1], speed[2], speed[3]})
                          : std::max(speed[0], speed[1]) + std::max(speed[2], speed[3]);
}

struct SampledMotion {
    double first_contact;  // first sample time with distance <= 1e-9; 2 if none
    double min_distance;
};

SampledMotion sample_motion(bool is_vertex_face, const Positions& p) {
    SampledMotion sampled{2.0, std::numeric_limits<double>::infinity()};
    for (int i = 0; i <= NUM_SAMPLES; ++i) {
        const double t = double(i) / NUM_SAMPLES;
        const double distance = distance_at(is_vertex_face, p, t);
        sampled.min_distance = std::min(sampled.min_distance, distance);
        if (distance <= 1e-9 && sampled.first_contact > 1.0) {
            sampled.first_contact = t;
        }
    }
    return sampled;
}

// Features that touch at t* = k / 16: positions at t* on a grid of 1/8, the contact point a
// barycentric (or edge-parameter) combination with weights in 1/8, displacements on a grid of 1/8.
// Every coordinate is a short dyadic, so the inputs touch exactly at t*.
Positions exact_contact(bool is_vertex_face, std::mt19937_64& rng, double& t_star) {
    std::uniform_int_distribution<int> coordinate(-16, 16);
    std::uniform_int_distribution<int> step(0, 16);
    std::uniform_int_distribution<int> weight(0, 8);
    const auto random_point = [&] {
        return Vec3d{coordinate(rng) / 8.0, coordinate(rng) / 8.0, coordinate(rng) / 8.0};
    };
    t_star = step(rng) / 16.0;
    std::array<Vec3d, 4> at_contact;
    for (Vec3d& x : at_contact) {
        x = random_point();
    }
    if (is_vertex_face) {
        const int w1 = weight(rng);
        const int w2 = std::uniform_int_distribution<int>(0, 8 - w1)(rng);
        at_contact[0] = at_contact[1] + (at_contact[2] - at_contact[1]) * (w1 / 8.0) +
                        (at_contact[3] - at_contact[1]) * (w2 / 8.0);
    } else {
        const double s = weight(rng) / 8.0;
        const double r = weight(rng) / 8.0;
        // Move edge a so that its point at s coincides with edge b's point at r.
        const Vec3d offset =
            lerp(at_contact[2], at_contact[3], r) - lerp(at_contact[0], at_contact[1], s);
        at_contact[0] = at_contact[0] + offset;
        at_contact[1] = at_contact[1] + offset;
    }
    Positions p;
    for (int k = 0; k < 4; ++k) {
        const Vec3d displacement = random_point();
        p[k] = at_contact[k] - displacement * t_star;
        p[k + 4] = at_contact[k] + displacement * (1.0 - t_star);
    }
    return p;
}

// Random small motions around the unit cube, most of them near misses or crossings.
Positions random_motion(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> position(-0.5, 0.5);
    std::uniform_real_distribution<double> motion(-0.6, 0.6);
    Positions p;
    for (int k = 0; k < 4; ++k) {
        p[k] = Vec3d{position(rng), position(rng), position(rng)};
        p[k + 4] = p[k] + Vec3d{motion(rng), motion(rng), motion(rng)};
    }
    return p;
}

class CcdRandom : public ::testing::TestWithParam<bool> {};

TEST_P(CcdRandom, ExactContactsAreNeverMissed) {
    const bool is_vertex_face = GetParam();
    std::mt19937_64 rng(is_vertex_face ? 11 : 12);
    int num_sampled_contacts = 0;
    for (int trial = 0; trial < 500; ++trial) {
        double t_star = 0.0;
        const Positions p = exact_contact(is_vertex_face, rng, t_star);
        const CcdResult result = is_vertex_face ? run_vf(p) : run_ee(p);
        const SampledMotion sampled = sample_motion(is_vertex_face, p);
        SCOPED_TRACE(::testing::Message() << "trial " << trial << " t* " << t_star);
        ASSERT_TRUE(result.hit);
        EXPECT_LE(result.toi, t_star);
        if (sampled.first_contact <= 1.0) {
            ++num_sampled_contacts;
            EXPECT_LE(result.toi, sampled.first_contact);
        }
    }
    // t* is on the sample grid, so the sampler sees (nearly) every contact.
    EXPECT_GT(num_sampled_contacts, 450);
}

TEST_P(CcdRandom, AgreesWithDenseSampling) {
    const bool is_vertex_face = GetParam();
    std::mt19937_64 rng(is_vertex_face ? 21 : 22);
    // Sampled distances <= 1e-9 (Euclidean, rounded) imply an L∞ distance below 2e-9.
    const CcdOptions options{.min_separation = 2e-9};
    int num_hits = 0;
    int num_clear_misses = 0;
    int num_sampled_contacts = 0;
    for (int trial = 0; trial < 1000; ++trial) {
        // Every other trial is a contact built in doubles (touching up to rounding).
        Positions p;
        if (trial % 2 == 0) {
            p = random_motion(rng);
        } else {
            std::uniform_real_distribution<double> unit(0.0, 1.0);
            p = random_motion(rng);
            const double t_star = std::floor(unit(rng) * NUM_SAMPLES) / NUM_SAMPLES;
            std::array<Vec3d, 4> x;
            for (int k = 0; k < 4; ++k) {
                x[k] = lerp(p[k], p[k + 4], t_star);
            }
            // Shift the first feature so that it touches the second at t*.
            if (is_vertex_face) {
                const auto prox = point_triangle_proximity(x[0], x[1], x[2], x[3]);
                const Vec3d offset = (x[1] * prox.barycentric.x + x[2] * prox.barycentric.y +
                                      x[3] * prox.barycentric.z) -
                                     x[0];
                p[0] = p[0] + offset;
                p[4] = p[4] + offset;
            } else {
                const auto prox = segment_segment_proximity(x[0], x[1], x[2], x[3]);
                const Vec3d offset = lerp(x[2], x[3], prox.t) - lerp(x[0], x[1], prox.s);
                for (const int k : {0, 1, 4, 5}) {
                    p[k] = p[k] + offset;
                }
            }
        }
        const CcdResult result = is_vertex_face ? run_vf(p, options) : run_ee(p, options);
        const SampledMotion sampled = sample_motion(is_vertex_face, p);
        SCOPED_TRACE(::testing::Message() << "trial " << trial);
        num_hits += result.hit ? 1 : 0;
        if (sampled.first_contact <= 1.0) {
            ++num_sampled_contacts;
            ASSERT_TRUE(result.hit) << "missed a sampled contact at t = " << sampled.first_contact;
            EXPECT_LE(result.toi, sampled.first_contact);
        }
        // Between samples the distance drops by at most lipschitz / (2 NUM_SAMPLES): a sampled
        // minimum above twice that (plus δ) proves there is no contact.
        const double margin = distance_lipschitz(is_vertex_face, p) / NUM_SAMPLES + 1e-6;
        if (sampled.min_distance > margin) {
            ++num_clear_misses;
            EXPECT_FALSE(result.hit)
                << "false positive at sampled distance " << sampled.min_distance;
        }
    }
    EXPECT_GT(num_sampled_contacts, 400);
    EXPECT_GT(num_clear_misses, 100);
    EXPECT_GT(num_hits, 400);
}

INSTANTIATE_TEST_SUITE_P(Kinds, CcdRandom, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& param_info) {
                             return param_info.param ? "VertexFace" : "EdgeEdge";
                         });

// ---------------------------------------------------------------------------------------------
// The Sample-Queries data set (Wang et al. 2021): 0 false negatives required.

TEST(CcdSampleQueries, NoFalseNegatives) {
    const std::filesystem::path root =
        std::filesystem::path(PLIANT_SHARED_DATA_DIR) / "ccd-queries";
    if (!std::filesystem::is_directory(root)) {
        GTEST_SKIP() << root << " not found";
    }
    // Every file of unit-tests and erleben-*, read with the io module's reader.
    std::vector<std::filesystem::path> files;
    for (const std::filesystem::path& file : io::find_ccd_query_files(root)) {
        const std::string relative = std::filesystem::relative(file, root).string();
        if (relative.starts_with("unit-tests") || relative.starts_with("erleben-")) {
            files.push_back(file);
        }
    }
    ASSERT_FALSE(files.empty());
    int total_queries = 0;
    int total_false_negatives = 0;
    int total_false_positives = 0;
    double total_ms = 0.0;
    for (const std::filesystem::path& file : files) {
        const std::string relative = std::filesystem::relative(file, root).string();
        const io::CcdQuerySet set = io::read_ccd_queries(file);
        const bool is_edge_edge = set.kind == io::CcdQueryKind::edge_edge;
        const std::vector<io::CcdQuery>& queries = set.queries;
        int positives = 0;
        int false_negatives = 0;
        int false_positives = 0;
        const auto start = std::chrono::steady_clock::now();
        for (const io::CcdQuery& query : queries) {
            ASSERT_GE(query.truth, 0) << relative << ": the sample sets carry a truth column";
            const bool colliding = query.truth == 1;
            const CcdResult result = is_edge_edge ? run_ee(query.points) : run_vf(query.points);
            positives += colliding ? 1 : 0;
            false_negatives += (colliding && !result.hit) ? 1 : 0;
            false_positives += (!colliding && result.hit) ? 1 : 0;
        }
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        EXPECT_EQ(false_negatives, 0) << relative;
        std::cout << relative << ": " << queries.size() << " queries, " << positives
                  << " positives, " << false_negatives << " false negatives, " << false_positives
                  << " false positives, " << (queries.empty() ? 0.0 : ms / double(queries.size()))
                  << " ms/query\n";
        total_queries += int(queries.size());
        total_false_negatives += false_negatives;
        total_false_positives += false_positives;
        total_ms += ms;
    }
    RecordProperty("queries", total_queries);
    RecordProperty("false_negatives", total_false_negatives);
    RecordProperty("false_positives", total_false_positives);
    std::cout << "total: " << total_queries << " queries, " << total_false_negatives
              << " false negatives, " << total_false_positives << " false positives, "
              << total_ms / std::max(total_queries, 1) << " ms/query\n";
}

}  // namespace
}  // namespace pliant::collision
