#include "pliant/pbd/tet_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "pliant/core/error.hpp"
#include "pliant/volume/generate.hpp"

namespace pliant::pbd {
namespace {

using volume::Volume;
using volume::VoxelType;

double total_volume(const geometry::TetMesh& mesh) {
    double sum = 0.0;
    for (const geometry::Tet& t : mesh.tets) {
        sum += geometry::signed_volume(
            vec3_cast<double>(mesh.positions[t[0]]), vec3_cast<double>(mesh.positions[t[1]]),
            vec3_cast<double>(mesh.positions[t[2]]), vec3_cast<double>(mesh.positions[t[3]]));
    }
    return sum;
}

// Faces (sorted vertex triples) → how many tets hold them.
std::map<std::array<std::int32_t, 3>, int> face_counts(const geometry::TetMesh& mesh) {
    std::map<std::array<std::int32_t, 3>, int> counts;
    for (const geometry::Tet& t : mesh.tets) {
        for (int skip = 0; skip < 4; ++skip) {
            std::array<std::int32_t, 3> face{};
            int n = 0;
            for (int i = 0; i < 4; ++i) {
                if (i != skip) {
                    face[static_cast<std::size_t>(n++)] = t[static_cast<std::size_t>(i)];
                }
            }
            std::sort(face.begin(), face.end());
            ++counts[face];
        }
    }
    return counts;
}

TEST(TetGrid, FullBoxTilesTheVolumeBoxWithConformingPositiveTets) {
    // 10 × 7 × 5 voxels of spacing (0.5, 1, 2), cells of 3: 4 × 3 × 2 cells, the last thinner.
    Volume v = Volume::allocate({10, 7, 5}, VoxelType::u8, {0.5, 1.0, 2.0}, {1.0, -2.0, 3.0});
    const TetGrid grid = build_tet_grid(v, {.cell_voxels = 3, .full_box = true});
    EXPECT_EQ(grid.cells, (std::array<std::int32_t, 3>{4, 3, 2}));
    EXPECT_EQ(grid.mesh.num_vertices(), 5u * 4u * 3u);
    EXPECT_EQ(grid.mesh.num_tets(), 5u * 4u * 3u * 2u);
    EXPECT_EQ(grid.num_active_cells(), 24);
    for (const geometry::Tet& t : grid.mesh.tets) {
        EXPECT_GT(geometry::signed_volume(grid.mesh.positions[t[0]], grid.mesh.positions[t[1]],
                                          grid.mesh.positions[t[2]], grid.mesh.positions[t[3]]),
                  0.0f);
    }
    EXPECT_NEAR(total_volume(grid.mesh), 5.0 * 7.0 * 10.0, 1e-3);
    // Conforming: every face is shared by two tets, except the faces on the box's boundary.
    const AABBd box = v.bounds();
    for (const auto& [face, count] : face_counts(grid.mesh)) {
        bool on_boundary = false;
        for (int axis = 0; axis < 3; ++axis) {
            for (double side : {box.lo[axis], box.hi[axis]}) {
                bool all = true;
                for (std::int32_t f : face) {
                    all = all && std::abs(grid.mesh.positions[static_cast<std::size_t>(f)][axis] -
                                          side) < 1e-5;
                }
                on_boundary = on_boundary || all;
            }
        }
        EXPECT_EQ(count, on_boundary ? 1 : 2);
    }
    // Lattice coordinates match positions.
    for (std::size_t i = 0; i < grid.mesh.num_vertices(); ++i) {
        const auto& l = grid.vertex_lattice[i];
        EXPECT_FLOAT_EQ(grid.mesh.positions[i].x,
                        static_cast<float>(1.0 + std::min(l[0] * 3, 10) * 0.5));
        EXPECT_FLOAT_EQ(grid.mesh.positions[i].z,
                        static_cast<float>(3.0 + std::min(l[2] * 3, 5) * 2.0));
    }
}

TEST(TetGrid, KeepsOnlyCellsNearVisibleVoxels) {
    Volume v = Volume::allocate({16, 16, 16}, VoxelType::rgba8);
    // One visible voxel at (4, 9, 15): its cell (1, 2, 3) of 4-voxel cells, and the dilation
    // reaches the neighbour cell (0, 2, 3) (voxel 4 is next to voxel 3) and (1, 2, 3) only along
    // x; along y voxel 9 is inside; along z voxel 15 is the last.
    const auto values = v.values<VoxelType::rgba8>();
    values[static_cast<std::size_t>(v.index(4, 9, 15) * 4 + 3)] = 1;
    const TetGrid grid = build_tet_grid(v, {.cell_voxels = 4});
    ASSERT_EQ(grid.num_active_cells(), 2);
    EXPECT_EQ(grid.tet_cell.front(), 0 + 4 * (2 + 4 * 3));
    EXPECT_EQ(grid.tet_cell.back(), 1 + 4 * (2 + 4 * 3));
    EXPECT_EQ(grid.mesh.num_vertices(), 12u);
    for (const geometry::Tet& t : grid.mesh.tets) {
        for (std::int32_t i : t) {
            EXPECT_GE(i, 0);
            EXPECT_LT(static_cast<std::size_t>(i), grid.mesh.num_vertices());
        }
    }
}

TEST(TetGrid, ScalarVisibilityFollowsTheTransferFunction) {
    const Volume sphere = volume::uniform_sphere({32, 32, 32}, 8.0, 100.0f);
    const TetGrid all = build_tet_grid(sphere, {.cell_voxels = 4});
    volume::TransferFunction hidden{.name = "hidden",
                                    .color = {{0.0, {1, 1, 1}}},
                                    .opacity = {{0.0, 0.0f}, {200.0, 0.0f}, {201.0, 1.0f}}};
    const TetGrid none = build_tet_grid(sphere, {.cell_voxels = 4, .tf = &hidden});
    EXPECT_GT(all.num_active_cells(), 0);
    EXPECT_LT(all.num_active_cells(), 8 * 8 * 8);
    EXPECT_EQ(none.num_active_cells(), 0);
    EXPECT_EQ(none.mesh.num_vertices(), 0u);
}

TEST(TetGrid, RejectsBadOptions) {
    const Volume v = Volume::allocate({4, 4, 4}, VoxelType::f32);
    EXPECT_THROW(build_tet_grid(v, {.cell_voxels = 0}), InvalidInput);
    EXPECT_THROW(build_tet_grid(Volume{}, {}), InvalidInput);
}

}  // namespace
}  // namespace pliant::pbd
