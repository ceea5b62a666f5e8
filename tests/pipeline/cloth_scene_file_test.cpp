#include "pliant/pipeline/cloth_scene_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <variant>

#include "pliant/core/error.hpp"

namespace pliant::pipeline {
namespace {

cloth::ClothScene parse(const std::string& text) {
    return parse_cloth_scene(text, "scene.json", "/scenes");
}

// Expects IoError whose message names the file and contains every one of `parts`.
void expect_error(const std::string& text, std::initializer_list<std::string> parts) {
    try {
        parse(text);
        ADD_FAILURE() << "no error for " << text;
    } catch (const IoError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("scene.json"), std::string::npos) << message;
        for (const std::string& part : parts) {
            EXPECT_NE(message.find(part), std::string::npos) << message << " lacks " << part;
        }
    }
}

TEST(ClothScene, ReadsEveryKey) {
    const cloth::ClothScene scene = parse(R"({
        "cloth": {"grid": {"size": [1.5, 0.5], "quads": [30, 10]},
                  "rotate_degrees": [90, 0, 0], "translate": [0, 0, 1]},
        "pins": {"vertices": [0, 5], "regions": [{"min": [-1, -1, 0], "max": [1, 1, 2]}]},
        "material": {"areal_density": 0.2, "stretch_compliance": 0, "bend_compliance": 3,
                     "damping": 1, "thickness": 0.002, "static_friction": 0.5,
                     "kinetic_friction": 0.4, "strain_limit": 0.05, "bending": "isometric",
                     "stretch_solver": "edges"},
        "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.5}},
                      {"plane": {"point": [0, 0, -1], "normal": [0, 0, 1]}},
                      {"box": {"min": [-1, -1, -1], "max": [1, 1, 0]}}],
        "gravity": [0, 0, -1], "fps": 30, "frames": 10, "substeps": 5,
        "self_collision": false, "untangle": false,
        "output": {"format": "ply"}
    })");
    ASSERT_TRUE(scene.grid.has_value());
    EXPECT_EQ(scene.grid->quads[0], 30);
    EXPECT_DOUBLE_EQ(scene.grid->size[1], 0.5);
    EXPECT_DOUBLE_EQ(scene.rotate_degrees.x, 90.0);
    ASSERT_EQ(scene.pins.size(), 1u);
    EXPECT_EQ(scene.pins[0].vertices.size(), 2u);
    EXPECT_EQ(scene.pins[0].regions.size(), 1u);
    EXPECT_TRUE(scene.pins[0].motion.is_static());
    EXPECT_DOUBLE_EQ(scene.material.thickness, 0.002);
    EXPECT_DOUBLE_EQ(scene.material.kinetic_friction, 0.4);
    EXPECT_DOUBLE_EQ(scene.material.strain_limit, 0.05);
    EXPECT_EQ(scene.material.bending, cloth::BendingModel::isometric);
    EXPECT_EQ(scene.material.stretch_solver, cloth::StretchSolver::edges);  // not the default
    ASSERT_EQ(scene.obstacles.size(), 3u);
    EXPECT_DOUBLE_EQ(std::get<cloth::SphereObstacle>(scene.obstacles[0].shape).radius, 0.5);
    EXPECT_TRUE(std::holds_alternative<cloth::PlaneObstacle>(scene.obstacles[1].shape));
    EXPECT_TRUE(std::holds_alternative<cloth::BoxObstacle>(scene.obstacles[2].shape));
    EXPECT_DOUBLE_EQ(scene.gravity.z, -1.0);
    EXPECT_EQ(scene.frames, 10);
    EXPECT_EQ(scene.substeps, 5);
    EXPECT_DOUBLE_EQ(scene.frames_per_second, 30.0);
    EXPECT_EQ(scene.frame_format, "ply");
    EXPECT_FALSE(scene.self_collision);
    EXPECT_FALSE(scene.untangle);
}

