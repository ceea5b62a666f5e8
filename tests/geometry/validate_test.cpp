#include "pliant/geometry/validate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pliant/core/error.hpp"

namespace pliant::geometry {
namespace {

std::string message_of(const TriangleMesh& mesh) {
    try {
        validate_mesh(mesh, "cloth.obj");
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return {};
}

TEST(Validate, AcceptsAGoodMesh) {
    TriangleMesh mesh{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
    EXPECT_EQ(message_of(mesh), "");
}

TEST(Validate, NamesTheOffendingElementAndValues) {
    TriangleMesh out_of_range{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 1, 3}}};
    EXPECT_EQ(message_of(out_of_range),
              "cloth.obj: triangle 1 corner 2 has vertex index 3, expected 0 <= index < 3");
    TriangleMesh negative{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, -1, 2}}};
    EXPECT_NE(message_of(negative).find("vertex index -1"), std::string::npos);
    TriangleMesh repeated{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 1}}};
    EXPECT_NE(message_of(repeated).find("repeats a vertex"), std::string::npos);
    TriangleMesh nan{{{0, 0, 0}, {1, NAN, 0}, {0, 1, 0}}, {{0, 1, 2}}};
    EXPECT_NE(message_of(nan).find("vertex 1 has a non-finite"), std::string::npos);
    TriangleMesh inf{{{0, 0, INFINITY}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
    EXPECT_NE(message_of(inf).find("vertex 0"), std::string::npos);
}

}  // namespace
}  // namespace pliant::geometry
