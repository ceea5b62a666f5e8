// `pliant deform` end to end: the rotate driver against an independently rotated phantom
// (trilinear reference), twist's volume and inversion report, the video, a TetGen mesh, and
// usage and input errors.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stdio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include "integration/run_cli.hpp"
#include "pliant/io/openvdb.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/volume/volume.hpp"

namespace pliant::test {
namespace {

using volume::Volume;
using volume::VoxelType;

// Trilinear sample of a scalar f32 volume at world point p: voxel centres at
// origin + (i + 0.5) spacing, clamped to the edge voxel within half a voxel of the box, 0 outside
// the box (the resampler's documented convention, written here independently).
double sample(const Volume& v, const Vec3d& p) {
    const AABBd box = v.bounds();
    for (int a = 0; a < 3; ++a) {
        if (p[a] < box.lo[a] || p[a] > box.hi[a]) {
            return 0.0;
        }
    }
    const auto values = v.values<VoxelType::f32>();
    std::array<std::int64_t, 3> i0{};
    std::array<double, 3> f{};
    for (int a = 0; a < 3; ++a) {
        const auto n = v.dims()[static_cast<std::size_t>(a)];
        const double g = std::clamp((p[a] - v.origin()[a]) / v.spacing()[a] - 0.5, 0.0,
                                    static_cast<double>(n - 1));
        i0[static_cast<std::size_t>(a)] =
            std::min<std::int64_t>(static_cast<std::int64_t>(g), n - 2);
        f[static_cast<std::size_t>(a)] = g - static_cast<double>(i0[static_cast<std::size_t>(a)]);
    }
    double sum = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
        const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
        sum += w * values[static_cast<std::size_t>(v.index(i0[0] + dx, i0[1] + dy, i0[2] + dz))];
    }
    return sum;
}

// The source rotated by `degrees` right-handed about `axis` through the box centre, sampled at
// the voxel centres: voxel x shows the source at R⁻¹ (x − c) + c.
Volume rotated_reference(const Volume& source, int axis, double degrees) {
    Volume out = Volume::allocate(source.dims(), VoxelType::f32, source.spacing(), source.origin());
    const auto values = out.values<VoxelType::f32>();
    const Vec3d c = source.bounds().center();
    const double a = -degrees * std::numbers::pi / 180.0;  // the inverse rotation
    const double cs = std::cos(a), sn = std::sin(a);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;  // right-handed: u → w for a positive turn
    for (std::int64_t k = 0; k < source.dims()[2]; ++k) {
        for (std::int64_t j = 0; j < source.dims()[1]; ++j) {
            for (std::int64_t i = 0; i < source.dims()[0]; ++i) {
                const Vec3d d = source.voxel_center(i, j, k) - c;
                Vec3d r = d;
                r[u] = cs * d[u] - sn * d[w];
                r[w] = sn * d[u] + cs * d[w];
                values[static_cast<std::size_t>(out.index(i, j, k))] =
                    static_cast<float>(sample(source, c + r));
            }
        }
    }
    return out;
}

double psnr(const Volume& a, const Volume& b, double peak) {
    const auto x = a.values<VoxelType::f32>();
    const auto y = b.values<VoxelType::f32>();
    double sum = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        sum += (double{x[i]} - y[i]) * (double{x[i]} - y[i]);
    }
    const double mse = sum / static_cast<double>(x.size());
    return mse == 0.0 ? 1000.0 : 10.0 * std::log10(peak * peak / mse);
}