TEST(ClothScene, ReadsTheSolver) {
    EXPECT_FALSE(parse(R"({"cloth": {"grid": {}}})").vbd);
    EXPECT_FALSE(parse(R"({"cloth": {"grid": {}}, "solver": "xpbd"})").vbd);
    const cloth::ClothScene plain = parse(R"({"cloth": {"grid": {}}, "solver": "vbd"})");
    ASSERT_TRUE(plain.vbd);
    EXPECT_EQ(plain.vbd->iterations, cloth::VBDOptions{}.iterations);
    const cloth::ClothScene tuned = parse(R"({"cloth": {"grid": {}},
        "solver": {"type": "vbd", "iterations": 4, "chebyshev_rho": 0.5}})");
    ASSERT_TRUE(tuned.vbd);
    EXPECT_EQ(tuned.vbd->iterations, 4);
    EXPECT_EQ(tuned.vbd->chebyshev_rho, 0.5);
    EXPECT_FALSE(parse(R"({"cloth": {"grid": {}}, "solver": {"type": "xpbd"}})").vbd);
}

TEST(ClothScene, ReadsTheContact) {
    const cloth::ClothScene plain = parse(R"({"cloth": {"grid": {}}, "solver": "vbd"})");
    EXPECT_FALSE(plain.vbd->ogc);
    const cloth::ClothScene proximity =
        parse(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": "proximity"})");
    EXPECT_FALSE(proximity.vbd->ogc);
    const cloth::ClothScene ogc =
        parse(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": "ogc"})");
    ASSERT_TRUE(ogc.vbd && ogc.vbd->ogc);
    EXPECT_EQ(ogc.vbd->ogc->bound_share, cloth::OgcOptions{}.bound_share);
    const cloth::ClothScene tuned = parse(R"({"cloth": {"grid": {}}, "solver": "vbd",
        "contact": {"type": "ogc", "radius": 0.004, "query_factor": 3, "bound_share": 0.2,
                    "redetect_share": 0.05, "stiffness": 1000, "audit": false}})");
    ASSERT_TRUE(tuned.vbd && tuned.vbd->ogc);
    EXPECT_EQ(tuned.vbd->ogc->radius, 0.004);
    EXPECT_EQ(tuned.vbd->ogc->query_factor, 3.0);
    EXPECT_EQ(tuned.vbd->ogc->bound_share, 0.2);
    EXPECT_EQ(tuned.vbd->ogc->redetect_share, 0.05);
    EXPECT_EQ(tuned.vbd->ogc->stiffness, 1000.0);
    EXPECT_FALSE(tuned.vbd->ogc->audit);
    EXPECT_TRUE(ogc.vbd->ogc->audit);
    EXPECT_FALSE(ogc.xpbd_ogc);
    // With the XPBD solver (the default) the options go to xpbd_ogc.
    const cloth::ClothScene xpbd = parse(R"({"cloth": {"grid": {}}, "contact": "ogc"})");
    EXPECT_FALSE(xpbd.vbd);
    ASSERT_TRUE(xpbd.xpbd_ogc);
    EXPECT_EQ(xpbd.xpbd_ogc->bound_share, cloth::OgcOptions{}.bound_share);
    const cloth::ClothScene xpbd_tuned = parse(R"({"cloth": {"grid": {}}, "solver": "xpbd",
        "contact": {"type": "ogc", "query_factor": 4, "redetect_share": 0.1, "audit": false}})");
    ASSERT_TRUE(xpbd_tuned.xpbd_ogc);
    EXPECT_EQ(xpbd_tuned.xpbd_ogc->query_factor, 4.0);
    EXPECT_EQ(xpbd_tuned.xpbd_ogc->redetect_share, 0.1);
    EXPECT_FALSE(xpbd_tuned.xpbd_ogc->audit);
    EXPECT_FALSE(parse(R"({"cloth": {"grid": {}}, "contact": "proximity"})").xpbd_ogc);
}

TEST(ClothScene, RejectsBadContact) {
    expect_error(R"({"cloth": {"grid": {}}, "contact": "ipc"})",
                 {"contact", "\"ogc\", \"proximity\"", "\"ipc\""});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "xpbd", "contact": {"bound_share": 0}})",
                 {"contact.bound_share", "0"});
    expect_error(R"({"cloth": {"grid": {}}, "contact": {"type": "ogc", "audit": 1}})",
                 {"contact.audit", "true or false"});
    expect_error(R"({"cloth": {"grid": {}}, "contact": {"type": "ogc", "stiffness": -1}})",
                 {"contact.stiffness", "-1"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": "ipc"})",
                 {"contact", "\"ogc\", \"proximity\"", "\"ipc\""});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": 1})",
                 {"contact", "\"ogc\"", "an integer"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"bound_share": 0.5}})",
                 {"contact.bound_share", "0.5"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"radius": -1}})",
                 {"contact.radius", "-1"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"query_factor": 0.5}})",
                 {"contact.query_factor", "0.5"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"redetect_share": 2}})",
                 {"contact.redetect_share", "2"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"stiffness": "hard"}})",
                 {"contact.stiffness", "a number", "string"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"audit": 1}})",
                 {"contact.audit", "true or false"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "vbd", "contact": {"radiuss": 1}})",
                 {"contact.radiuss", "unknown key"});
}

