// The bar for OpenVDB: a file written by pliant reads back in OpenVDB's own Python module
// (pyopenvdb, Debian python3-openvdb) with the same values, voxel for voxel, at the same world
// positions. tests/io/openvdb_readback.py prints what pyopenvdb reads as JSON; this compares it
// with the volume pliant wrote. Skips when /usr/bin/python3 has no pyopenvdb.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stdio.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "pliant/io/openvdb.hpp"
#include "pliant/volume/volume.hpp"
#include "support/python_readback.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::TempDir;
using volume::Volume;
using volume::VoxelType;

bool has_pyopenvdb() {
    const std::string command =
        std::string(pliant::test::SYSTEM_PYTHON) + " -c 'import pyopenvdb' >/dev/null 2>&1";
    return std::system(command.c_str()) == 0;
}

// Runs the readback script on `path` and parses its JSON.
nlohmann::json read_with_pyopenvdb(const std::filesystem::path& path) {
    return pliant::test::run_python_readback("tests/io/openvdb_readback.py", path);
}

// A 7 × 6 × 5 volume: a ball of varying values in an empty border, anisotropic spacing.
Volume ball(VoxelType type) {
    Volume v = Volume::allocate({7, 6, 5}, type, {0.5, 0.25, 1.5}, {-2.0, 1.0, 0.75});
    const int ch = volume::channels(type);
    for (std::int64_t k = 0; k < 5; ++k) {
        for (std::int64_t j = 0; j < 6; ++j) {
            for (std::int64_t i = 0; i < 7; ++i) {
                const double r2 =
                    (i - 3.0) * (i - 3.0) + (j - 2.5) * (j - 2.5) + (k - 2.0) * (k - 2.0);
                const bool inside = r2 < 6.5;
                const std::int64_t n = v.index(i, j, k);
                for (int c = 0; c < ch; ++c) {
                    const auto at = static_cast<std::size_t>(n * ch + c);
                    const double x =
                        inside ? 1.0 + static_cast<double>((n * 5 + c * 11) % 200) : 0.0;
                    if (type == VoxelType::f32) {
                        v.values<VoxelType::f32>()[at] = static_cast<float>(x * 0.125 - 7.0);
                        if (!inside) {
                            v.values<VoxelType::f32>()[at] = 0.0F;
                        }
                    } else if (type == VoxelType::u16) {
                        v.values<VoxelType::u16>()[at] = static_cast<std::uint16_t>(x * 300);
                    } else {
                        v.values<VoxelType::rgba8>()[at] = static_cast<std::uint8_t>(x);
                    }
                }
            }
        }
    }
    return v;
}

double channel(const Volume& v, std::int64_t n, int c) {
    const auto at = static_cast<std::size_t>(n * volume::channels(v.type()) + c);
    switch (v.type()) {
        case VoxelType::f32:
            return v.values<VoxelType::f32>()[at];
        case VoxelType::u16:
            return v.values<VoxelType::u16>()[at];
        case VoxelType::rgba8:
            return v.values<VoxelType::rgba8>()[at] / 255.0;
        default:
            return NAN;
    }
}

TEST(OpenVdbPython, PyopenvdbReadsTheValuesPliantWrote) {
    if (!has_pyopenvdb()) {
        GTEST_SKIP() << pliant::test::SYSTEM_PYTHON << " has no pyopenvdb (Debian python3-openvdb)";
    }
    TempDir dir;
    for (const VoxelType type : {VoxelType::f32, VoxelType::u16, VoxelType::rgba8}) {
        SCOPED_TRACE(std::string(volume::name(type)));
        const Volume v = ball(type);
        write_openvdb(dir / "ball.vdb", v);
        const nlohmann::json grids = read_with_pyopenvdb(dir / "ball.vdb");
        const bool rgba = volume::channels(type) == 4;
        ASSERT_EQ(grids.size(), rgba ? 2U : 1U);
        for (const auto& [name, grid] : grids.items()) {
            SCOPED_TRACE(name);
            EXPECT_EQ(grid["type"], name == "color" ? "vec3s" : "float");
            EXPECT_EQ(grid["class"], "fog volume");
            EXPECT_EQ(grid["pliant_dims"], (nlohmann::json{7, 6, 5}));
            EXPECT_EQ(grid["pliant_voxel_type"], std::string(volume::name(type)));
            // Every nonzero voxel, and only those, is active, with its value and voxel centre.
            std::int64_t nonzero = 0;
            for (std::int64_t n = 0; n < v.num_voxels(); ++n) {
                nonzero += channel(v, n, rgba ? 3 : 0) != 0.0 ? 1 : 0;
            }
            EXPECT_EQ(grid["active"].get<std::int64_t>(), nonzero);
            ASSERT_EQ(static_cast<std::int64_t>(grid["voxels"].size()), nonzero);
            for (const auto& voxel : grid["voxels"]) {
                ASSERT_EQ(voxel["min"], voxel["max"]);  // single voxels, no tiles
                const auto i = voxel["min"][0].get<std::int64_t>();
                const auto j = voxel["min"][1].get<std::int64_t>();
                const auto k = voxel["min"][2].get<std::int64_t>();
                ASSERT_TRUE(i >= 0 && i < 7 && j >= 0 && j < 6 && k >= 0 && k < 5);
                const std::int64_t n = v.index(i, j, k);
                const Vec3d c = v.voxel_center(i, j, k);
                EXPECT_NEAR(voxel["world"][0].get<double>(), c.x, 1e-12);
                EXPECT_NEAR(voxel["world"][1].get<double>(), c.y, 1e-12);
                EXPECT_NEAR(voxel["world"][2].get<double>(), c.z, 1e-12);
                if (name == "color") {
                    for (int ch = 0; ch < 3; ++ch) {
                        EXPECT_EQ(voxel["value"][ch].get<double>(),
                                  static_cast<double>(static_cast<float>(channel(v, n, ch))));
                    }
                } else {
                    EXPECT_EQ(voxel["value"][0].get<double>(),
                              static_cast<double>(static_cast<float>(channel(v, n, rgba ? 3 : 0))));
                }
            }
        }
    }
}

}  // namespace
}  // namespace pliant::io