TEST(DeformCommand, RotateReproducesTheAnalyticallyRotatedPhantom) {
    ScratchDir scratch;
    ASSERT_EQ(run_cli("volume generate shepp-logan " + quoted(scratch / "sl.nrrd") + " --dims 48",
                      scratch)
                  .exit_code,
              0);
    const Volume source = io::read_volume(scratch / "sl.nrrd");
    // The phantom is symmetric under a half turn about z, not under 30° about z or x.
    for (const auto& [axis_name, axis] : {std::pair{"z", 2}, std::pair{"x", 0}}) {
        SCOPED_TRACE(axis_name);
        const CliResult r = run_cli(std::string("--json deform ") + quoted(scratch / "sl.nrrd") +
                                        " --driver rotate --angle 30 --axis " + axis_name +
                                        " --frames 3 -o " + quoted(scratch / "rot.nrrd"),
                                    scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json json = nlohmann::json::parse(r.out);
        EXPECT_EQ(json.at("inverted_tets"), 0);
        EXPECT_NEAR(json.at("volume_ratio").get<double>(), 1.0, 1e-5);
        for (const char* key : {"ms_per_substep", "resample_ms", "volume_ratio", "inverted_tets",
                                "tets", "vertices", "voxels_written"}) {
            EXPECT_TRUE(json.contains(key)) << key;
        }
        const Volume deformed = io::read_volume(scratch / "rot.nrrd");
        const Volume reference = rotated_reference(source, axis, 30.0);
        const double db = psnr(deformed, reference, 2.0);
        EXPECT_GE(db, 35.0);
        std::printf("rotate 30 degrees about %s: PSNR %.1f dB against the reference\n", axis_name,
                    db);
        // And against the other turning direction: a left-handed rotation is far off.
        EXPECT_LT(psnr(deformed, rotated_reference(source, axis, -30.0), 2.0), db - 10.0);
    }
}

TEST(DeformCommand, TwistKeepsVolumeAndWritesAVideo) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate rgba-test " + quoted(scratch / "rt.nrrd") + " --dims 24", scratch)
            .exit_code,
        0);
    // An output format that cannot hold RGBA float fails before the run, writing nothing.
    const CliResult refused = run_cli("deform " + quoted(scratch / "rt.nrrd") +
                                          " --driver twist -o " + quoted(scratch / "tw.nii.gz"),
                                      scratch);
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_NE(refused.err.find("no RGBA float"), std::string::npos) << refused.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "tw.nii.gz"));
    const bool has_ffmpeg = std::system("command -v ffmpeg >/dev/null 2>&1") == 0;
    const std::string video =
        has_ffmpeg ? " --render " + quoted(scratch / "tw.mp4") + " --size 64x48" : "";
    const CliResult r = run_cli("--json deform " + quoted(scratch / "rt.nrrd") +
                                    " --driver twist --angle 90 --cells 3 --frames 12 -o " +
                                    quoted(scratch / "tw.nrrd") + video,
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json.at("max_inverted_tets"), 0);
    EXPECT_NEAR(json.at("volume_ratio").get<double>(), 1.0, 0.01);
    EXPECT_GT(json.at("tets").get<int>(), 0);
    const Volume out = io::read_volume(scratch / "tw.nrrd");
    EXPECT_EQ(out.type(), VoxelType::rgba32f);
    EXPECT_EQ(out.dims(), (volume::Dims{24, 24, 24}));
    if (has_ffmpeg) {
        EXPECT_GT(std::filesystem::file_size(scratch / "tw.mp4"), 1000u);
    }
}