TEST(ClothScene, DefaultsAndRelativeMeshPath) {
    const cloth::ClothScene scene = parse(R"({"cloth": {"mesh": "shirt.obj"}})");
    EXPECT_FALSE(scene.grid.has_value());
    EXPECT_EQ(scene.mesh, std::filesystem::path("/scenes/shirt.obj"));
    EXPECT_EQ(scene.frames, 72);
    EXPECT_EQ(scene.substeps, 40);
    EXPECT_DOUBLE_EQ(scene.gravity.z, -9.81);
    EXPECT_EQ(scene.frame_format, "obj");
    EXPECT_TRUE(scene.self_collision);
    EXPECT_TRUE(scene.untangle);
    EXPECT_DOUBLE_EQ(scene.material.thickness, cloth::ClothMaterial{}.thickness);
    EXPECT_TRUE(std::isinf(scene.material.strain_limit));
    EXPECT_EQ(scene.material.bending, cloth::BendingModel::dihedral);
    EXPECT_EQ(scene.material.stretch_solver, cloth::StretchSolver::chains);
    EXPECT_EQ(
        parse(R"({"cloth": {"grid": {}}, "material": {"bending": "isometric"}})").material.bending,
        cloth::BendingModel::isometric);
}

TEST(ClothScene, NullStrainLimitIsAcceptedAsNoLimit) {
    const cloth::ClothScene scene =
        parse(R"({"cloth": {"grid": {}}, "material": {"strain_limit": null}})");
    EXPECT_TRUE(std::isinf(scene.material.strain_limit));
}

TEST(ClothScene, BrokenInputNamesTheKey) {
    expect_error("{", {"not valid JSON"});
    expect_error("[]", {"expected an object"});
    expect_error("{}", {"cloth", "required"});
    expect_error(R"({"cloth": {"grid": {}}, "colth": 1})", {"colth", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"strech_compliance": 1}})",
                 {"material.strech_compliance", "unknown key", "stretch_compliance"});
    expect_error(R"({"cloth": {"grid": {}, "mesh": "a.obj"}})", {"grid", "mesh", "both"});
    expect_error(R"({"cloth": {}})", {"neither"});
    expect_error(R"({"cloth": {"grid": {"quads": [0, 3]}}})", {"cloth.grid.quads", "[0,3]"});
    expect_error(R"({"cloth": {"grid": {"size": [1, -1]}}})", {"cloth.grid.size"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"thickness": "5mm"}})",
                 {"material.thickness", "a number", "string"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"damping": -1}})",
                 {"material.damping", "[0,"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"strain_limit": -0.1}})",
                 {"material.strain_limit", "[0,", "-0.1"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"strain_limit": "5%"}})",
                 {"material.strain_limit", "a number", "string"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"bending": "hinge"}})",
                 {"material.bending", "\"dihedral\", \"isometric\"", "\"hinge\""});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"bending": 1}})",
                 {"material.bending", "\"dihedral\"", "an integer"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"stretch_solver": "chain"}})",
                 {"material.stretch_solver", "\"chains\", \"edges\"", "\"chain\""});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"stretch_solver": null}})",
                 {"material.stretch_solver", "\"edges\""});
    expect_error(R"({"cloth": {"grid": {}}, "solver": "pbd"})",
                 {"solver", "\"vbd\", \"xpbd\"", "\"pbd\""});
    expect_error(R"({"cloth": {"grid": {}}, "solver": 3})", {"solver", "\"xpbd\""});
    expect_error(R"({"cloth": {"grid": {}}, "solver": {"type": "vbd", "iterations": 0}})",
                 {"solver.iterations", "0"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": {"chebyshev_rho": 1.5}})",
                 {"solver.chebyshev_rho", "1.5"});
    expect_error(R"({"cloth": {"grid": {}}, "solver": {"iteration": 3}})",
                 {"solver.iteration", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "gravity": [0, 0]})",
                 {"gravity", "3 numbers", "2 elements"});
    expect_error(R"({"cloth": {"grid": {}}, "frames": 1.5})", {"frames", "an integer"});
    expect_error(R"({"cloth": {"grid": {}}, "substeps": 0})", {"substeps"});
    expect_error(R"({"cloth": {"grid": {}}, "untangle": "yes"})",
                 {"untangle", "true or false", "string"});
    expect_error(R"({"cloth": {"grid": {}}, "self_collision": 1})",
                 {"self_collision", "true or false"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": {}})", {"obstacles", "an array"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"cone": {}}]})",
                 {"obstacles[0].cone", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{}]})", {"obstacles[0]", "exactly one"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"sphere": {"radius": -1}}]})",
                 {"obstacles[0].sphere.radius"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"plane": {"normal": [0, 0, 0]}}]})",
                 {"obstacles[0].plane.normal", "nonzero"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"box": {"min": [0, 0, 0]}}]})",
                 {"obstacles[0].box.max", "required"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"vertices": [-1]}})",
                 {"pins.vertices[0]", "vertex index"});
    expect_error(R"({"cloth": {"grid": {}}, "output": {"format": "stl"}})",
                 {"output.format", "\"obj\"", "\"stl\""});
    expect_error(R"({"cloth": {"grid": {}}, "gravity": [0, 0, 1e999]})",
                 {"not valid JSON", "overflow"});
}

// Numbers a JSON parser accepts but the simulation cannot use: integers beyond 64 bits or whose
// product overflows, grids beyond make_grid_sheet's sides, vectors outside [1e-30, 1e6] in
// magnitude (gravity 1e300 left the exact predicates' domain mid-run), flat boxes. Each is an
// error naming the key and the value as written.
TEST(ClothScene, HostileNumbersNameTheKeyAndTheValue) {
    expect_error(R"({"cloth": {"grid": {"quads": [4294967296, 4294967296]}}})",
                 {"cloth.grid.quads", "[1, 16384]", "4294967296"});
    expect_error(R"({"cloth": {"grid": {"quads": [4611686018427387912, 4]}}})",
                 {"cloth.grid.quads", "4611686018427387912"});
    expect_error(R"({"cloth": {"grid": {"quads": [1, 20000]}}})",
                 {"cloth.grid.quads", "[1,20000]"});
    expect_error(R"({"cloth": {"grid": {"quads": [10000, 10000]}}})",
                 {"cloth.grid.quads", "50,000,000"});
    expect_error(R"({"cloth": {"grid": {"size": [1e-300, 1e-300]}}})",
                 {"cloth.grid.size", "[1e-6, 1e6]"});
    expect_error(R"({"cloth": {"grid": {}}, "frames": 18446744073709551615})",
                 {"frames", "[0, 1000000]", "18446744073709551615"});
    expect_error(R"({"cloth": {"grid": {}}, "substeps": 9223372036854775808})",
                 {"substeps", "9223372036854775808"});
    expect_error(R"({"cloth": {"grid": {}}, "gravity": [0, 0, -1e300]})",
                 {"gravity[2]", "0 or a magnitude in [1e-30, 1000000]", "-1e+300"});
    expect_error(R"({"cloth": {"grid": {}, "translate": [1e-100, 0, 0.5]}})",
                 {"cloth.translate[0]", "1e-100"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"plane": {"normal": [0, 0, 1e200]}}]})",
                 {"obstacles[0].plane.normal[2]"});
    expect_error(
        R"({"cloth": {"grid": {}}, "obstacles": [{"box": {"min": [-1, -1, 0], "max": [1, 1, 0]}}]})",
        {"obstacles[0].box.max", "max > min on every axis", "max (1, 1, 0)"});
    // A key with a NUL in it is printed escaped, not cut short.
    expect_error("{\"cloth\": {\"grid\": {}}, \"f\\u0000ps\": 24}",
                 {"\"f\\u0000ps\"", "unknown key"});
    // The bounds themselves are accepted.
    const cloth::ClothScene edge = parse(R"({"cloth": {"grid": {"quads": [16384, 2]}},
                                             "gravity": [1e-30, 0, -1e6]})");
    EXPECT_EQ(edge.grid->quads[0], 16384);
    EXPECT_EQ(edge.gravity.z, -1e6);
}