// --resample map renders the frames through their inverse map; the output volume is the exact
// resample either way, bit for bit.
TEST(DeformCommand, RendersThroughTheInverseMap) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate rgba-test " + quoted(scratch / "rt.nrrd") + " --dims 24", scratch)
            .exit_code,
        0);
    const bool has_ffmpeg = std::system("command -v ffmpeg >/dev/null 2>&1") == 0;
    for (const char* mode : {"exact", "map"}) {
        SCOPED_TRACE(mode);
        const std::string name = mode;
        const std::string video =
            has_ffmpeg ? " --render " + quoted(scratch / (name + ".mp4")) + " --size 64x48" : "";
        const CliResult r = run_cli("--json deform " + quoted(scratch / "rt.nrrd") +
                                        " --driver twist --angle 60 --cells 3 --frames 6 "
                                        "--shading --resample " +
                                        name + " -o " + quoted(scratch / (name + ".nrrd")) + video,
                                    scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json json = nlohmann::json::parse(r.out);
        EXPECT_EQ(json.at("resample_mode"), name);
        if (has_ffmpeg) {
            EXPECT_GT(std::filesystem::file_size(scratch / (name + ".mp4")), 1000u);
            EXPECT_EQ(json.at("map_ms").get<double>() > 0.0, name == "map");
        }
    }
    const Volume exact = io::read_volume(scratch / "exact.nrrd");
    const Volume map = io::read_volume(scratch / "map.nrrd");
    EXPECT_TRUE(std::equal(exact.bytes().begin(), exact.bytes().end(), map.bytes().begin(),
                           map.bytes().end()));
    for (const auto& [option, value] :
         {std::pair{"--resample", "nearest"}, std::pair{"--thin-levels", "3"}}) {
        const CliResult bad =
            run_cli("deform " + quoted(scratch / "rt.nrrd") + " --driver twist " + option + " " +
                        value + " -o " + quoted(scratch / "bad.nrrd"),
                    scratch);
        EXPECT_EQ(bad.exit_code, 2) << option;
        EXPECT_NE(bad.err.find(option), std::string::npos) << bad.err;
        EXPECT_FALSE(std::filesystem::exists(scratch / "bad.nrrd")) << option;
    }
}

TEST(DeformCommand, DeformsATetGenMesh) {
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 16", scratch)
            .exit_code,
        0);
    const Volume source = io::read_volume(scratch / "s.nrrd");
    // One cell of 5 tets over the volume's box (1-based, as TetGen writes).
    const AABBd b = source.bounds();
    std::string node = "8 3 0 0\n";
    for (int corner = 0; corner < 8; ++corner) {
        node += std::to_string(corner + 1) + " " + std::to_string(corner & 1 ? b.hi.x : b.lo.x) +
                " " + std::to_string(corner & 2 ? b.hi.y : b.lo.y) + " " +
                std::to_string(corner & 4 ? b.hi.z : b.lo.z) + "\n";
    }
    {
        std::FILE* f = std::fopen((scratch / "cube.node").c_str(), "wb");
        std::fputs(node.c_str(), f);
        std::fclose(f);
        f = std::fopen((scratch / "cube.ele").c_str(), "wb");
        std::fputs("5 4 0\n1 1 2 3 5\n2 4 3 2 8\n3 6 2 5 8\n4 7 5 3 8\n5 2 3 5 8\n", f);
        std::fclose(f);
    }
    const CliResult r =
        run_cli("--json deform " + quoted(scratch / "s.nrrd") + " --mesh " +
                    quoted(scratch / "cube.node") + " --driver bubble --frames 4 -o " +
                    quoted(scratch / "b.nrrd") + " --mesh-out " + quoted(scratch / "b.vtu"),
                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("tets"), 5);
    EXPECT_EQ(j.at("mesh_output"), (scratch / "b.vtu").string());
    EXPECT_TRUE(std::filesystem::exists(scratch / "b.nrrd"));
    // The .vtu read back by Python's xml module (tests/io/vtu_readback.py): the 8 vertices and
    // 5 tets of the TetGen mesh, moved by the bubble.
    const std::string command = std::string("/usr/bin/python3 ") + PLIANT_SOURCE_DIR +
                                "/tests/io/vtu_readback.py " + quoted(scratch / "b.vtu");
    FILE* pipe = ::popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string text;
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) {
        text.append(buffer, n);
    }
    ASSERT_EQ(::pclose(pipe), 0) << command;
    const nlohmann::json vtu = nlohmann::json::parse(text);
    EXPECT_EQ(vtu.at("points"), 8);
    EXPECT_EQ(vtu.at("cells"), 5);
    EXPECT_EQ(vtu.at("arrays").at("Cells/types").at("values"),
              (nlohmann::json{10, 10, 10, 10, 10}));
    double largest = 0.0;
    for (const auto& d : vtu.at("arrays").at("PointData/displacement").at("values")) {
        largest = std::max(largest, std::abs(d.get<double>()));
    }
    EXPECT_GT(largest, 0.0);
    EXPECT_NEAR(largest, j.at("max_displacement").get<double>(), largest);
}