TEST(ClothScene, InstancesPinGroupsMotionAirAndMeshObstacles) {
    const cloth::ClothScene scene = parse(R"({
        "cloth": {"grid": {"quads": [4, 4]},
                  "instances": [{"translate": [0, 0, 1]}, {"rotate_degrees": [0, 0, 30]}]},
        "pins": [{"vertices": [0]},
                 {"regions": [{"min": [-1, -1, 0], "max": [1, 1, 0]}],
                  "motion": {"pivot": [0, 0, 1],
                             "keyframes": [{"time": 0},
                                           {"time": 3, "rotate_degrees": [0, 0, 720],
                                            "translate": [0, 0, -0.3]}]}}],
        "obstacles": [{"mesh": {"file": "bowl.obj", "translate": [0, 0, -1]},
                       "motion": {"keyframes": [{"time": 1, "rotate_degrees": [0, 0, 90]}]}},
                      {"sphere": {}, "motion": {"keyframes": [{"time": 0},
                                                              {"time": 1, "translate": [1, 0, 0]}]}}],
        "air": {"wind": [8, 0, 0], "gust_amplitude": 0.4}
    })");
    ASSERT_EQ(scene.instances.size(), 2u);
    EXPECT_DOUBLE_EQ(scene.instances[0].translate.z, 1.0);
    EXPECT_DOUBLE_EQ(scene.instances[1].rotate_degrees.z, 30.0);
    ASSERT_EQ(scene.pins.size(), 2u);
    EXPECT_TRUE(scene.pins[0].motion.is_static());
    ASSERT_EQ(scene.pins[1].motion.keyframes.size(), 2u);
    EXPECT_DOUBLE_EQ(scene.pins[1].motion.keyframes[1].rotate_degrees.z, 720.0);
    EXPECT_DOUBLE_EQ(scene.pins[1].motion.pivot.z, 1.0);
    ASSERT_EQ(scene.obstacles.size(), 2u);
    EXPECT_EQ(scene.obstacles[0].mesh, std::filesystem::path("/scenes/bowl.obj"));
    EXPECT_DOUBLE_EQ(scene.obstacles[0].mesh_placement.translate.z, -1.0);
    EXPECT_TRUE(scene.obstacles[0].motion.rotates());
    EXPECT_FALSE(scene.obstacles[1].motion.rotates());
    EXPECT_DOUBLE_EQ(scene.air.density, 1.2);  // given an "air" object, air is on
    EXPECT_DOUBLE_EQ(scene.air.wind.x, 8.0);
    EXPECT_DOUBLE_EQ(scene.air.gust_amplitude, 0.4);
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"grid": {}}})").air.density, 0.0);
}

TEST(ClothScene, BrokenMotionAndAirNameTheKey) {
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"motion": {}}})",
                 {"pins.motion.keyframes", "non-empty"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": [{"motion": {"keyframes": [{}]}}]})",
                 {"pins[0].motion.keyframes[0].time", "required"});
    expect_error(
        R"({"cloth": {"grid": {}}, "pins": {"motion": {"keyframes": [{"time": 1}, {"time": 1}]}}})",
        {"pins.motion.keyframes[1].time", "after the previous keyframe"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": [{"motion": {"keyframes": [{"time": 0,
                 "spin": 1}]}}]})",
                 {"pins[0].motion.keyframes[0].spin", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"box": {"min": [0, 0, 0],
                 "max": [1, 1, 1]}, "motion": {"keyframes": [{"time": 0,
                 "rotate_degrees": [0, 0, 5]}]}}]})",
                 {"obstacles[0].motion", "boxes stay axis-aligned"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {}}]})",
                 {"obstacles[0].mesh.file", "file name"});
    expect_error(R"({"cloth": {"grid": {}}, "air": {"gust_period": 0}})", {"air.gust_period"});
    expect_error(R"({"cloth": {"grid": {}}, "air": {"wind": [1, 0]}})", {"air.wind"});
    expect_error(R"({"cloth": {"grid": {}, "instances": [{"scale": 2}]}})",
                 {"cloth.instances[0].scale", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": 3})", {"pins", "an object"});
}

TEST(ClothScene, MissingFile) {
    EXPECT_THROW(read_cloth_scene("/nonexistent/scene.json"), IoError);
}

}  // namespace
}  // namespace pliant::pipeline

namespace pliant::pipeline {
namespace {

TEST(ClothScene, ReadsDeformingObstaclesAndAttachedPins) {
    const cloth::ClothScene scene = parse(R"({
        "cloth": {"grid": {}},
        "pins": [{"vertices": [1]},
                 {"vertices": [0, 2], "attach": {"obstacle": "body", "max_distance": 0.1}},
                 {"vertices": [3], "attach": {"obstacle": 0}}],
        "obstacles": [{"name": "body",
                       "mesh": {"frames": "body/frame_%04d.obj", "fps": 30, "loop": true,
                                "start": 1, "count": 12, "translate": [0, 0, 1]}},
                      {"mesh": {"frames": ["a.obj", "/abs/b.obj"]}}]})");
    ASSERT_EQ(scene.obstacles.size(), 2u);
    const cloth::SceneObstacle& body = scene.obstacles[0];
    EXPECT_EQ(body.name, "body");
    EXPECT_EQ(body.frames_pattern, std::filesystem::path("/scenes/body/frame_%04d.obj"));
    EXPECT_EQ(body.frames_fps, 30.0);
    EXPECT_TRUE(body.loop);
    EXPECT_EQ(body.frame_start, 1);
    EXPECT_EQ(body.frame_count, 12);
    EXPECT_EQ(body.mesh_placement.translate, (Vec3d{0, 0, 1}));
    const cloth::SceneObstacle& listed = scene.obstacles[1];
    ASSERT_EQ(listed.frames.size(), 2u);
    EXPECT_EQ(listed.frames[0], std::filesystem::path("/scenes/a.obj"));
    EXPECT_EQ(listed.frames[1], std::filesystem::path("/abs/b.obj"));
    EXPECT_EQ(listed.mesh, listed.frames[0]);
    EXPECT_EQ(listed.frames_fps, 0.0);  // the scene's
    EXPECT_FALSE(listed.loop);
    EXPECT_FALSE(scene.pins[0].attach);
    ASSERT_TRUE(scene.pins[1].attach);
    EXPECT_EQ(scene.pins[1].attach->obstacle_index, 0);
    EXPECT_EQ(scene.pins[1].attach->max_distance, 0.1);
    EXPECT_EQ(scene.pins[2].attach->obstacle_index, 0);
}

TEST(ClothScene, BrokenDeformingObstaclesAndAttachmentsNameTheKey) {
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {"frames": 3}}]})",
                 {"obstacles[0].mesh.frames", "a file pattern"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {"frames": []}}]})",
                 {"obstacles[0].mesh.frames", "non-empty list"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {"frames": ["a.obj", 2]}}]})",
                 {"obstacles[0].mesh.frames[1]", "a file name"});
    expect_error(
        R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {"file": "a.obj", "frames": "b%d"}}]})",
        {"obstacles[0].mesh.frames", "both"});
    expect_error(R"({"cloth": {"grid": {}},
                     "obstacles": [{"mesh": {"frames": "b%d.obj", "fps": 0}}]})",
                 {"obstacles[0].mesh.fps"});
    expect_error(R"({"cloth": {"grid": {}},
                     "obstacles": [{"mesh": {"frames": "b%d.obj", "loop": 1}}]})",
                 {"obstacles[0].mesh.loop", "true or false"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"mesh": {"file": "a.obj", "fps": 2}}]})",
                 {"obstacles[0].mesh.fps", "unknown key"});
    expect_error(R"({"cloth": {"grid": {}}, "obstacles": [{"name": "a", "sphere": {}},
                                                          {"name": "a", "sphere": {}}]})",
                 {"obstacles[1].name", "\"a\"", "obstacles[0]"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"vertices": [0], "attach": {"obstacle": "x"}},
                     "obstacles": [{"name": "body", "mesh": {"file": "a.obj"}}]})",
                 {"pins.attach.obstacle", "\"body\"", "got \"x\""});
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"vertices": [0], "attach": {"obstacle": 0}},
                     "obstacles": [{"sphere": {}}]})",
                 {"pins.attach.obstacle", "a mesh obstacle", "an analytic shape"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"vertices": [0], "attach": {"obstacle": 2}},
                     "obstacles": [{"sphere": {}}]})",
                 {"pins.attach.obstacle", "the scene has 1 obstacles"});
    expect_error(R"({"cloth": {"grid": {}}, "pins": {"vertices": [0], "attach": {}}})",
                 {"pins.attach.obstacle", "nothing"});
    expect_error(R"({"cloth": {"grid": {}},
                     "pins": {"vertices": [0], "attach": {"obstacle": 0},
                              "motion": {"keyframes": [{"time": 0}]}},
                     "obstacles": [{"mesh": {"file": "a.obj"}}]})",
                 {"pins.attach", "both"});
}