TEST(DeformCommand, ReadsAndWritesOpenVdb) {
    if (!io::has_openvdb_support()) {
        GTEST_SKIP() << "built without OpenVDB";
    }
    ScratchDir scratch;
    ASSERT_EQ(
        run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 12", scratch)
            .exit_code,
        0);
    ASSERT_EQ(
        run_cli("volume convert " + quoted(scratch / "s.nrrd") + " " + quoted(scratch / "s.vdb"),
                scratch)
            .exit_code,
        0);
    const Volume nrrd = io::read_volume(scratch / "s.nrrd");
    const Volume vdb = io::read_volume(scratch / "s.vdb");
    ASSERT_EQ(vdb.dims(), nrrd.dims());
    EXPECT_TRUE(std::equal(nrrd.bytes().begin(), nrrd.bytes().end(), vdb.bytes().begin()));
    const CliResult r = run_cli("deform " + quoted(scratch / "s.vdb") +
                                    " --driver rotate --frames 2 -o " + quoted(scratch / "o.vdb"),
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(io::read_volume(scratch / "o.vdb").dims(), nrrd.dims());
    // --grid names the float grid; an unknown one is an error listing the file's grids.
    const CliResult info =
        run_cli("volume info " + quoted(scratch / "s.vdb") + " --grid density", scratch);
    EXPECT_EQ(info.exit_code, 0) << info.err;
    const CliResult bad =
        run_cli("deform " + quoted(scratch / "s.vdb") + " --grid smoke --driver rotate -o " +
                    quoted(scratch / "p.vdb"),
                scratch);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_NE(bad.err.find("no grid named 'smoke'; the file has 'density' (float)"),
              std::string::npos)
        << bad.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "p.vdb"));
}

TEST(DeformCommand, UsageAndInputErrors) {
    ScratchDir scratch;
    ASSERT_EQ(run_cli("volume generate sphere " + quoted(scratch / "s.nrrd") + " --dims 8", scratch)
                  .exit_code,
              0);
    const std::string in = quoted(scratch / "s.nrrd");
    const std::string out = " -o " + quoted(scratch / "o.nrrd");
    struct Case {
        std::string args;
        int exit_code;
        const char* fragment;
    };
    const Case cases[] = {
        {"deform " + in + " --driver melt" + out, 2, "--driver"},
        {"deform " + in + out, 2, "--driver is required"},
        {"deform " + in + " --driver twist --amplitude 0.1" + out, 2,
         "--amplitude: applies to --driver wave, not twist"},
        {"deform " + in + " --driver rotate --stiffness 1.5" + out, 2, "--stiffness"},
        {"deform " + in + " --driver rotate --render " + quoted(scratch / "v.png") + out, 2,
         "expected an .mp4"},
        {"deform " + in + " --driver rotate --cells 0" + out, 2, "--cells"},
        {"deform " + in + " --driver rotate --mesh-out " + quoted(scratch / "m.vtk") + out, 2,
         "expected a .vtu"},
        {"deform " + quoted(scratch / "missing.nrrd") + " --driver rotate" + out, 1,
         "missing.nrrd"},
        {"deform " + in + " --driver rotate -o " + quoted(scratch / "o.inv3"), 1, "inv3"},
        {"deform " + in + " --driver wave --axis z" + out, 1, "displacement"},
        {"deform " + in + " --driver rotate --mesh " + quoted(scratch / "none.node") + out, 1,
         "none.node"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const CliResult r = run_cli(c.args, scratch);
        EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
        EXPECT_NE(r.err.find(c.fragment), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
        EXPECT_FALSE(std::filesystem::exists(scratch / "o.nrrd"));
    }
}

}  // namespace
}  // namespace pliant::test