TEST(ClothScene, MaterialPresetsAndPhysicalStiffness) {
    const cloth::ClothScene denim = parse(R"({"cloth": {"grid": {}}, "material": "denim"})");
    EXPECT_EQ(denim.material_preset, "denim");
    EXPECT_DOUBLE_EQ(denim.material.areal_density, 0.40);
    ASSERT_TRUE(denim.stretch_stiffness && denim.bend_stiffness);
    EXPECT_DOUBLE_EQ(*denim.stretch_stiffness, 1.5e4);

    // A preset as a start, with overrides; a compliance replaces the preset's stiffness.
    const cloth::ClothScene silk = parse(R"({"cloth": {"grid": {}}, "material":
        {"preset": "silk", "areal_density": 0.08, "bend_compliance": 2, "thickness": 0.003}})");
    EXPECT_DOUBLE_EQ(silk.material.areal_density, 0.08);
    EXPECT_DOUBLE_EQ(silk.material.thickness, 0.003);
    EXPECT_TRUE(silk.stretch_stiffness);
    EXPECT_FALSE(silk.bend_stiffness);
    EXPECT_DOUBLE_EQ(silk.material.bend_compliance, 2.0);

    const cloth::ClothScene custom = parse(
        R"({"cloth": {"grid": {}}, "material": {"stretch_stiffness": 500, "bend_stiffness": 1e-4}})");
    EXPECT_EQ(custom.material_preset, "");
    EXPECT_DOUBLE_EQ(*custom.stretch_stiffness, 500.0);
    EXPECT_DOUBLE_EQ(*custom.bend_stiffness, 1e-4);

    const cloth::ClothScene plain = parse(R"({"cloth": {"grid": {}}})");
    EXPECT_FALSE(plain.stretch_stiffness || plain.bend_stiffness);

    expect_error(R"({"cloth": {"grid": {}}, "material": "wool"})",
                 {"material", "a material preset", "\"cotton\"", "got \"wool\""});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"preset": "Denim"}})",
                 {"material.preset", "got \"Denim\""});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"preset": 3}})",
                 {"material.preset", "a material preset name", "got an integer"});
    expect_error(R"({"cloth": {"grid": {}}, "material": 3})",
                 {"material", "a material preset name or an object", "got an integer"});
    expect_error(
        R"({"cloth": {"grid": {}}, "material": {"stretch_stiffness": 1, "stretch_compliance": 1}})",
        {"material.stretch_stiffness", "either it or stretch_compliance", "got both"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"bend_stiffness": 0}})",
                 {"material.bend_stiffness", "got 0"});
    expect_error(R"({"cloth": {"grid": {}}, "material": {"bend_stiffness": "stiff"}})",
                 {"material.bend_stiffness", "a number"});
}

TEST(ClothScene, MeshUnitsAndScale) {
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"mesh": "a.obj"}})").mesh_scale, 1.0);
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"mesh": "a.obj", "units": "cm"}})").mesh_scale, 0.01);
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"mesh": "a.obj", "units": "mm"}})").mesh_scale, 0.001);
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"mesh": "a.obj", "units": "m"}})").mesh_scale, 1.0);
    EXPECT_DOUBLE_EQ(parse(R"({"cloth": {"mesh": "a.obj", "scale": 0.0254}})").mesh_scale, 0.0254);
    expect_error(R"({"cloth": {"mesh": "a.obj", "units": "inch"}})",
                 {"cloth.units", R"("cm", "m", "mm")", "got \"inch\""});
    expect_error(R"({"cloth": {"mesh": "a.obj", "units": "cm", "scale": 2}})",
                 {"cloth.scale", "either it or \"units\"", "got both"});
    expect_error(R"({"cloth": {"mesh": "a.obj", "scale": 0}})", {"cloth.scale", "got 0"});
    expect_error(R"({"cloth": {"mesh": "a.obj", "scale": "big"}})", {"cloth.scale", "a number"});
    expect_error(R"({"cloth": {"grid": {}, "units": "cm"}})",
                 {"cloth.units", "a cloth \"mesh\"", "got a grid"});
}

TEST(ClothScene, SeamsAndPointCache) {
    const cloth::ClothScene scene = parse(R"({"cloth": {"grid": {}},
        "seams": [{"a": [0, 1, 2], "b": [9, 8, 7]},
                  {"a": {"from": 10, "to": 13}, "b": {"from": 23, "to": 20}, "seconds": 0.25}],
        "output": {"point_cache": "pc2"}})");
    ASSERT_EQ(scene.seams.size(), 2u);
    EXPECT_EQ(scene.seams[0].a, (std::vector<std::int32_t>{0, 1, 2}));
    EXPECT_EQ(scene.seams[0].b, (std::vector<std::int32_t>{9, 8, 7}));
    EXPECT_DOUBLE_EQ(scene.seams[0].seconds, 1.0);
    EXPECT_EQ(scene.seams[1].a, (std::vector<std::int32_t>{10, 11, 12, 13}));
    EXPECT_EQ(scene.seams[1].b, (std::vector<std::int32_t>{23, 22, 21, 20}));
    EXPECT_DOUBLE_EQ(scene.seams[1].seconds, 0.25);
    EXPECT_EQ(scene.seams[1].key, "seams[1]");
    EXPECT_EQ(scene.point_cache, "pc2");
    EXPECT_EQ(parse(R"({"cloth": {"grid": {}}, "output": {"point_cache": null}})").point_cache, "");

    const std::string head = R"({"cloth": {"grid": {}}, "seams": )";
    expect_error(head + R"([{"a": [0, 1], "b": [2]}]})",
                 {"seams[0].b", "as many vertices as a (2)", "got 1"});
    expect_error(head + R"([{"a": [0]}]})", {"seams[0].b", "a required list", "got nothing"});
    expect_error(head + R"([{"a": [], "b": []}]})", {"seams[0].a", "at least one vertex"});
    expect_error(head + R"([{"a": [-1], "b": [2]}]})", {"seams[0].a[0]", "a vertex index", "-1"});
    expect_error(head + R"([{"a": [0.5], "b": [2]}]})", {"seams[0].a[0]", "0.5"});
    expect_error(head + R"([{"a": "0-3", "b": [2]}]})",
                 {"seams[0].a", "a list of vertex indices", "string"});
    expect_error(head + R"([{"a": {"from": 3}, "b": [2]}]})",
                 {"seams[0].a", R"(both "from" and "to")"});
    expect_error(head + R"([{"a": {"from": 0, "to": 2, "step": 1}, "b": [2]}]})",
                 {"seams[0].a.step", "a known key"});
    expect_error(head + R"([{"a": {"from": 0, "to": 20000000}, "b": [2]}]})",
                 {"seams[0].a", "at most 10,000,000"});
    expect_error(head + R"([{"a": [0], "b": [1], "seconds": 0}]})", {"seams[0].seconds", "got 0"});
    expect_error(head + R"([{"a": [0], "b": [1], "glue": 1}]})", {"seams[0].glue", "a known key"});
    expect_error(head + R"({"a": [0], "b": [1]}})", {"seams", "an array"});
    EXPECT_EQ(parse(R"({"cloth": {"grid": {}}, "output": {"point_cache": "mdd"}})").point_cache,
              "mdd");
    expect_error(R"({"cloth": {"grid": {}}, "output": {"point_cache": "abc"}})",
                 {"output.point_cache", R"(one of "mdd", "pc2")", "got \"abc\""});
}

}  // namespace
}  // namespace pliant::pipeline
